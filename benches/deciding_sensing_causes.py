"""What do the sensors cost, and why? The runs a controller holds in the deciding campaign on the
truth but not on motion-capture sensors (the same draws, run for run), flown again on sensors
changed one way at a time, each judged by the campaign's hold rule (``deciding.fly_longer`` with
no extension: the campaign's own flights and rows when nothing is changed):

- ``as flown``: the mocap suite as the campaign flew it (every run must fail again: a check that
  the flights reproduce);
- ``other noise (seed + 1)``, ``(seed + 2)``: the same sensors, another draw of their noise: the
  control. These runs were picked for failing with one draw of the noise; any change that alters
  the flight gives them another chance, so a change explains the loss only where it rescues more
  runs than another draw of the noise does;
- ``gyro range x2``: the gyroscope's range doubled, +-4000 deg/s (``Sensing.gyro_range_rad_s``;
  parts with that range exist, the ICM-42688-P's noise and errors kept);
- ``no gyro clamp``: the range at its largest accepted value, 1,000 rad/s (nothing spins that
  fast: the simulator counts 200 rad/s as lost);
- ``IMU at 1 kHz``: the ICM-42688-P at 1 kHz instead of 500 Hz;
- ``no clamp, IMU at 1 kHz``: both.

Why: the paired comparison shows these runs spin past the gyro's range on the truth far more
often than the runs held on both; a correlation. Flying them again with the clamp removed, beside
the control, measures whether the clamp causes the loss (measured 2026-11-29 on the campaign of
seed 0: it does not rescue more runs than another draw of the noise: README, "On sensors").

Run (after both flights; about a minute on the 2-core machine):

    python benches/deciding_sensing_causes.py MOCAP_DIR TRUTH_DIR --json benches/results/deciding_sensing_causes.json

Per controller and cell: the runs held on the truth and not on mocap, and how many of them hold
in each variant.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).parent))

import numpy as np  # noqa: E402
from _results import add_json_option, figure, write  # noqa: E402

import rotorfault as rf  # noqa: E402
from rotorfault.studies import deciding as D  # noqa: E402
from rotorfault.studies.storage import iter_tables, pyarrow_module, read_manifest  # noqa: E402
from rotorfault.studies.summaries import numpy_columns  # noqa: E402

CONTROLLERS = ("indi-controller", "relaxed-hover-feedback")
NO_CLAMP_RAD_S = 1000.0


def _load(path: str) -> tuple[D.DecidingCampaign, dict[str, Any]]:
    suite = D.DecidingCampaign.from_dict(read_manifest(path)["arguments"]["suite"])
    columns = numpy_columns(pyarrow_module().concat_tables(list(iter_tables(path))))
    return suite, D.rejudge_holds(suite, columns)


def variants(sensing: rf.Sensing) -> dict[str, rf.Sensing]:
    return {
        "as flown": sensing,
        # The control: the same sensors with other noise. Runs picked for failing with the
        # campaign's noise regress toward their mean with any other draw of it; a change that
        # matters must beat these.
        "other noise (seed + 1)": sensing.replace(seed=sensing.seed + 1),
        "other noise (seed + 2)": sensing.replace(seed=sensing.seed + 2),
        "gyro range x2": sensing.replace(gyro_range_rad_s=2.0 * sensing.gyro_range_in_effect_rad_s),
        "no gyro clamp": sensing.replace(gyro_range_rad_s=NO_CLAMP_RAD_S),
        "IMU at 1 kHz": sensing.replace(imu_rate_hz=1000.0),
        "no clamp, IMU at 1 kHz": sensing.replace(gyro_range_rad_s=NO_CLAMP_RAD_S, imu_rate_hz=1000.0),
    }


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("sensed", help="the suite's --out directory flown with --sensing")
    parser.add_argument("truth", help="the same suite's --out directory flown on the truth")
    add_json_option(parser)
    args = parser.parse_args()
    suite, sensed = _load(args.sensed)
    truth_suite, truth = _load(args.truth)
    if suite.sensing is None or truth_suite.sensing is not None:
        raise SystemExit("sensed, truth: the first dataset must be flown on sensors, the second on the truth")
    if dataclasses.replace(suite, sensing=None, certify=truth_suite.certify, chunk_size=truth_suite.chunk_size) != truth_suite:
        raise SystemExit("truth: not the same suite (runs, seed, vehicles, fault classes, controllers)")
    for key in ("vehicle", "fault_class", "controller", "index"):
        if not np.array_equal(sensed[key], truth[key]):
            raise SystemExit("truth: its rows are not the sensed suite's, row for row")
    lost_to_sensing = truth["holds"].astype(bool) & ~sensed["holds"].astype(bool)
    names = list(variants(suite.sensing))
    rows: list[dict[str, Any]] = []
    for cell in suite.cells:
        if cell.controller not in CONTROLLERS:
            continue
        mask = lost_to_sensing & (sensed["vehicle"] == cell.vehicle) & (sensed["fault_class"] == cell.fault_class) & (
            sensed["controller"] == cell.controller)
        indices = sensed["index"][mask].tolist()
        if not indices:
            continue
        held = {}
        for name, sensing in variants(suite.sensing).items():
            flown = D.fly_longer(dataclasses.replace(suite, sensing=sensing), cell, indices, 0.0)
            held[name] = int(sum(flown["holds"]))
        if held["as flown"]:
            raise SystemExit(f"{cell}: {held['as flown']} of the runs lost on sensors hold when flown again: the flights do not reproduce")
        rows.append({"vehicle": cell.vehicle, "fault_class": cell.fault_class, "controller": cell.controller, "runs": len(indices), "held": held})
        print(f"{cell.vehicle:17s} {cell.fault_class:19s} {cell.controller:22s} {len(indices):3d} lost to sensing; held again: "
              + ", ".join(f"{n} {held[n]}" for n in names[1:]))
    figures = []
    for controller in CONTROLLERS:
        mine = [r for r in rows if r["controller"] == controller]
        total = sum(r["runs"] for r in mine)
        for name in names[1:]:
            figures.append(figure(f"{controller}: runs held on the truth, not on {suite.sensing.suite}, held again with {name}",
                                  sum(r["held"][name] for r in mine), "runs", baseline=f"of the {total} lost to sensing", baseline_value=total))
    if args.json_path:
        write(args.json_path, "deciding_sensing_causes", "What the sensors cost in the deciding campaign, and whether the gyro's clamp causes it",
              figures)
        import json

        path = Path(args.json_path)
        data = json.loads(path.read_text(encoding="utf-8"))
        data["cells"] = rows
        data["variants"] = {n: {k: v for k in rf.Sensing.FIELDS if (v := getattr(s, k)) is not None}
                            for n, s in variants(suite.sensing).items()}
        path.write_text(json.dumps(data, indent=2) + "\n", encoding="utf-8")


if __name__ == "__main__":
    main()

"""Does the gyro's clamp cost the deciding campaign's runs on sensors? The cells where sensing
costs INDI or the relaxed hover LQR most, every applicable run of them flown on motion-capture
sensors with the IMU part's gyro range and with no clamp at all, each with three draws of the
sensors' noise, judged by the campaign's hold rule (``deciding.fly_longer`` with no extension).

Why this design: the paired comparison with the truth (``deciding_record.py --against-truth``)
shows the runs lost to sensing spin past the gyro's range far more often than those held on both:
a correlation. Flying only those runs again with a change cannot test it: they were picked for
failing with one draw of the noise, and any change that alters the flight gives them another
chance (in a first version of this bench, c3e5399, another draw of the noise alone rescued 22 and 24 of
INDI's 38 such runs). Here every run is
flown with and without the clamp under the same three noise draws, so the clamp's effect is the
difference in held runs at equal noise, and the spread over the draws is its yardstick.

- ``part's range``: the sensing as flown (+-2000 deg/s, 34.9 rad/s); noise offset 0 is the
  campaign's own flight, checked to reproduce the dataset's window values bit for bit;
- ``no gyro clamp``: ``Sensing.gyro_range_rad_s`` at its largest, 1,000 rad/s (the simulator counts
  200 rad/s as lost, so nothing clamps); the part's noise and errors kept, the same noise draws.

Run (after both flights; about 5 minutes on the 2-core machine):

    python benches/deciding_sensing_causes.py MOCAP_DIR TRUTH_DIR --json benches/results/deciding_sensing_causes.json

ke-robust (420 runs lost to sensing, 161 gained) is not flown: its losses are not concentrated in
fast spins (24 % of them past the range against 11 % of its runs held on both).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).parent))

import numpy as np  # noqa: E402
from _results import add_json_option, figure, write  # noqa: E402

import rotorfault as rf  # noqa: E402
from rotorfault.studies import deciding as D  # noqa: E402
from rotorfault.studies.storage import read_manifest  # noqa: E402

#: (vehicle, fault class, controller): where sensing cost INDI or the relaxed hover LQR more than 3
#: runs in the campaign of seed 0 (the record's against_truth).
CELLS = (
    ("ke-quadcopter", "one-rotor-hover", "relaxed-hover-feedback"),
    ("ke-quadcopter", "two-opposing-hover", "indi-controller"),
    ("ke-quadcopter", "two-opposing-hover", "relaxed-hover-feedback"),
    ("hexa-ppnnpn", "one-rotor-hover", "indi-controller"),
    ("hexa-ppnnpn", "one-rotor-forward", "indi-controller"),
)
NOISE_OFFSETS = (0, 1, 2)
NO_CLAMP_RAD_S = 1000.0


def _load(path: str) -> tuple[D.DecidingCampaign, Any, dict[str, Any]]:
    """The dataset's suite, its rows (holds judged by the current rule) and its job's arguments."""
    result = D.read_deciding(path, certify=False)
    return result.suite, result.columns, read_manifest(path)["arguments"]


def settings(sensing: rf.Sensing) -> dict[str, rf.Sensing]:
    return {"part's range": sensing, "no gyro clamp": sensing.replace(gyro_range_rad_s=NO_CLAMP_RAD_S)}


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("sensed", help="the suite's --out directory flown with --sensing")
    parser.add_argument("truth", help="the same suite's --out directory flown on the truth")
    add_json_option(parser)
    args = parser.parse_args()
    suite, sensed, arguments = _load(args.sensed)
    truth_suite, truth, truth_arguments = _load(args.truth)
    if suite.sensing is None or truth_suite.sensing is not None:
        raise SystemExit("sensed, truth: the first dataset must be flown on sensors, the second on the truth")
    if dataclasses.replace(suite, sensing=None, certify=truth_suite.certify, chunk_size=truth_suite.chunk_size) != truth_suite:
        raise SystemExit("truth: not the same suite (runs, seed, vehicles, fault classes, controllers)")
    # Flown by the controllers and sensors of this code, or the flights below are not the dataset's.
    for given, name in ((arguments, "sensed"), (truth_arguments, "truth")):
        if given.get("controllers_revision") != D.CONTROLLERS_REVISION:
            raise SystemExit(f"{name}: flown by controllers revision {given.get('controllers_revision')}, this code is {D.CONTROLLERS_REVISION}")
    if arguments.get("sensing_revision", D.SENSING_REVISION) != D.SENSING_REVISION:
        raise SystemExit(f"sensed: flown by sensing revision {arguments['sensing_revision']}, this code is {D.SENSING_REVISION}")
    for key in ("vehicle", "fault_class", "controller", "index"):
        if not np.array_equal(sensed[key], truth[key]):
            raise SystemExit("truth: its rows are not the sensed suite's, row for row")
    rows: list[dict[str, Any]] = []
    for vehicle, fault_class, controller in CELLS:
        cell = next(c for c in suite.cells if (c.vehicle, c.fault_class, c.controller) == (vehicle, fault_class, controller))
        mine = (sensed["vehicle"] == vehicle) & (sensed["fault_class"] == fault_class) & (sensed["controller"] == controller)
        flown = mine & sensed["applicable"] & (sensed["outcome"] != "design-refused")
        indices = sensed["index"][flown].tolist()
        held: dict[str, list[int]] = {}
        for name, sensing in settings(suite.sensing).items():
            held[name] = []
            for offset in NOISE_OFFSETS:
                noise = sensing.replace(seed=(sensing.seed + offset) % 2**64)
                values = D.fly_longer(dataclasses.replace(suite, sensing=noise), cell, indices, 0.0)
                if name == "part's range" and offset == 0:
                    for column in ("hold_altitude_error_m", "hold_horizontal_error_m"):
                        if not np.array_equal(np.asarray(values[column]), sensed[column][flown], equal_nan=True):
                            raise SystemExit(f"{vehicle} {fault_class} {controller}: the campaign's flights do not reproduce ({column})")
                held[name].append(int(sum(values["holds"])))
        part, free = np.array(held["part's range"]), np.array(held["no gyro clamp"])
        row = {"vehicle": vehicle, "fault_class": fault_class, "controller": controller, "runs": len(indices),
               "held_on_truth": int(np.sum(truth["holds"].astype(bool)[flown])), "noise_offsets": list(NOISE_OFFSETS), "held": held,
               "no_clamp_minus_part_mean": float(np.mean(free - part)), "part_spread_over_noise": int(part.max() - part.min())}
        rows.append(row)
        print(f"{vehicle:14s} {fault_class:19s} {controller:22s} {len(indices)} runs, truth {row['held_on_truth']}; part's range "
              f"{part.tolist()}, no clamp {free.tolist()}: no clamp - part {row['no_clamp_minus_part_mean']:+.1f} "
              f"(part's spread over the noise {row['part_spread_over_noise']})")
    figures = [figure(f"{r['vehicle']} {r['fault_class']} {r['controller']}: held with no gyro clamp minus with the part's range, "
                      f"mean over {len(NOISE_OFFSETS)} noise draws", r["no_clamp_minus_part_mean"], "runs",
                      baseline=f"spread of the part's range over the draws ({r['runs']} runs)", baseline_value=r["part_spread_over_noise"])
               for r in rows]
    if args.json_path:
        write(args.json_path, "deciding_sensing_causes", "Does the gyro's clamp cost the deciding campaign's runs on sensors?", figures)
        path = Path(args.json_path)
        data = json.loads(path.read_text(encoding="utf-8"))
        data["cells"] = rows
        data["settings"] = {n: {k: v for k in rf.Sensing.FIELDS if (v := getattr(s, k)) is not None} for n, s in settings(suite.sensing).items()}
        path.write_text(json.dumps(data, indent=2) + "\n", encoding="utf-8")


if __name__ == "__main__":
    main()

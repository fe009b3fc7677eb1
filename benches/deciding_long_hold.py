"""Do the deciding campaign's holds last? Every run a cell's best controller held in a flown
``rotorfault campaign --suite deciding --out DIR`` dataset, flown again ``--extend-s`` longer
(60 s by default: 85 s after the failure instead of 25) with the same draws and controller, and
judged by the same hold rule over the longer window (``rotorfault.studies.deciding.fly_longer``:
within 1 m altitude and 3 m horizontal from 5 s after the failure to the end, not lost, and the
spin not growing past the rule's allowance between the window's last two 5 s spans).

Why: the rule judges a spin's growth over the campaign's window only, and without rotational
damping it allows 1 rad/s per 5 s; a relaxed spin that creeps up more slowly than that over the
window and runs away later (seen on the x500, suite seed 1: two opposing rotors, 15.4 -> 16.0
rad/s in the window, 42 rad/s 30 s later) counts as held. This measures how many of the held runs
that is, per cell.

Run (after the flight; about 3 minutes on the 2-core machine):

    python benches/deciding_long_hold.py DIR --record python/rotorfault/papers/bench_results/deciding_full_run.json

Per cell: the best controller (the record's decision), its held runs in the dataset, and how
many of them still hold flown longer; the runs that do not, with their outcome and spin.
"""

from __future__ import annotations

import argparse
import json
import multiprocessing
import sys
import time
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).parent))

from _results import add_json_option, figure, write  # noqa: E402

from rotorfault.studies import deciding as D  # noqa: E402
from rotorfault.studies.storage import read_manifest  # noqa: E402

CHUNK = 50


def _suite(path: Path) -> D.DecidingCampaign:
    return D.DecidingCampaign.from_dict(read_manifest(path)["arguments"]["suite"])


def _fly(job: tuple[str, str, str, str, list[int], float]) -> tuple[str, str, str, list[int], dict[str, list[Any]]]:
    path, vehicle, fault_class, controller, indices, extend_s = job
    suite = _suite(Path(path))
    cell = next(c for c in suite.cells if (c.vehicle, c.fault_class, c.controller) == (vehicle, fault_class, controller))
    return vehicle, fault_class, controller, indices, D.fly_longer(suite, cell, indices, extend_s)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("dataset", type=Path, help="a deciding campaign's --out directory")
    parser.add_argument("--record", type=Path, required=True, help="its record (benches/deciding_record.py --json): the best controller per cell")
    parser.add_argument("--extend-s", type=float, default=60.0, help="how much longer each held run flies, s (default 60)")
    parser.add_argument("--processes", type=int, default=2)
    add_json_option(parser)
    args = parser.parse_args()
    started = time.perf_counter()
    arguments = read_manifest(args.dataset)["arguments"]
    # Held runs flown again by other controllers than flew them would measure nothing: refused.
    if arguments.get("controllers_revision") != D.CONTROLLERS_REVISION:
        sys.exit(f"{args.dataset} was flown by controllers revision {arguments.get('controllers_revision')}, "
                 f"these are revision {D.CONTROLLERS_REVISION}: fly it again")
    record = json.loads(args.record.read_text()).get("campaign", {})
    if record.get("suite") != arguments["suite"]:
        sys.exit(f"{args.record} is the record of another suite than {args.dataset}'s")
    columns = D.read_deciding(args.dataset, certify=False).columns  # holds judged by the current rule
    decision = record["decision"]
    jobs = []
    for d in decision:
        held = ((columns["vehicle"] == d["vehicle"]) & (columns["fault_class"] == d["fault_class"])
                & (columns["controller"] == d["controller"]) & columns["holds"])
        indices = sorted(int(i) for i in columns["index"][held])
        for k in range(0, len(indices), CHUNK):
            jobs.append((str(args.dataset), d["vehicle"], d["fault_class"], d["controller"], indices[k:k + CHUNK], args.extend_s))
    with multiprocessing.get_context("spawn").Pool(args.processes) as pool:
        parts = pool.map(_fly, jobs, chunksize=1)
    figures = []
    total_held = total_lasting = 0
    for d in decision:
        key = (d["vehicle"], d["fault_class"], d["controller"])
        rows = [(i, {name: values[j] for name, values in flown.items()})
                for v, f, c, indices, flown in parts if (v, f, c) == key for j, i in enumerate(indices)]
        lasting = [i for i, r in rows if r["holds"]]
        total_held += len(rows)
        total_lasting += len(lasting)
        print(f"{d['vehicle']:16s} {d['fault_class']:18s} {d['controller']:22s} held {len(rows):4d}, "
              f"still held {args.extend_s:.0f} s longer {len(lasting):4d}")
        for i, r in rows:
            if not r["holds"]:
                print(f"    run {i:4d}: {r['outcome']}, altitude {r['hold_altitude_error_m']:.2f} m, horizontal "
                      f"{r['hold_horizontal_error_m']:.2f} m, spin {r['hold_final_spin_rad_s']:.1f} rad/s "
                      f"(+{r['hold_spin_growth_rad_s']:.2f} over the last 5 s)")
        figures.append(figure(f"{'/'.join(key)}: held runs still held {args.extend_s:.0f} s longer", len(lasting), "runs",
                              baseline="held in the campaign's window", baseline_value=len(rows),
                              ratio=len(lasting) / len(rows) if rows else None))
    print(f"all cells: {total_lasting} of {total_held} held runs still hold {args.extend_s:.0f} s longer "
          f"({time.perf_counter() - started:.0f} s)")
    write(args.json_path, "deciding_long_hold", "The deciding campaign's held runs flown longer", figures)


if __name__ == "__main__":
    main()

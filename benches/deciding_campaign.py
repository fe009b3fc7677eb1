"""The deciding campaign (issue 30): throughput per controller and the full campaign's time.

Run:  python benches/deciding_campaign.py [--runs N] [--json PATH]

(a) per controller: the deciding suite restricted to that controller, ``N`` runs per cell
    (default 20) over every vehicle and fault class it applies to, flown through
    ``run_deciding`` (Rust batches, summaries only): flown runs/s and control steps/s (400 Hz,
    each run ``fault time + 25 s``).
(b) baseline in the same run: the existing campaign path (``run_campaign``, Ke's quadcopter,
    summaries only) over the same number of runs of 30 s; ratio (a)/(b) in steps/s.
(c) extrapolation: (a) is the full grid with fewer runs per cell (same cells, same draw
    distribution, so the same share of runs flown, refused or not applicable): the full suite's
    time (1,000 runs per cell) is (a)'s wall time x 1000 / N. Target (issue 30): < 15 minutes.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))

import numpy as np  # noqa: E402
from _results import add_json_option, figure, write  # noqa: E402

import rotorfault as rf  # noqa: E402
from rotorfault.studies import Campaign, run_campaign  # noqa: E402
from rotorfault.studies import deciding as D  # noqa: E402


def steps_of(columns: dict[str, np.ndarray]) -> int:
    flown = columns["outcome"] != "not-flown"
    flown &= columns["outcome"] != "design-refused"
    return int(np.sum(np.round((columns["fault_time_s"][flown] + D.AFTER_FAULT_S) / D.DT_S)))


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--runs", type=int, default=20, help="runs per cell of (a)")
    add_json_option(parser)
    args = parser.parse_args()
    print(f"rotorfault {rf.__version__}, {os.cpu_count()} CPUs, load {os.getloadavg()[0]:.1f}")
    rates: dict[str, float] = {}
    walls: dict[str, float] = {}
    D._lanzon_design("lanzon-quadrotor")  # the H-infinity synthesis, once per process: not a per-run cost
    figures = []
    total_steps = total_wall = 0.0
    for name in D.CONTROLLERS:
        suite = D.DecidingCampaign(runs=args.runs, controllers=(name,), chunk_size=50, certify=False)  # flight throughput
        t = time.perf_counter()
        result = D.run_deciding(suite, progress=False)
        wall = time.perf_counter() - t
        cols = dict(result.columns)
        flown = int(np.sum((cols["outcome"] != "not-flown") & (cols["outcome"] != "design-refused")))
        steps = steps_of(cols)
        total_steps += steps
        total_wall += wall
        rates[name] = flown / wall if flown else float("inf")
        walls[name] = wall
        print(f"(a) {name:<22} {flown:>5} flown runs in {wall:6.1f} s: {flown / wall:7.1f} runs/s, {steps / wall / 1e6:.2f} M steps/s")
        if flown:
            figures.append(figure(f"deciding campaign, {name}: control steps/s", steps / wall, "steps/s"))
            figures.append(figure(f"deciding campaign, {name}: runs/s", flown / wall, "runs/s"))
    n = max(200, int(total_steps // 12_000))
    c = Campaign(runs=n, seed=1, duration_s=30.0, chunk_size=100)
    t = time.perf_counter()
    run_campaign(c, progress=False)
    base_wall = time.perf_counter() - t
    base_rate = n * 12_000 / base_wall
    rate = total_steps / total_wall
    print(f"(b) baseline run_campaign (ke-hil, 30 s), {n} runs: {base_rate / 1e6:.2f} M steps/s; "
          f"ratio (a, all controllers)/(b) = {rate / base_rate:.2f}")
    figures.append(figure("deciding campaign, all controllers: control steps/s", rate, "steps/s",
                          baseline="run_campaign, Ke's quadcopter, summaries only", baseline_value=base_rate, ratio=rate / base_rate))
    # (c) The suite of (a) is the full grid with fewer runs per cell: same cells, same draw
    # distribution, so the full campaign's time is (a)'s wall time scaled by 1000 / runs.
    full = D.DecidingCampaign(runs=1000)
    seconds = sum(walls.values()) * full.runs / args.runs
    print(f"(c) full campaign, 1,000 runs per cell, {len(full.cells)} cells, {full.total_runs:,} rows: "
          f"(a)'s {sum(walls.values()):.1f} s x {full.runs / args.runs:g}")
    print(f"    estimated time on this machine (load {os.getloadavg()[0]:.1f}): {seconds / 60:.1f} min "
          f"(target < 15 min: {'PASS' if seconds < 900 else 'FAIL'})")
    figures.append(figure("deciding campaign, 1,000 runs per cell: estimated time", seconds / 60, "min", target="< 15"))
    write(args.json_path, "deciding_campaign", "The deciding campaign (issue 30): throughput and the full campaign's time", figures,
          reduced=None if args.runs >= 20 else f"{args.runs} runs per cell in (a)")


if __name__ == "__main__":
    main()

"""Batches in SIMD lanes against the scalar path, one thread each, in one run (issue 32).

Run:  python benches/simulation_lanes.py [--runs N] [--reps R] [--json PATH]   (about a minute)

Two closed-loop batches, each flown with ``rf.simulate_batch(..., lanes="scalar")`` (one run at
a time) and ``lanes="auto"`` (four runs per AVX2 register), alternately ``--reps`` times on one
rayon thread (``RAYON_NUM_THREADS=1``, set before the package loads); the figures are the median
process CPU times (which other processes on a shared machine do not inflate) and their ratio.
Before timing, every column the two settings record is checked equal bit for bit.

- hover LQR: the quad-x preset (400 Hz control, 2 RK4 substeps, 20 ms rotor lag) under
  ``rf.lqr_hover``, perturbed starts around 10 m;
- Ke FTC: the ``ke-hil`` preset (Ke's Table IV gains, QP allocation every step, rotor lag and
  drag) losing rotor 1 at 2 s in every run (the lanes group runs whose fault times are equal).

Target (issue 32): the lanes >= 3x the scalar path per core for both batches. The Rust bench
``cargo bench --bench lanes`` measures the same without Python (its figures in benches/README.md).
"""

from __future__ import annotations

import os

os.environ["RAYON_NUM_THREADS"] = "1"  # before rotorfault loads: its rayon pool reads it once

import argparse  # noqa: E402
import statistics  # noqa: E402
import time  # noqa: E402
from collections.abc import Callable  # noqa: E402

import numpy as np  # noqa: E402

import rotorfault as rf  # noqa: E402
from rotorfault.control import ke  # noqa: E402

RUNS = 16
DURATION_S = 10.0
TARGET_RATIO = 3.0
COLUMNS = ("position", "velocity", "quaternion", "euler", "omega", "primary_axis", "rotor_command", "rotor_thrust", "efficiency",
           "rows_on_grid", "off_grid_row")


def starts(runs: int) -> list[rf.State]:
    rng = np.random.default_rng(32)
    return [rf.State(position=(0, 0, -10) + rng.uniform(-0.3, 0.3, size=3), velocity=rng.uniform(-0.3, 0.3, size=3),
                     euler=rng.uniform(-0.05, 0.05, size=3)) for _ in range(runs)]


def hover_lqr(runs: int) -> Callable[[str], rf.BatchResult]:
    sim = rf.Simulator(rf.Airframe.preset("quad-x"), dt_s=1 / 400, substeps=2,
                       actuator=rf.FixedPitchActuator(time_constant_s=0.02))
    controller = rf.lqr_hover(sim, position=(0, 0, -10))
    x0s = starts(runs)
    return lambda lanes: rf.simulate_batch(sim, x0s, DURATION_S, controllers=controller, record_every=40,
                                           lanes=lanes)  # type: ignore[arg-type]


def ke_ftc(runs: int) -> Callable[[str], rf.BatchResult]:
    preset = ke.preset("ke-hil")
    sim = preset.simulator()
    controller = rf.UniformPassiveFtc(preset.airframe, gains=preset.gains, position=(0, 0, -10))
    x0s = starts(runs)
    faults = [[rf.RotorFault(1, 2.0, 0.0)]] * runs
    return lambda lanes: rf.simulate_batch(sim, x0s, DURATION_S, controllers=controller, faults=faults,
                                           record_every=40, lanes=lanes)  # type: ignore[arg-type]


def timed(fly: Callable[[str], rf.BatchResult], lanes: str) -> float:
    start = time.process_time()
    fly(lanes)
    return time.process_time() - start


def main() -> None:
    from _results import add_json_option, figure, write

    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--runs", type=int, default=RUNS, help=f"runs per batch (default {RUNS})")
    parser.add_argument("--reps", type=int, default=7, help="timed calls of each setting (default 7)")
    add_json_option(parser)
    args = parser.parse_args()
    if args.runs < 4 or args.reps < 1:
        parser.error("--runs: at least 4 (one group of lanes); --reps: at least 1")
    figures = []
    for name, make in (("hover LQR", hover_lqr), ("Ke FTC", ke_ftc)):
        fly = make(args.runs)
        scalar, auto = fly("scalar"), fly("auto")
        for column in COLUMNS:
            np.testing.assert_array_equal(getattr(auto.columns, column), getattr(scalar.columns, column),
                                          err_msg=f"{name}: {column}")
        assert not scalar.diverged.any(), f"{name}: the benched flights must not diverge"
        samples = [(timed(fly, "scalar"), timed(fly, "auto")) for _ in range(args.reps)]
        scalar_s = statistics.median(s for s, _ in samples)
        lanes_s = statistics.median(a for _, a in samples)
        ratio = scalar_s / lanes_s
        print(f"{name}: {args.runs} runs x {DURATION_S:g} s, one thread: scalar {scalar_s * 1e3:.1f} ms, "
              f"lanes {lanes_s * 1e3:.1f} ms CPU -> lanes {ratio:.2f}x the scalar path "
              f"(target {TARGET_RATIO:g}x: {'met' if ratio >= TARGET_RATIO else 'NOT met'})")
        figures.append(figure(f"{name}: batch of {args.runs} x {DURATION_S:g} s, one thread, lanes='auto' (CPU time)",
                              lanes_s, "s", baseline="lanes='scalar', same run", baseline_value=scalar_s, ratio=ratio,
                              target=f">= {TARGET_RATIO:g}x"))
    write(args.json_path, "simulation_lanes",
          "Closed-loop batches in SIMD lanes (four runs per AVX2 register) against the scalar path, one thread "
          "(issue 32)", figures, reduced=None if args.runs == RUNS else f"{args.runs} runs instead of {RUNS} (--runs)")


if __name__ == "__main__":
    main()

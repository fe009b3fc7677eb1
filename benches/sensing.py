"""Flying on sensors against flying on the truth: closed-loop batches of every controller the
project flies on sensors, both ways in one run, and the ratio of their speeds (issue 29: batches
with sensors and the estimator at >= 50 % of the truth-state speed).

Run:  python benches/sensing.py [--runs N] [--rounds K] [--json benches/results/sensing.json]
      (about a minute on an idle 2-core machine; build the extension with fat LTO first:
      ``pip install -e . --no-deps`` without the no-LTO variables)

Per controller, one batch (``rf.simulate_batch``, ``--runs`` runs, 16 by default, each from its own
seeded start offset; recorded at 10 Hz) on the truth and the same batch on motion capture with the
estimator (the sensing the project's reports fly it with): its own vehicle and scenario,

- ``ke``: Ke's uniform passive FTC (``ke-hil`` preset, ke-quadcopter, 400 Hz), rotor 1 lost at 2 s,
  10 s; ``rf.Sensing()`` (ICM-42688-P at 500 Hz, OptiTrack at 240 Hz, DShot rotor speeds);
- ``lanzon``: Lanzon's controller, design (c), Scenario B (rotor 2 dead, 1 kHz loop), 10 s; the IMU
  at its loop rate (``lanzon.MOCAP_AT_LOOP_RATE``, 1 kHz);
- ``wang-lqr``: Wang's LQR on the VPP quadcopter with propeller 1 failed, scenario 1, 1 kHz loop, 10 s;
  the IMU at 1 kHz (as ``wang``'s report);
- ``hover-lqr``: ``rf.lqr_hover`` on quad-x at 400 Hz, no fault, 10 s; ``rf.Sensing()``;
- ``indi``: ``rf.IndiController`` on the ke-quadcopter, rotor 1 lost at 2 s (and reported then),
  10 s; ``rf.Sensing()``.

Both batches fly the default way (``lanes='auto'``: four runs per AVX2 register where the batch
allows, issue 32; on sensors the truth flies in the lanes and so do the runs' estimators where
their sensors share one schedule, as motion capture's do, each run's sensors beside them, bit for
bit the scalar results); the truth flown one run at a time
(``lanes='scalar'``) is timed beside them and its ratio printed and recorded for reference (the
target is on the default truth batch), and so is the sensed batch flown one run at a time (the
path every sensed run took before session h39).

Timing: ``--rounds`` rounds (7), truth, sensors, scalar truth and scalar sensors in turn in each so all see the
same load;
each batch timed in process CPU time (``time.process_time``: every thread, ns resolution; a batch is
0.1-1 s of it) and in wall time; the medians, and the ratio truth time / sensed time (the sensed
batch's speed as a fraction of the truth's). The ratio is taken on CPU time, which other processes
on a shared machine do not inflate; the wall-time ratio is printed beside it. Before timing, every
truth run and every sensed run must fly to the end without divergence.
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

import rotorfault as rf
from rotorfault.control import ke
from rotorfault.control.lanzon import LanzonController, LanzonVehicle
from rotorfault.papers import lanzon, wang

sys.path.insert(0, str(Path(__file__).parent))
from _results import add_json_option, figure, write  # noqa: E402

RUNS = 16
ROUNDS = 7
DURATION_S = 10.0
RECORD_HZ = 10.0
TARGET_RATIO = 0.5
HOVER_M = (0.0, 0.0, -10.0)


@dataclass(frozen=True)
class Case:
    """One controller's batch: its simulator on the truth and on sensors, starts, controllers, faults."""

    name: str
    what: str
    truth: rf.Simulator
    sensed: rf.Simulator
    starts: list[rf.State]
    controllers: Any
    faults: list[list[rf.RotorFault]] | None

    def fly(self, sensed: bool, lanes: str = "auto") -> rf.BatchResult:
        sim = self.sensed if sensed else self.truth
        every = max(1, round(1.0 / (RECORD_HZ * sim.dt_s)))
        return rf.simulate_batch(sim, self.starts, DURATION_S, controllers=self.controllers, faults=self.faults,
                                 record_every=every, lanes=lanes)

    @property
    def steps(self) -> int:
        return len(self.starts) * round(DURATION_S / self.truth.dt_s)


def _offsets(runs: int, seed: int, base: np.ndarray, scale: float) -> list[rf.State]:
    rng = np.random.default_rng(seed)
    return [rf.State.from_vector(base + np.concatenate([rng.uniform(-scale, scale, 3), np.zeros(9)]))
            for _ in range(runs)]


def ke_case(runs: int) -> Case:
    pre = ke.preset("ke-hil")
    faults = [[rf.RotorFault(1, 2.0)]] * runs
    return Case("ke", "Ke FTC (ke-hil), rotor 1 lost at 2 s, 400 Hz, IMU 500 Hz", pre.simulator(),
                pre.simulator(sensing=rf.Sensing()), _offsets(runs, 1, rf.State(position=HOVER_M).vector(), 0.2),
                rf.UniformPassiveFtc(pre.airframe, gains=pre.gains, position=HOVER_M), faults)


def indi_case(runs: int) -> Case:
    pre = ke.preset("ke-hil")
    faults = [[rf.RotorFault(1, 2.0)]] * runs
    return Case("indi", "INDI, rotor 1 lost at 2 s, 400 Hz, IMU 500 Hz", pre.simulator(),
                pre.simulator(sensing=rf.Sensing()), _offsets(runs, 5, rf.State(position=HOVER_M).vector(), 0.2),
                rf.IndiController(pre.airframe, failures=faults[0], position=HOVER_M), faults)


def lanzon_case(runs: int) -> Case:
    vehicle = LanzonVehicle()
    case = lanzon.design_case("c")
    sc = lanzon.scenario("B")
    controller = LanzonController(case.design(vehicle), position=sc.position, outer_loop=case.outer_loop)
    return Case("lanzon", "Lanzon, design (c), Scenario B, rotor 2 dead, 1 kHz, IMU 1 kHz",
                vehicle.simulator(limits=case.limits), vehicle.simulator(limits=case.limits,
                                                                         sensing=lanzon.MOCAP_AT_LOOP_RATE),
                _offsets(runs, 2, sc.initial_state().vector(), 0.2), controller, [[rf.RotorFault(2, 0.0)]] * runs)


def wang_case(runs: int) -> Case:
    vehicle = rf.vpp.preset("wang")
    s = wang.scenario(1, duration_s=DURATION_S)
    law = wang.controller(vehicle, s)
    base = vehicle.simulator(failed=(1,))

    def sim(sensing: rf.Sensing | None) -> rf.Simulator:
        return rf.Simulator(base.airframe, actuator=vehicle.actuator, drag=vehicle.drag, dt_s=wang.DT_S,
                            ground_z_m=wang.GROUND_Z_M, sensing=sensing)

    return Case("wang-lqr", "Wang's LQR, VPP, propeller 1 failed, scenario 1, 1 kHz, IMU 1 kHz", sim(None),
                sim(rf.Sensing(imu_rate_hz=1000.0)), _offsets(runs, 3, rf.State().vector(), 0.05), law, None)


def hover_case(runs: int) -> Case:
    quad = rf.Airframe.preset("quad-x")
    truth = rf.Simulator(quad)
    return Case("hover-lqr", "hover LQR (rf.lqr_hover), quad-x, 400 Hz, IMU 500 Hz", truth,
                rf.Simulator(quad, sensing=rf.Sensing()), _offsets(runs, 4, rf.State(position=HOVER_M).vector(), 0.2),
                rf.lqr_hover(truth, position=HOVER_M), None)


CASES: tuple[Callable[[int], Case], ...] = (ke_case, lanzon_case, wang_case, hover_case, indi_case)


def timed(fly: Callable[[], Any]) -> tuple[float, float]:
    cpu, wall = time.process_time(), time.perf_counter()
    fly()
    return time.process_time() - cpu, time.perf_counter() - wall


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--runs", type=int, default=RUNS, help=f"runs per batch (default {RUNS})")
    parser.add_argument("--rounds", type=int, default=ROUNDS, help=f"timed rounds per batch (default {ROUNDS})")
    add_json_option(parser)
    args = parser.parse_args()
    if args.runs < 1 or args.rounds < 1:
        parser.error("--runs and --rounds: must be >= 1")
    print(f"rotorfault {rf.__version__}, {platform.processor() or platform.machine()}, {os.cpu_count()} CPUs, "
          f"load average {os.getloadavg()[0]:.1f}")
    figures = []
    for make in CASES:
        case = make(args.runs)
        for sensed in (False, True):
            batch = case.fly(sensed)
            lost = int(np.count_nonzero(batch.diverged))
            assert lost == 0, f"{case.name}: {lost} runs lost {'on sensors' if sensed else 'on the truth'}"
        samples = [(timed(lambda: case.fly(False)), timed(lambda: case.fly(True)),
                    timed(lambda: case.fly(False, lanes="scalar")), timed(lambda: case.fly(True, lanes="scalar")))
                   for _ in range(args.rounds)]
        truth_cpu = statistics.median(s[0][0] for s in samples)
        truth_wall = statistics.median(s[0][1] for s in samples)
        sensed_cpu = statistics.median(s[1][0] for s in samples)
        sensed_wall = statistics.median(s[1][1] for s in samples)
        scalar_cpu = statistics.median(s[2][0] for s in samples)
        sensed_scalar_cpu = statistics.median(s[3][0] for s in samples)
        ratio = truth_cpu / sensed_cpu
        # Per control step and run: the truth's step, and what sensing adds to it (the sensors,
        # the tape they read and the estimator). The ratio is truth / (truth + added): it reaches
        # the target only where the truth's step costs at least what sensing adds.
        truth_us = 1e6 * truth_cpu / case.steps
        added_us = 1e6 * (sensed_cpu - truth_cpu) / case.steps
        print(f"{case.name:10s} {case.what}: {args.runs} x {DURATION_S:g} s, CPU truth {1e3 * truth_cpu:7.1f} ms, "
              f"sensors {1e3 * sensed_cpu:7.1f} ms, speed / truth speed {ratio:.2f} "
              f"({'met' if ratio >= TARGET_RATIO else 'NOT met'}); wall {1e3 * truth_wall:.1f} / "
              f"{1e3 * sensed_wall:.1f} ms ({truth_wall / sensed_wall:.2f}); truth one run at a time "
              f"(lanes='scalar') {1e3 * scalar_cpu:.1f} ms: {scalar_cpu / sensed_cpu:.2f}; sensors one run at a time "
              f"{1e3 * sensed_scalar_cpu:.1f} ms (lanes {sensed_scalar_cpu / sensed_cpu:.2f}x); per control step and "
              f"run: truth {truth_us:.3f} us, sensing adds {added_us:.3f} us")
        figures.append(figure(
            f"{case.name}: {case.what}; batch of {args.runs} x {DURATION_S:g} s on motion capture + estimator, "
            f"CPU time per batch (wall {1e3 * sensed_wall:.1f} ms)",
            sensed_cpu * 1e3, "ms", baseline=f"the same batch on the truth (wall {1e3 * truth_wall:.1f} ms)",
            baseline_value=truth_cpu * 1e3, ratio=ratio, target=f">= {TARGET_RATIO} of the truth's speed"))
        figures.append(figure(
            f"{case.name}: the same sensed batch against the truth flown one run at a time (lanes='scalar'); "
            f"for reference", sensed_cpu * 1e3, "ms",
            baseline="the same batch on the truth, lanes='scalar'", baseline_value=scalar_cpu * 1e3,
            ratio=scalar_cpu / sensed_cpu))
        figures.append(figure(
            f"{case.name}: the same sensed batch (its truth in lanes) against itself flown one run at a time "
            f"(lanes='scalar'); for reference", sensed_cpu * 1e3, "ms",
            baseline="the same batch on sensors, lanes='scalar'", baseline_value=sensed_scalar_cpu * 1e3,
            ratio=sensed_scalar_cpu / sensed_cpu))
        figures.append(figure(
            f"{case.name}: what flying on sensors adds per control step and run (the sensed batch's CPU time "
            f"less the truth's, over its {case.steps} control steps); the 0.5 target holds where the truth's "
            f"step costs at least this; for reference", added_us, "us",
            baseline="the truth's own step (the truth batch's CPU time over its control steps)",
            baseline_value=truth_us, ratio=truth_us / added_us))
    reduced = None if (args.runs, args.rounds) == (RUNS, ROUNDS) else f"--runs {args.runs} --rounds {args.rounds}"
    write(args.json_path, "sensing", "Closed-loop batches on sensors and the estimator against the truth (issue 29)",
          figures, reduced=reduced)


if __name__ == "__main__":
    main()

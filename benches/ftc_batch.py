"""Closed-loop fault scenarios per second: Ke's uniform passive FTC in a rotorfault batch.

Run:  pip install ".[bench]" && python benches/ftc_batch.py [--runs N] [--json PATH]   (about a minute;
      ``--runs`` below 1,000 is a reduced run, labelled so in the JSON)

The batch: 1,000 runs of 30 s each of the ke-quadcopter with the ``ke-hil`` controller preset
(Table IV gains, QP allocation through the active-set solver every step, rotor lag, rotational and
translational drag), 400 Hz control with 4 RK4 substeps (12 million control steps, 48 million RK4
steps). Each run draws one of the stabilisable fault patterns of Ke Section II-B (one rotor, one
plus partial faults, two opposite, two adjacent (Ke's right pair), three), random first-failure time in
[1, 5] s, the next failures 6-10 s later, and a random start within 1 m of the setpoint.
Recording is thinned to 1 Hz (``record_every=400``) so memory stays bounded.

Reported: control steps per second end to end from Python (argument conversion, the parallel
batch with the GIL released, the stacked result), the same for one run on one thread, and in the
same run RotorPy 3 flying its SE3 hover controller (no rotor faults: it has none) as the peer
baseline, when RotorPy is installed (``.[bench]``).

Target (issue 5): at least 500,000 closed-loop control steps per second on the 2-core machine.

INDI (issue 30): in the same run, the same kind of batch (``--runs`` runs) over the patterns INDI
flies on this quadrotor (one rotor, one plus undetected partial faults, two opposite; INDI is told
of each complete loss at its time), flown by ``rf.IndiController`` and, as the baseline on exactly
the same scenarios, by Ke's FTC: INDI's closed-loop steps/s and the ratio to Ke's.
"""

from __future__ import annotations

import importlib.util
import os
import platform
import time
from pathlib import Path

import numpy as np

import rotorfault as rf
from rotorfault.control import ke

RUNS = 1000
T_FINAL_S = 30.0
TARGET_STEPS_PER_S = 500_000
PATTERNS = (
    ("one", ((1, 0.0),)),
    ("one+partial", ((1, 0.0), (2, 0.7), (3, 0.6), (4, 0.8))),
    ("two-opposite", ((1, 0.0), (3, 0.0))),
    ("two-adjacent", ((1, 0.0), (2, 0.0))),
    ("three", ((1, 0.0), (2, 0.0), (3, 0.0))),
)


#: The patterns INDI flies on the ke-quadcopter (it refuses two adjacent and three: no hover with
#: zero roll and pitch torque is left).
INDI_PATTERNS = tuple(p for p in PATTERNS if p[0] in ("one", "one+partial", "two-opposite"))


def batch_inputs(rng: np.random.Generator, runs: int = RUNS,
                 patterns: tuple[tuple[str, tuple[tuple[int, float], ...]], ...] = PATTERNS,
                 ) -> tuple[list[rf.State], list[list[rf.RotorFault]], list[str]]:
    starts, faults, names = [], [], []
    for _ in range(runs):
        name, pattern = patterns[int(rng.integers(len(patterns)))]
        t = float(rng.uniform(1.0, 5.0))
        run_faults = []
        for k, (rotor, efficiency) in enumerate(pattern):
            if k > 0 and not (name == "one+partial" and k > 1):
                t += float(rng.uniform(6.0, 10.0))
            run_faults.append(rf.RotorFault(rotor, t, efficiency))
        starts.append(rf.State(position=(0, 0, -10) + rng.uniform(-1, 1, size=3)))
        faults.append(run_faults)
        names.append(name)
    return starts, faults, names


def rotorpy_steps_per_s() -> float | None:
    from rotorfault._util.optional import is_available

    if not is_available("rotorpy"):
        return None
    path = Path(__file__).with_name("simulation_rotorpy.py")
    spec = importlib.util.spec_from_file_location("simulation_rotorpy", path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    fly, _ = module.rotorpy_setup()
    wall, steps, _, _ = fly()
    return float(steps / wall)


def indi_comparison(sim: rf.Simulator, preset: ke.FtcPreset, runs: int, steps_per_run: int) -> tuple[float, float, int, float]:
    """INDI's batch and Ke's FTC on the same INDI-flyable scenarios: (INDI steps/s, INDI one run on
    one thread, INDI runs lost, Ke steps/s)."""
    starts, faults, _ = batch_inputs(np.random.default_rng(30), runs, INDI_PATTERNS)
    indi = [rf.IndiController(preset.airframe, failures=[f for f in fl if f.efficiency == 0.0], position=(0, 0, -10))
            for fl in faults]
    ftc = rf.UniformPassiveFtc(preset.airframe, gains=preset.gains, position=(0, 0, -10))
    t0 = time.perf_counter()
    single = sim.run(starts[0], T_FINAL_S, controller=indi[0], faults=faults[0], record_every=400)
    single_rate = steps_per_run / (time.perf_counter() - t0)
    assert not single.diverged
    t0 = time.perf_counter()
    batch = rf.simulate_batch(sim, starts, T_FINAL_S, controllers=indi, faults=faults, record_every=400)
    indi_rate = runs * steps_per_run / (time.perf_counter() - t0)
    t0 = time.perf_counter()
    rf.simulate_batch(sim, starts, T_FINAL_S, controllers=ftc, faults=faults, record_every=400)
    ke_rate = runs * steps_per_run / (time.perf_counter() - t0)
    return indi_rate, single_rate, int(np.count_nonzero(batch.diverged)), ke_rate


def main() -> None:
    import argparse

    from _results import add_json_option, figure, write

    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--runs", type=int, default=RUNS, help=f"runs in the batch (default {RUNS})")
    add_json_option(parser)
    args = parser.parse_args()
    runs = args.runs
    if runs < 1:
        parser.error("--runs: must be >= 1")
    print(f"rotorfault {rf.__version__}, {platform.processor() or platform.machine()}, {os.cpu_count()} CPUs")
    preset = ke.preset("ke-hil")
    sim = preset.simulator()
    rng = np.random.default_rng(5)
    starts, faults, names = batch_inputs(rng, runs)
    controller = rf.UniformPassiveFtc(preset.airframe, gains=preset.gains, position=(0, 0, -10))
    steps_per_run = round(T_FINAL_S / sim.dt_s)

    # One run on one thread.
    t0 = time.perf_counter()
    single = sim.run(starts[0], T_FINAL_S, controller=controller, faults=faults[0], record_every=400)
    single_s = time.perf_counter() - t0
    assert not single.diverged

    t0 = time.perf_counter()
    batch = rf.simulate_batch(sim, starts, T_FINAL_S, controllers=controller, faults=faults, record_every=400)
    batch_s = time.perf_counter() - t0
    diverged = [names[i] for i in np.nonzero(batch.diverged)[0]]
    total_steps = runs * steps_per_run
    rate = total_steps / batch_s
    final_r = np.abs(batch.omega[:, -1, 2])
    print(f"\nbatch: {runs} runs x {T_FINAL_S:.0f} s at {1 / sim.dt_s:.0f} Hz, {sim.substeps} RK4 substeps: "
          f"{total_steps / 1e6:.0f} M control steps in {batch_s:.2f} s")
    print(f"  {rate:,.0f} closed-loop control steps/s  (target {TARGET_STEPS_PER_S:,}: "
          f"{'met' if rate >= TARGET_STEPS_PER_S else 'NOT met'})")
    print(f"  one run, one thread: {steps_per_run / single_s:,.0f} steps/s")
    print(f"  runs lost: {len(diverged)} of {runs} {sorted(set(diverged))}; final |r| median "
          f"{np.median(final_r[np.isfinite(final_r)]):.1f} rad/s")
    peer = rotorpy_steps_per_s()
    if peer is None:
        from rotorfault._util.optional import install_hint

        print(f"  RotorPy not installed ({install_hint('rotorpy')}): no peer baseline")
    else:
        print(f"  RotorPy 3 SE3 hover (no faults), same run: {peer:,.0f} steps/s -> rotorfault is {rate / peer:,.0f}x")
    indi_rate, indi_single, indi_lost, ke_same_rate = indi_comparison(sim, preset, runs, steps_per_run)
    print(f"\nINDI: {runs} runs x {T_FINAL_S:.0f} s over {', '.join(p[0] for p in INDI_PATTERNS)}: "
          f"{indi_rate:,.0f} closed-loop control steps/s (one run, one thread: {indi_single:,.0f})")
    print(f"  Ke's FTC on the same scenarios, same run: {ke_same_rate:,.0f} steps/s -> INDI runs at "
          f"{indi_rate / ke_same_rate:.2f}x; runs lost: INDI {indi_lost} of {runs}")
    write(args.json_path, "ftc_batch",
          f"Ke's uniform passive FTC: {runs:,} fault scenarios of {T_FINAL_S:g} s at {1 / sim.dt_s:.0f} Hz, "
          f"{sim.substeps} RK4 substeps, QP allocation every step, rf.simulate_batch", [
              figure("closed-loop control steps/s, batch, end to end from Python", rate, "control steps/s",
                     baseline=None if peer is None else "RotorPy 3 SE3 hover (no faults), same run",
                     baseline_value=peer, ratio=None if peer is None else rate / peer, target=f">= {TARGET_STEPS_PER_S:,}/s"),
              figure("one run, one thread", steps_per_run / single_s, "control steps/s"),
              figure("runs lost", len(diverged), "runs"),
              figure("INDI (issue 30): closed-loop control steps/s, batch, end to end from Python", indi_rate,
                     "control steps/s", baseline="Ke's FTC on the same scenarios, same run",
                     baseline_value=ke_same_rate, ratio=indi_rate / ke_same_rate),
              figure("INDI: one run, one thread", indi_single, "control steps/s"),
              figure("INDI: runs lost", indi_lost, "runs"),
          ], reduced=None if runs == RUNS else f"{runs:,} runs instead of {RUNS:,} (--runs)")


if __name__ == "__main__":
    main()

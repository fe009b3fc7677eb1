"""Simulator throughput: rotorfault's parallel batch (Rust, rayon) vs RotorPy, in one run.

Run:  python benches/simulation_rotorpy.py [--rounds N] [--json PATH]   (about 70 s on a 2-core machine;
      ``--json`` also writes the figures, the machine and the date, read by ``rotorfault reproduce``)
Needs RotorPy: ``pip install "rotorfault[bench]"`` (said before any work when it is missing).

(a) rotorfault closed loop: ``rf.simulate_batch`` of 1,000 hover runs of the ``quad-x`` preset with
    ``rf.lqr_hover`` (python-control LQR, run in Rust as ``LinearFeedback``), 10 s each at 400 Hz
    control with 4 RK4 substeps per control period, from seeded random offsets about the hover
    point (position +-0.2 m, velocity +-0.2 m/s, roll/pitch/yaw +-0.05 rad, rates +-0.1 rad/s).
(b) rotorfault open loop: the same batch shape with ``rf.OpenLoop.constant(u_trim)`` (the hover
    thrusts held) from seeded random position offsets (at rest, level), so every run hovers in
    place at its own start point.
(c) RotorPy: its ``Multirotor`` with its Crazyflie parameters, its ``SE3Control`` and a
    ``HoverTraj`` at a fixed point, through its own ``rotorpy.simulate.simulate`` loop (the loop
    ``Environment.run`` calls, with the Environment's default world, no wind, IMU, motion capture
    and null estimator) at ``t_step = 1/400`` s, sequentially (RotorPy's batched path,
    ``BatchedMultirotor``, needs PyTorch and is not used), starting 2 cm / 1 cm / 1 cm off the
    hover point.

What a "step" is (the README says it at length):
- rotorfault control step: one control period of 1/400 s: divergence checks, recording, one
  controller evaluation, then 4 RK4 substeps (each: actuator update, 4 wrench + Newton-Euler
  evaluations). RK4 steps = 4 x control steps.
- RotorPy step: one pass of ``simulate``'s loop at ``t_step = 1/400`` s: one ``Multirotor.step``
  (``scipy.integrate.solve_ivp`` RK45, adaptive, from 0 to t_step on its 20-element state vector:
  position, velocity, quaternion, body rates, wind, 4 rotor speeds with first-order motor
  dynamics, aerodynamic drag on), one SE3 controller update, the trajectory, IMU and mocap samples.

Validation before anything is timed: no rotorfault run diverges and every run ends within 5 cm of
its target (closed loop: the LQR set-point; open loop: its own start); RotorPy's hover ends within
5 cm of its set-point with exit status TIMEOUT (ran to the end).

Timing: (a), (b) and (c) in interleaved rounds (a, b, c, a, b, c, ...); medians are reported.
rotorfault is timed end to end from Python (argument conversion, the Rust batch with the GIL
released, conversion of every trajectory to NumPy, stacking into the BatchResult); RotorPy is
timed around its simulate() call (its loop plus merging the recorded dicts). One extra profiled
call per rotorfault variant splits the time into the Rust call (simulation and conversion to NumPy) and the Python wrapper.
Threads: the batch uses every core rayon sees (``RAYON_NUM_THREADS`` is left as the environment
sets it and printed); RotorPy runs on one core. The ratio is printed both aggregate and per core.
"""

from __future__ import annotations

import cProfile
import importlib.metadata
import os
import platform
import pstats
import resource
import statistics
import time
from collections.abc import Callable

import numpy as np

import rotorfault as rf

PRESET = "quad-x"
DT = 1.0 / 400.0
SUBSTEPS = 4
T_FINAL = 10.0
RUNS = 1_000
TARGET = (0.0, 0.0, -10.0)  # NED: 10 m up
SEED = 20240611
TOLERANCE_M = 0.05
ROUNDS = 5

ROTORPY_T_FINAL = 3.0
ROTORPY_OFFSET = np.array([0.02, -0.01, 0.01])

TARGET_OPEN_RK4_PER_S = 5_000_000
TARGET_CLOSED_STEPS_PER_S = 1_000_000
TARGET_RATIO_VS_ROTORPY = 1_000.0


def verdict(ok: bool) -> str:
    return "PASS" if ok else "MISS"


def interleaved_times(
    fns: dict[str, Callable[[], object]], rounds: int
) -> tuple[dict[str, list[float]], dict[str, list[tuple[float, float]]]]:
    """Each function once per round, rounds interleaved (a, b, c, a, b, c, ...) so that background
    load and clock drift hit every variant alike; the validation calls before this are the warm-up.
    A function that returns a float reports its own timed section (RotorPy: its simulate() loop,
    without building the vehicle and environment); otherwise the whole call is timed. Also returns
    the process's (user, system) CPU seconds per call, all threads."""
    samples: dict[str, list[float]] = {key: [] for key in fns}
    cpu: dict[str, list[tuple[float, float]]] = {key: [] for key in fns}
    for _ in range(rounds):
        for key, fn in fns.items():
            before = resource.getrusage(resource.RUSAGE_SELF)
            t0 = time.perf_counter()
            result = fn()
            elapsed = time.perf_counter() - t0
            after = resource.getrusage(resource.RUSAGE_SELF)
            samples[key].append(result if isinstance(result, float) else elapsed)
            del result  # free this batch (GBs) before the next variant allocates its own
            cpu[key].append((after.ru_utime - before.ru_utime, after.ru_stime - before.ru_stime))
    return samples, cpu


def rust_call_share(fn: Callable[[], object]) -> tuple[float, float]:
    """(total, inside the extension's simulate_batch) seconds of one profiled call."""
    profile = cProfile.Profile()
    t0 = time.perf_counter()
    profile.runcall(fn)
    total = time.perf_counter() - t0
    stats = pstats.Stats(profile).stats  # type: ignore[attr-defined]
    inside = sum(
        tt for (filename, _, name), (_, _, tt, _, _) in stats.items() if filename == "~" and "simulate_batch" in name
    )
    return total, inside


# -- rotorfault -------------------------------------------------------------------------------------


def closed_loop_starts(rng: np.random.Generator) -> list[rf.State]:
    target = np.array(TARGET)
    return [
        rf.State(
            position=target + rng.uniform(-0.2, 0.2, 3),
            velocity=rng.uniform(-0.2, 0.2, 3),
            euler=rng.uniform(-0.05, 0.05, 3),
            omega=rng.uniform(-0.1, 0.1, 3),
        )
        for _ in range(RUNS)
    ]


def open_loop_starts(rng: np.random.Generator) -> list[rf.State]:
    target = np.array(TARGET)
    return [rf.State(position=target + rng.uniform(-0.2, 0.2, 3)) for _ in range(RUNS)]


def check_batch(name: str, result: rf.BatchResult, targets: np.ndarray) -> float:
    steps = round(T_FINAL / DT) + 1
    if result.position.shape != (RUNS, steps, 3):
        raise AssertionError(f"{name}: position shape {result.position.shape}, expected {(RUNS, steps, 3)}")
    if result.diverged.any():
        first = int(np.flatnonzero(result.diverged)[0])
        raise AssertionError(f"{name}: {result.diverged.sum()} runs diverged, first run {first}: "
                             f"{result.trajectories[first].events[0]}")
    miss = np.linalg.norm(result.position[:, -1, :] - targets, axis=1)
    worst = float(miss.max())
    if worst > TOLERANCE_M:
        raise AssertionError(f"{name}: run {int(miss.argmax())} ends {worst:.3f} m from its target (> {TOLERANCE_M} m)")
    return worst


# -- RotorPy ----------------------------------------------------------------------------------------


def rotorpy_setup() -> tuple[Callable[[], tuple[float, int, np.ndarray, object]], dict[str, float]]:
    """A function that flies RotorPy's hover once (returns wall time, steps, final position, exit
    status), and RotorPy's parameters for the printout."""
    from rotorpy.controllers.quadrotor_control import SE3Control  # type: ignore[import-untyped]
    from rotorpy.environments import Environment  # type: ignore[import-untyped]
    from rotorpy.simulate import simulate  # type: ignore[import-untyped]
    from rotorpy.trajectories.hover_traj import HoverTraj  # type: ignore[import-untyped]
    from rotorpy.vehicles.crazyflie_params import quad_params  # type: ignore[import-untyped]
    from rotorpy.vehicles.multirotor import Multirotor  # type: ignore[import-untyped]

    hover_speed = float(np.sqrt(quad_params["mass"] * 9.81 / (quad_params["num_rotors"] * quad_params["k_eta"])))
    setpoint = np.zeros(3)

    def fly() -> tuple[float, int, np.ndarray, object]:
        x0 = {
            "x": setpoint + ROTORPY_OFFSET,
            "v": np.zeros(3),
            "q": np.array([0.0, 0.0, 0.0, 1.0]),  # [i, j, k, w]
            "w": np.zeros(3),
            "wind": np.zeros(3),
            "rotor_speeds": np.full(quad_params["num_rotors"], hover_speed),
        }
        vehicle = Multirotor(quad_params, initial_state=x0)
        # The Environment only supplies its defaults (world, no wind, IMU, mocap, null estimator);
        # its own run() would add plotting objects after the loop, so its loop is called directly.
        env = Environment(
            vehicle=vehicle,
            controller=SE3Control(quad_params),
            trajectory=HoverTraj(x0=setpoint),
            sim_rate=round(1.0 / DT),
        )
        np.random.seed(SEED)  # RotorPy's sensors draw from NumPy's global generator
        t0 = time.perf_counter()
        out = simulate(
            env.world, x0, vehicle, env.controller, env.trajectory, env.wind_profile, env.imu,
            env.mocap, env.estimator, ROTORPY_T_FINAL, DT, env.safety_margin, False, terminate=False,
        )
        wall = time.perf_counter() - t0
        t, state, exit_status = out[0], out[1], out[8]
        return wall, len(t) - 1, np.asarray(state["x"][-1]), exit_status

    return fly, {"mass_kg": quad_params["mass"], "hover_rad_s": hover_speed}


def rotorpy_breakdown() -> tuple[float, float]:
    """Share of RotorPy's loop spent in Multirotor.step, and derivative evaluations per step
    (an instrumented run, not timed for the headline)."""
    from rotorpy.vehicles.multirotor import Multirotor  # type: ignore[import-untyped,unused-ignore]

    original_step, original_rhs = Multirotor.step, Multirotor._s_dot_fn
    spent = [0.0]
    calls = {"step": 0, "rhs": 0}

    def step(self, *args, **kwargs):  # type: ignore[no-untyped-def]
        calls["step"] += 1
        t0 = time.perf_counter()
        try:
            return original_step(self, *args, **kwargs)
        finally:
            spent[0] += time.perf_counter() - t0

    def rhs(self, *args, **kwargs):  # type: ignore[no-untyped-def]
        calls["rhs"] += 1
        return original_rhs(self, *args, **kwargs)

    Multirotor.step, Multirotor._s_dot_fn = step, rhs
    try:
        fly, _ = rotorpy_setup()
        wall, _, _, _ = fly()
    finally:
        Multirotor.step, Multirotor._s_dot_fn = original_step, original_rhs
    # statedot (for the IMU) also calls _s_dot_fn once per step.
    rhs_in_step = (calls["rhs"] - (calls["step"] + 1)) / calls["step"]
    return spent[0] / wall, rhs_in_step


def main() -> None:
    import argparse

    from _results import add_json_option, figure, write

    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--rounds", type=int, default=ROUNDS, help=f"interleaved timing rounds (default {ROUNDS})")
    add_json_option(parser)
    args = parser.parse_args()
    rounds = args.rounds
    if rounds < 1:
        parser.error("--rounds: must be >= 1")
    from rotorfault._util.optional import MissingDependency, require_available

    try:  # before any work: the one message of a missing optional package, naming the extra
        require_available("the RotorPy comparison", "rotorpy")
    except MissingDependency as exc:
        raise SystemExit(str(exc)) from None
    rotorpy_version = importlib.metadata.version("rotorpy")

    cores_os = os.cpu_count() or 1
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else cores_os
    env = {k: os.environ[k] for k in sorted(os.environ) if k.startswith(("OPENBLAS", "OMP_", "RAYON", "MKL_"))}
    threads = int(os.environ.get("RAYON_NUM_THREADS", "0") or 0) or cores
    print(f"machine: {platform.machine()} {platform.processor() or ''}".rstrip()
          + f", os.cpu_count() = {cores_os}, usable cores = {cores}, rayon threads = {threads}")
    print(f"python {platform.python_version()}, numpy {np.__version__}, rotorfault {rf.__version__}, "
          f"rotorpy {rotorpy_version}")
    print(f"thread/BLAS env (left as-is): {env or 'none set'}")
    load_before = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")

    airframe = rf.Airframe.preset(PRESET)
    sim = rf.Simulator(airframe, dt_s=DT, substeps=SUBSTEPS)
    lqr = rf.lqr_hover(sim, position=TARGET)
    hold = rf.OpenLoop.constant(lqr.u_trim)
    rng = np.random.default_rng(SEED)
    closed_x0 = closed_loop_starts(rng)
    open_x0 = open_loop_starts(rng)
    control_steps = round(T_FINAL / DT)  # per run: control periods advanced
    rk4_steps = control_steps * SUBSTEPS

    def closed() -> rf.BatchResult:
        return rf.simulate_batch(sim, closed_x0, T_FINAL, controllers=lqr)

    def opened() -> rf.BatchResult:
        return rf.simulate_batch(sim, open_x0, T_FINAL, controllers=hold)

    # -- validate (also the warm-up) --------------------------------------------------------------
    worst_closed = check_batch("(a) closed loop", closed(), np.tile(TARGET, (RUNS, 1)))
    worst_open = check_batch("(b) open loop", opened(), np.array([s.position for s in open_x0]))
    fly, rp_params = rotorpy_setup()
    _, rp_steps, rp_end, rp_exit = fly()
    rp_miss = float(np.linalg.norm(rp_end))
    if rp_exit is None or "TIMEOUT" not in str(rp_exit) or rp_miss > TOLERANCE_M:
        raise AssertionError(f"RotorPy hover: exit {rp_exit}, ends {rp_miss:.3f} m from the set-point")
    print()
    print(f"rotorfault: {PRESET}, {RUNS:,} runs x {T_FINAL:g} s at {1 / DT:g} Hz control, {SUBSTEPS} RK4 substeps "
          f"= {control_steps:,} control steps and {rk4_steps:,} RK4 steps per run")
    print(f"validation: (a) LQR hover from random offsets: all runs end within {worst_closed * 100:.2f} cm of "
          f"the target; (b) open-loop hover thrusts: within {worst_open * 100:.2e} cm of their start; "
          f"RotorPy: ends {rp_miss * 100:.3f} cm from its set-point ({rp_exit.name})")  # type: ignore[attr-defined]
    print()

    # -- timing: (a), (b), (c) interleaved ------------------------------------------------------------
    samples, cpu = interleaved_times(
        {"closed": closed, "open": opened, "rotorpy": lambda: fly()[0]}, rounds
    )
    t_closed = statistics.median(samples["closed"])
    t_open = statistics.median(samples["open"])
    closed_steps_s = RUNS * control_steps / t_closed
    closed_rk4_s = RUNS * rk4_steps / t_closed
    open_rk4_s = RUNS * rk4_steps / t_open
    print(f"timing: {rounds} interleaved rounds (rotorfault (a), (b), RotorPy), end to end from Python, median (min)")
    print(f"{'variant':38s} {'median':>9s} {'min':>9s} {'control steps/s':>16s} {'RK4 steps/s':>13s} {'per core':>11s}")
    print(f"{'(a) closed loop, LQR (LinearFeedback)':38s} {t_closed:8.3f}s {min(samples['closed']):8.3f}s "
          f"{closed_steps_s:16,.0f} {closed_rk4_s:13,.0f} {closed_rk4_s / threads:11,.0f}")
    print(f"{'(b) open loop, hover thrusts held':38s} {t_open:8.3f}s {min(samples['open']):8.3f}s "
          f"{RUNS * control_steps / t_open:16,.0f} {open_rk4_s:13,.0f} {open_rk4_s / threads:11,.0f}")
    for key, label in (("closed", "(a)"), ("open", "(b)")):
        user = statistics.median(u for u, _ in cpu[key])
        system = statistics.median(s for _, s in cpu[key])
        print(f"    {label} CPU per call (median, all threads): user {user:.2f} s, system {system:.2f} s "
              f"(system time is page faults: every call allocates and touches the recorded trajectories)")
    for key, fn in (("(a)", closed), ("(b)", opened)):
        total, inside = rust_call_share(fn)
        print(f"    {key} one profiled call: {total:.3f} s, of which {inside:.3f} s in the Rust call "
              f"(simulation + conversion to NumPy), {total - inside:.3f} s in the Python wrapper "
              f"(Trajectory objects, stacking); simulation-only lower bound on RK4 steps/s: "
              f"{RUNS * rk4_steps / inside:,.0f}")
    print()

    # -- RotorPy -----------------------------------------------------------------------------------
    rp_wall = statistics.median(samples["rotorpy"])
    rp_rate = rp_steps / rp_wall
    share, rhs_per_step = rotorpy_breakdown()
    print(f"RotorPy: Crazyflie params ({rp_params['mass_kg']} kg), SE3Control, HoverTraj, simulate() at "
          f"t_step = 1/{1 / DT:g} s, {ROTORPY_T_FINAL:g} s = {rp_steps:,} steps, sequential, "
          f"{rounds} runs: median {rp_wall:.3f} s (min {min(samples['rotorpy']):.3f} s) -> {rp_rate:,.0f} steps/s")
    print(f"    instrumented run: {share:.0%} of the loop in Multirotor.step (solve_ivp RK45), "
          f"{rhs_per_step:.1f} derivative evaluations per step")
    print()

    ratio = closed_steps_s / rp_rate
    print(f"target: open-loop RK4 steps/s (aggregate) >= {TARGET_OPEN_RK4_PER_S:,}: {open_rk4_s:,.0f} "
          f"-> {verdict(open_rk4_s >= TARGET_OPEN_RK4_PER_S)}")
    print(f"target: closed-loop control steps/s (LQR batch) >= {TARGET_CLOSED_STEPS_PER_S:,}: "
          f"{closed_steps_s:,.0f} -> {verdict(closed_steps_s >= TARGET_CLOSED_STEPS_PER_S)}")
    print(f"target: rotorfault closed loop / RotorPy >= {TARGET_RATIO_VS_ROTORPY:,.0f}x: {ratio:,.0f}x "
          f"-> {verdict(ratio >= TARGET_RATIO_VS_ROTORPY)} "
          f"(per core: {ratio / threads:,.0f}x; {threads} rayon threads vs RotorPy's 1)")
    load_after = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    peak_gb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024**2  # ru_maxrss is in KiB on Linux
    print()
    print(f"peak resident memory: {peak_gb:.1f} GiB")
    print(f"1-min load average: {load_before:.2f} before timing, {load_after:.2f} after "
          f"(this script alone keeps 1 to {cores} cores busy; a load well above {cores} means "
          f"other work shared the CPUs and the figures are pessimistic)")
    write(args.json_path, "simulation_rotorpy",
          f"simulator: {RUNS:,} hover runs of {T_FINAL:g} s ({PRESET}, {1 / DT:g} Hz, {SUBSTEPS} RK4 substeps), rf.simulate_batch", [
              figure("closed loop (LQR), batch, end to end from Python", closed_steps_s, "control steps/s",
                     baseline=f"RotorPy {rotorpy_version} SE3 hover, sequential, same run", baseline_value=rp_rate, ratio=ratio,
                     target=f">= {TARGET_CLOSED_STEPS_PER_S:,}/s and >= {TARGET_RATIO_VS_ROTORPY:,.0f}x"),
              figure("open loop, batch", open_rk4_s, "RK4 steps/s", target=f">= {TARGET_OPEN_RK4_PER_S:,}/s"),
          ], reduced=None if rounds == ROUNDS else f"{rounds} timing rounds instead of {ROUNDS} (--rounds)")


if __name__ == "__main__":
    main()

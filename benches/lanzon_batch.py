"""Lanzon et al.'s controller (RFL + discretised H-infinity loop-shaping controller + outer loop with
the yaw-synchronised rotation) at 1 kHz: closed-loop control steps per second, in Rust and as a
Python callback, and the time of ``ncfsyn`` on the 5-state shaped plant.

Run:  python benches/lanzon_batch.py      (about a minute on an idle 2-core machine)

The batch: 1,000 runs of 10 s of the Lanzon quadrotor (Table 1, printed I_zz) with rotor 2 dead,
our design (c) (30 rad/s crossover) flying Scenario B (Table 3's start, setpoint (0, 0, 1) m up),
the paper's actuator limits (thrust in [0, 5] N, 50 N/s), gyroscopic moment, drag, 1 kHz control
with 2 RK4 substeps (10 million control steps). Each run starts from Table 3's state with a random
offset (+-1 m in position, +-0.05 rad in roll and pitch). Recording is thinned to 10 Hz.

Baseline, in the same run: the same controller as a Python callback ``f(t, x)`` (the discrete
controller stepped in NumPy, the closed-form RFL of ``LanzonVehicle.rfl``, the outer loop
(28)-(31), eq. (9)), flying the first run on one thread for 2 s; its commands are first checked
against the Rust controller's on the same states (``_rfcore.replay``) to 1e-9.

``ncfsyn``: the median of 20 syntheses of the paper's design on the 5-state RFL plant shaped by
the 9-state loop-shape weight (python-control's ``minreal`` and scipy's Riccati solvers inside).

Targets (issue 10): >= 500,000 control steps/s in the batch on 2 cores; >= 100x the Python
callback; ncfsyn < 50 ms.
"""

from __future__ import annotations

import math
import os
import platform
import statistics
import time

import numpy as np

import rotorfault as rf
from rotorfault import _rfcore
from rotorfault.control import lanzon as L
from rotorfault.control.robust import loop_shape_weight, ncfsyn, target_loop_shape
from rotorfault.papers import lanzon as paper

RUNS = 1000
DURATION_S = 10.0
CALLBACK_S = 2.0
TARGET_STEPS_PER_S = 500_000
TARGET_RATIO = 100.0
TARGET_NCFSYN_S = 0.050


class PythonLanzon:
    """The Rust controller's law, written in Python: a callback for ``Simulator.run``."""

    def __init__(self, controller: L.LanzonController, dt_s: float) -> None:
        self.v = controller.design.vehicle
        self.a, self.b, self.c, self.d = controller.design.discretise(dt_s)
        self.xi = np.zeros(self.a.shape[0])
        self.gains = controller.outer_loop
        assert controller.position is not None
        n, e_, d = controller.position
        self.target = np.array([n, -e_, -d])

    def __call__(self, t: float, x: np.ndarray) -> np.ndarray:
        v, g = self.v, self.gains
        s = L.LanzonVehicle.paper_state(x)
        phi, theta, psi, p, q, r = s[:6]
        pos, vel = s[6:9], s[9:12]
        e = pos - self.target
        z1 = -g.k_p_xy * e[0] - g.k_d_xy * vel[0]
        z2 = -g.k_p_xy * e[1] - g.k_d_xy * vel[1]
        amax = g.max_vertical_accel_m_s2
        z3 = min(max(-g.k_p_z * e[2] - g.k_d_z * vel[2], -amax), amax)
        # (31): rotate the world-frame demands into the spinning frame
        sp, cp = math.sin(psi), math.cos(psi)
        u1 = sp * z1 - cp * z2
        u2 = cp * z1 + sp * z2
        u3 = v.gravity_m_s2 + v.linear_drag_n_s_m / v.mass_kg * vel[2] + z3
        u3 = min(max(u3, v.gravity_m_s2 - amax), v.gravity_m_s2 + amax)
        lim = g.max_tilt_rad
        phi_d = min(max(u1 / u3, -lim), lim)
        theta_d = min(max(u2 / u3, -lim), lim)
        r_d = v.mass_kg * u3 * v.drag_torque_ratio_m / v.rotational_drag_n_m_s
        err = np.array([phi_d - phi, theta_d - theta, r_d - r])
        w = self.c @ self.xi + self.d @ err
        self.xi = self.a @ self.xi + self.b @ err
        alpha, beta = v.rfl([phi, theta, p, q, r - v.spin_rate_rad_s])
        u = alpha + beta @ w + [v.mass_kg * v.gravity_m_s2, 0.0, v.mass_kg * v.gravity_m_s2 * v.drag_torque_ratio_m]
        return v.rotor_thrusts(u)


def main() -> None:
    print(f"rotorfault {rf.__version__}, {platform.processor() or platform.machine()}, {os.cpu_count()} CPUs, "
          f"load average {os.getloadavg()[0]:.1f}")
    vehicle = L.LanzonVehicle()
    case = paper.design_case("c")
    designed = case.design(vehicle)
    sc = paper.scenario("B")
    assert sc.position is not None
    controller = L.LanzonController(designed, position=sc.position, outer_loop=case.outer_loop)
    sim = vehicle.simulator(limits=True)
    faults = [rf.RotorFault(2, 0.0)]
    rng = np.random.default_rng(10)
    base = sc.initial_state().vector()
    starts = []
    for _ in range(RUNS):
        x = base.copy()
        x[0:3] += rng.uniform(-1, 1, 3)
        x[6:8] += rng.uniform(-0.05, 0.05, 2)
        starts.append(rf.State.from_vector(x))
    steps_per_run = round(DURATION_S / sim.dt_s)

    # The Python callback must be the same law: commands on recorded states.
    probe = sim.run(starts[0], 1.0, controller=controller, faults=faults)
    states = np.array([rf.State.from_vector(x)._packed() for x in np.column_stack(
        [probe.position, probe.velocity, probe.euler, probe.omega])[:200]])
    got = _rfcore.replay(controller.core(sim.dt_s), probe.t[:200], states, 4)
    py = PythonLanzon(controller, sim.dt_s)
    want = np.array([py(float(t), rf.State.from_vector(x).vector()) for t, x in zip(probe.t[:200], np.column_stack(
        [probe.position, probe.velocity, probe.euler, probe.omega])[:200])])
    agree = float(np.max(np.abs(got - want)))
    print(f"Python callback vs Rust commands on 200 recorded states: max |difference| {agree:.2e} N")

    t0 = time.perf_counter()
    batch = rf.simulate_batch(sim, starts, DURATION_S, controllers=controller, faults=[faults] * RUNS, record_every=100)
    batch_s = time.perf_counter() - t0
    rate = RUNS * steps_per_run / batch_s
    lost = int(batch.diverged.sum())

    t0 = time.perf_counter()
    single = sim.run(starts[0], DURATION_S, controller=controller, faults=faults, record_every=100)
    single_s = time.perf_counter() - t0
    assert not single.diverged

    t0 = time.perf_counter()
    # A callback has no trim: start its actuators where the Rust controller's start (u_trim).
    slow = sim.run(starts[0], CALLBACK_S, controller=PythonLanzon(controller, sim.dt_s), faults=faults, record_every=100,
                   initial_command=controller.u_trim)
    callback_s = time.perf_counter() - t0
    callback_rate = round(CALLBACK_S / sim.dt_s) / callback_s
    drift = float(np.max(np.abs(slow.position[-1] - sim.run(starts[0], CALLBACK_S, controller=controller, faults=faults,
                                                              record_every=100).position[-1])))

    plant = vehicle.plant()
    w1 = loop_shape_weight(plant, target_loop_shape(100.0))
    times = []
    for _ in range(20):
        t0 = time.perf_counter()
        result = ncfsyn(plant, w1)
        times.append(time.perf_counter() - t0)
    ncf_s = statistics.median(times)

    print(f"\nbatch: {RUNS} runs x {DURATION_S:g} s at {1 / sim.dt_s:.0f} Hz, {sim.substeps} RK4 substeps, "
          f"{RUNS * steps_per_run / 1e6:.0f} M control steps in {batch_s:.2f} s ({lost} runs lost)")
    print(f"  {rate:,.0f} closed-loop control steps/s  (target {TARGET_STEPS_PER_S:,}: "
          f"{'met' if rate >= TARGET_STEPS_PER_S else 'NOT met'})")
    print(f"  one run, one thread: {steps_per_run / single_s:,.0f} steps/s")
    print(f"  Python callback (same law), one thread: {callback_rate:,.0f} steps/s; final positions differ by "
          f"{drift:.1e} m after {CALLBACK_S:g} s")
    print(f"  batch / callback: {rate / callback_rate:,.0f}x; one thread / callback: "
          f"{steps_per_run / single_s / callback_rate:,.0f}x  (target {TARGET_RATIO:g}x: "
          f"{'met' if rate / callback_rate >= TARGET_RATIO else 'NOT met'})")
    print(f"ncfsyn, paper's design ({result.shaped_plant.nstates}-state shaped plant): median {1e3 * ncf_s:.1f} ms of 20 "
          f"(min {1e3 * min(times):.1f} ms; target {1e3 * TARGET_NCFSYN_S:g} ms: "
          f"{'met' if ncf_s < TARGET_NCFSYN_S else 'NOT met'}); gamma_min {result.gamma_min:.3f}")


if __name__ == "__main__":
    main()

"""The flight simulator from Python: hover, free fall, rotor failure under LQR, every actuator
effect in isolation, controllers (built-in, Lti, Python callable), batches, bad input.
Closed forms are checked to 1e-9 unless stated."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import rotorfault as rf
from rotorfault._typing import BatchLanes

G = 9.80  # the Du presets' gravity


@pytest.fixture(scope="module")
def quad() -> rf.Airframe:
    return rf.Airframe.preset("quad-x")


@pytest.fixture(scope="module")
def sim(quad: rf.Airframe) -> rf.Simulator:
    return rf.Simulator(quad, dt_s=1 / 400, substeps=2)


@pytest.fixture(scope="module")
def lqr(sim: rf.Simulator) -> rf.LinearFeedback:
    return rf.lqr_hover(sim, position=(0, 0, -10))


def test_trimmed_hover_stays_put(sim: rf.Simulator, lqr: rf.LinearFeedback) -> None:
    start = rf.State(position=(0, 0, -10))
    for controller in (lqr, rf.OpenLoop.constant(lqr.u_trim)):
        tr = sim.run(start, 10.0, controller=controller)
        assert not tr.diverged
        assert np.abs(tr.position - [0, 0, -10]).max() < 1e-9
        # Open loop, the trim's rounding torque (~1e-16 N m) is integrated twice: ~1e-12 rad.
        assert np.abs(tr.euler).max() < 1e-10
    np.testing.assert_allclose(lqr.u_trim, np.full(4, 1.535 * G / 4), rtol=1e-12)


def test_lqr_recovers_from_a_perturbation(sim: rf.Simulator, lqr: rf.LinearFeedback) -> None:
    tr = sim.run(rf.State(position=(0.5, -0.3, -9.0), euler=(0.1, -0.1, 0.3), omega=(0.2, 0, 0)), 10.0, controller=lqr)
    assert not tr.diverged
    assert np.linalg.norm(tr.position[-1] - [0, 0, -10]) < 0.01
    assert np.abs(tr.euler[-1]).max() < 1e-3


def test_rotation_and_primary_axis_agree(sim: rf.Simulator, lqr: rf.LinearFeedback) -> None:
    tr = sim.run(rf.State(position=(0, 0, -10), euler=(0.3, -0.2, 1.0), omega=(1, 2, 3)), 0.5, controller=lqr)
    r = tr.rotation
    np.testing.assert_allclose(r[:, :, 2], tr.primary_axis, atol=1e-12)
    np.testing.assert_allclose(np.einsum("nij,nkj->nik", r, r), np.broadcast_to(np.eye(3), r.shape), atol=1e-12)
    # Z-Y-X Euler angles rebuild the same matrix.
    roll, pitch, yaw = tr.euler[0]
    cr, sr, cp, sp, cy, sy = np.cos(roll), np.sin(roll), np.cos(pitch), np.sin(pitch), np.cos(yaw), np.sin(yaw)
    expected = np.array([[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
                         [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
                         [-sp, cp * sr, cp * cr]])
    np.testing.assert_allclose(r[0], expected, atol=1e-12)


def test_free_fall_matches_the_closed_form(sim: rf.Simulator) -> None:
    tr = sim.run(rf.State(position=(0, 0, -100), velocity=(1.0, 0, -3.0)), 2.0)
    t = tr.t
    np.testing.assert_allclose(tr.position[:, 2], -100 - 3.0 * t + 0.5 * G * t**2, rtol=0, atol=1e-9)
    np.testing.assert_allclose(tr.position[:, 0], t, rtol=0, atol=1e-12)
    assert np.all(tr.rotor_thrust == 0.0)


def test_rotor_failure_under_lqr_is_reported_not_raised(sim: rf.Simulator, lqr: rf.LinearFeedback) -> None:
    """The problem rotorfault exists for: a hovering quad-x loses rotor 1 at 1 s, the hover LQR
    cannot hold it, and the run ends with an event saying when and why: it falls the 10 m to the
    ground and crashes (issue #28: without a ground it fell 13.7 m and ended later, by tilt)."""
    tr = sim.run(rf.State(position=(0, 0, -10)), 10.0, controller=lqr, faults=[rf.RotorFault(rotor=1, time=1.0)])
    assert tr.diverged
    event = tr.events[0]
    assert event.kind == "crashed" and 1.0 < event.time_s < 10.0
    assert str(event).startswith("crashed at t = ") and event.state.shape == (12,)
    assert tr.t[-1] == pytest.approx(event.time_s)
    # At the ground (z = 0), with the impact read off the state there.
    assert 0.0 < tr.position[-1, 2] < 1e-9 and event.state[2] == tr.position[-1, 2]
    assert event.impact_speed_m_s == pytest.approx(float(np.linalg.norm(event.state[3:6])), rel=1e-12)
    assert event.impact_vertical_speed_m_s == pytest.approx(event.state[5], rel=1e-12) and event.state[5] > 0
    assert event.impact_tilt_rad == pytest.approx(math.acos(tr.primary_axis[-1, 2]), abs=1e-9)
    # Without the ground the same flight goes on through the plane until it tilts past 90 degrees.
    free = rf.Simulator(sim.airframe, dt_s=sim.dt_s, substeps=sim.substeps, ground=False)
    lost = free.run(rf.State(position=(0, 0, -10)), 10.0, controller=lqr, faults=[rf.RotorFault(rotor=1, time=1.0)])
    assert lost.events[0].kind == "tilt" and lost.events[0].time_s > event.time_s and lost.position[-1, 2] > 0
    assert lost.events[0].impact_speed_m_s is None and "tilt" in str(lost.events[0])
    before, after = np.searchsorted(tr.t, [0.5, 1.5])
    np.testing.assert_array_equal(tr.efficiency[before], [1, 1, 1, 1])
    np.testing.assert_array_equal(tr.efficiency[after], [0, 1, 1, 1])
    assert tr.rotor_thrust[after, 0] == 0.0
    assert np.all(np.isnan(tr.rotor_command[-1]))  # no command after the divergence
    assert np.all(np.isnan(tr.measured[-1])) and tr.measured.shape == (len(tr.t), 12)
    np.testing.assert_allclose(tr.measured[0], rf.State(position=(0, 0, -10)).vector(), atol=1e-15)


def test_partial_fault_scales_thrust_only(sim: rf.Simulator, lqr: rf.LinearFeedback) -> None:
    tr = sim.run(rf.State(position=(0, 0, -10)), 0.5, controller=rf.OpenLoop.constant(lqr.u_trim),
                 faults=[rf.RotorFault(rotor=3, time=0.25, efficiency=0.5)])
    i = np.searchsorted(tr.t, 0.3)
    assert tr.rotor_thrust[i, 2] == pytest.approx(0.5 * lqr.u_trim[2], rel=1e-15)
    assert tr.rotor_command[i, 2] == lqr.u_trim[2]  # the controller's command is unchanged


def test_saturation_lag_and_rate_limit_in_isolation(quad: rf.Airframe) -> None:
    start = rf.State(position=(0, 0, -1000))
    # Saturation: asking 100 N gives max_thrust_n.
    sim = rf.Simulator(quad, limits=rf.DivergenceLimits(max_speed_m_s=math.inf, max_altitude_loss_m=math.inf))
    tr = sim.run(start, 0.1, controller=rf.OpenLoop.constant([100.0] * 4), initial_command=[0.0] * 4)
    assert np.all(tr.rotor_thrust[1:] == 6.125)
    # First-order lag: one time constant after a step, 1 - 1/e of the step (exact discretisation).
    lagged = rf.Simulator(quad, actuator=rf.FixedPitchActuator(time_constant_s=0.025))
    tr = lagged.run(start, 0.1, controller=rf.OpenLoop.constant([4.0] * 4), initial_command=[0.0] * 4)
    i = np.searchsorted(tr.t, 0.025)
    assert tr.rotor_thrust[i, 0] == pytest.approx(4.0 * (1 - math.exp(-1)), abs=1e-12)
    # Rate limit: 50 N/s ramps 0 -> 4 N in 80 ms.
    limited = rf.Simulator(quad, actuator=rf.FixedPitchActuator(rate_limit_n_s=50.0))
    tr = limited.run(start, 0.2, controller=rf.OpenLoop.constant([4.0] * 4), initial_command=[0.0] * 4)
    i = np.searchsorted(tr.t, 0.04)
    assert tr.rotor_thrust[i, 0] == pytest.approx(2.0, abs=1e-12)
    assert tr.rotor_thrust[-1, 0] == 4.0


def test_sensor_noise_has_the_requested_snr_and_is_reproducible(quad: rf.Airframe) -> None:
    start = rf.State(position=(10.0, 20.0, -1000.0), velocity=(1.0, 2.0, -3.0))
    sim = rf.Simulator(quad, noise=rf.Noise(snr_db=15.0, seed=3), limits=rf.DivergenceLimits(max_altitude_loss_m=math.inf))
    tr = sim.run(start, 2.0)
    truth = np.array([rf.State(position=p, velocity=v).vector()[:6] for p, v in zip(tr.position, tr.velocity)])
    ratio = (tr.measured[:, :6] - truth) / np.abs(truth)
    # 10^(-15/20) = 0.1778; 801 x 6 samples give a standard error of about 1 % on the std.
    assert ratio.std() == pytest.approx(10 ** (-15 / 20), rel=0.05)
    assert abs(ratio.mean()) < 0.02
    # Noise reaches the controller only: with no controller the flight is the noiseless one.
    np.testing.assert_array_equal(tr.position, rf.Simulator(quad, limits=sim.limits).run(start, 2.0).position)
    np.testing.assert_array_equal(sim.run(start, 2.0).measured, tr.measured)
    other = rf.Simulator(quad, noise=rf.Noise(snr_db=15.0, seed=4), limits=sim.limits).run(start, 2.0)
    assert not np.array_equal(other.measured, tr.measured)
    floor = rf.Simulator(quad, noise=rf.Noise(std=(0.1, 0.2, 0.01, 0.05), seed=1), limits=sim.limits).run(start, 2.0)
    error = floor.measured - np.array([rf.State(position=p, velocity=v, quaternion=q, omega=w).vector()
                                       for p, v, q, w in zip(floor.position, floor.velocity, floor.quaternion, floor.omega)])
    np.testing.assert_allclose(error.std(axis=0), np.repeat([0.1, 0.2, 0.01, 0.05], 3), rtol=0.12)


def test_noisy_lqr_hover_stays_close(sim: rf.Simulator, lqr: rf.LinearFeedback) -> None:
    noisy = rf.Simulator(sim.airframe, dt_s=sim.dt_s, substeps=sim.substeps, noise=rf.Noise(std=(0.02, 0.02, 0.002, 0.01), seed=0))
    tr = noisy.run(rf.State(position=(0, 0, -10)), 10.0, controller=lqr)
    assert not tr.diverged
    assert np.abs(tr.position - [0, 0, -10]).max() < 0.2


def test_wind_with_linear_drag_sets_the_terminal_velocity(quad: rf.Airframe) -> None:
    wind = (3.0, -2.0, 0.0)
    sim = rf.Simulator(quad, drag=rf.Drag(linear_n_s_m=1.0), wind=wind)
    hover = np.full(4, 1.535 * G / 4)
    tr = sim.run(rf.State(position=(0, 0, -10)), 20.0, controller=rf.OpenLoop.constant(hover))
    # m dv/dt = -k_t (v - wind): v -> wind with time constant m / k_t = 1.535 s.
    expected = np.array(wind) * (1 - math.exp(-20.0 / 1.535))
    np.testing.assert_allclose(tr.velocity[-1], expected, atol=1e-9)


def test_lti_and_callable_controllers_fly_like_linear_feedback(sim: rf.Simulator, lqr: rf.LinearFeedback) -> None:
    start = rf.State(position=(0.3, 0, -9.5), euler=(0.05, 0, 0))
    reference = sim.run(start, 2.0, controller=lqr)
    k = lqr.gain
    static = rf.Lti(np.zeros((0, 0)), np.zeros((0, 12)), np.zeros((4, 0)), -k, lqr.x_trim, lqr.u_trim)
    np.testing.assert_allclose(sim.run(start, 2.0, controller=static).position, reference.position, atol=1e-12)

    def law(t: float, x: np.ndarray) -> np.ndarray:
        e = x - lqr.x_trim
        e[8] = (e[8] + np.pi) % (2 * np.pi) - np.pi
        return lqr.u_trim - k @ e

    np.testing.assert_allclose(sim.run(start, 2.0, controller=law).position, reference.position, atol=1e-9)


def test_continuous_lti_with_integral_action_removes_a_bias(quad: rf.Airframe) -> None:
    """An altitude integrator (continuous, discretised at the control rate) on top of LQR
    removes the steady error that a 10 % weaker hover trim leaves."""
    sim = rf.Simulator(quad, dt_s=1 / 400, substeps=2)
    lqr = rf.lqr_hover(sim, position=(0, 0, -10))
    weak = lqr.u_trim * 0.9
    biased = sim.run(rf.State(position=(0, 0, -10)), 20.0, controller=rf.LinearFeedback(lqr.gain, lqr.x_trim, weak))
    assert abs(biased.position[-1, 2] + 10) > 1.0  # LQR alone: a 2 m steady sag
    b = np.zeros((1, 12))
    b[0, 2] = 1.0  # integrate the down-position error
    # More thrust while below the target (positive down error); a gentle gain, since the hover
    # LQR leaves little altitude damping to spare.
    c = 0.03 * np.ones((4, 1))
    pi = rf.Lti(np.zeros((1, 1)), b, c, -lqr.gain, lqr.x_trim, weak)
    fixed = sim.run(rf.State(position=(0, 0, -10)), 60.0, controller=pi)
    assert np.abs(fixed.position[-4000:, 2] + 10).max() < 1e-5  # the last 10 s


def test_python_controller_errors_propagate(sim: rf.Simulator) -> None:
    def broken(t: float, x: np.ndarray) -> list[float]:
        if t > 0.1:
            raise ZeroDivisionError("controller bug")
        return [3.0] * 4

    with pytest.raises(ZeroDivisionError, match="controller bug"):
        sim.run(rf.State(position=(0, 0, -10)), 1.0, controller=broken)
    with pytest.raises(ValueError, match="must return 4 commands, got 2 at t = 0"):
        sim.run(rf.State(position=(0, 0, -10)), 1.0, controller=lambda t, x: [1.0, 2.0])


def test_a_python_controller_returning_nan_ends_the_run_with_an_event(sim: rf.Simulator) -> None:
    """Divergence is never an exception: a callable that returns NaN (here from t = 0.1 s on)
    ends the run at that control step with the controller named in the event, exactly as a
    built-in controller does; the row shows the NaN command it returned."""

    def blows_up(t: float, x: np.ndarray) -> list[float]:
        return [float("nan") if t > 0.0999 else 3.0] + [3.0] * 3

    tr = sim.run(rf.State(position=(0, 0, -10)), 1.0, controller=blows_up)
    assert tr.diverged
    event = tr.events[0]
    assert event.kind == "non-finite-command" and "controller" in event.description
    assert event.time_s == pytest.approx(0.1, abs=1e-12) and tr.t[-1] == event.time_s
    assert np.isnan(tr.rotor_command[-1, 0]) and np.all(tr.rotor_command[-1, 1:] == 3.0)
    assert np.all(np.isfinite(tr.rotor_command[:-1]))
    # An infinite command is a divergence too; a wrong count stays the controller's error.
    tr = sim.run(rf.State(position=(0, 0, -10)), 1.0, controller=lambda t, x: [math.inf] * 4)
    assert tr.events[0].kind == "non-finite-command" and tr.events[0].time_s == 0.0


def test_batch_time_axis_is_the_recorded_times(quad: rf.Airframe) -> None:
    """``BatchResult.t`` holds the recorded times, the thinned grid and the exact end, equal to
    every completed run's ``t`` (issue 18: it was ``arange(rows) * dt_s``, 0.10 s for a 1 s run
    with record_every=10). A run diverging between two grid times keeps its exact last row in its
    Trajectory and is NaN from the next grid row on, never stacked into a row of another time."""
    sim = rf.Simulator(quad, dt_s=0.01)
    b = rf.simulate_batch(sim, [rf.State(position=(0, 0, -10))], 1.0, record_every=10)
    assert b.t[-1] == 1.0 == b.trajectories[0].t[-1]
    np.testing.assert_array_equal(b.t, b.trajectories[0].t)
    assert b.position.shape == (1, 11, 3)
    # 100 m up: the 3 s free fall (44 m) stays clear of the ground.
    b = rf.simulate_batch(sim, [rf.State(position=(0, 0, -100))], 3.0, record_every=7)
    assert len(b.t) == 44 and b.t[-1] == 3.0 and b.t[-2] == pytest.approx(2.94, abs=1e-12)
    np.testing.assert_array_equal(b.t, b.trajectories[0].t)
    # A shortened last step (1.05 s at dt = 0.1): the grid ends exactly at 1.05.
    b = rf.simulate_batch(rf.Simulator(quad, dt_s=0.1), [rf.State(position=(0, 0, -10))], 1.05, record_every=3)
    np.testing.assert_allclose(b.t, [0.0, 0.3, 0.6, 0.9, 1.05], rtol=0, atol=1e-15)
    assert b.t[-1] == 1.05
    # Free fall (no thrust): the 2 m altitude-loss limit is crossed at sqrt(2 * 2 / g) =
    # 0.6389 s, between the grid rows 0.6 and 0.7 of record_every = 10; the runs thrown up at
    # 3 m/s lose at most 3 - 4.9 = 1.9 m in 1 s and do not diverge.
    limited = rf.Simulator(quad, dt_s=0.01, limits=rf.DivergenceLimits(max_altitude_loss_m=2.0))
    up = rf.State(position=(0, 0, -10), velocity=(0, 0, -3))
    b = rf.simulate_batch(limited, [up, rf.State(position=(0, 0, -10)), up], 1.0, record_every=10)
    falls = b.trajectories[1]
    assert falls.events[0].kind == "altitude-loss" and not b.diverged[0] and not b.diverged[2]
    assert b.divergence_time[1] == falls.t[-1] == pytest.approx(math.sqrt(2 * 2.0 / G), abs=1e-9)
    np.testing.assert_array_equal(b.t, b.trajectories[0].t)
    row = int(np.searchsorted(b.t, 0.65))  # the first grid row after the last recorded step
    np.testing.assert_array_equal(b.t[:row], falls.t[:-1])
    np.testing.assert_array_equal(b.position[1, :row], falls.position[:-1])
    assert np.all(np.isnan(b.position[1, row:]))
    # Every stacked row is the state at the row's time: z = 10 + g t^2 / 2 (to RK4's round-off).
    np.testing.assert_allclose(b.position[1, :row, 2], -10 + 0.5 * G * b.t[:row] ** 2, rtol=0, atol=1e-12)


def test_batch_runs_start_at_their_own_trim_with_lagging_actuators(quad: rf.Airframe, lqr: rf.LinearFeedback) -> None:
    sim = rf.Simulator(quad, dt_s=1 / 400, substeps=2, actuator=rf.FixedPitchActuator(time_constant_s=0.025, rate_limit_n_s=50.0))
    controllers = [None, lqr, rf.OpenLoop.constant(lqr.u_trim * 0.5)]
    starts = [rf.State(position=(0, 0, -10))] * 3
    batch = rf.simulate_batch(sim, starts, 2.0, controllers=controllers)
    for i, c in enumerate(controllers):
        np.testing.assert_array_equal(batch.trajectories[i].position, sim.run(starts[i], 2.0, controller=c).position)
    np.testing.assert_allclose(batch.rotor_thrust[1, 0], lqr.u_trim)  # trimmed start, not zero


def test_open_loop_hover_with_lag_stays_put(quad: rf.Airframe, lqr: rf.LinearFeedback) -> None:
    sim = rf.Simulator(quad, actuator=rf.FixedPitchActuator(time_constant_s=0.025, rate_limit_n_s=50.0))
    tr = sim.run(rf.State(position=(0, 0, -10)), 5.0, controller=rf.OpenLoop.constant(lqr.u_trim))
    assert np.abs(tr.position - [0, 0, -10]).max() < 1e-9


def test_changing_the_actuator_takes_effect(quad: rf.Airframe) -> None:
    sim = rf.Simulator(quad)
    hover = rf.OpenLoop([0.0, 0.01], [[0.0] * 4, [4.0] * 4])
    fast = sim.run(rf.State(position=(0, 0, -10)), 0.05, controller=hover)
    sim.actuator = rf.FixedPitchActuator(time_constant_s=0.05)
    slow = sim.run(rf.State(position=(0, 0, -10)), 0.05, controller=hover)
    assert fast.rotor_thrust[-1, 0] == 4.0 and slow.rotor_thrust[-1, 0] < 3.0


def test_continuous_lti_is_discretised_by_zero_order_hold(sim: rf.Simulator, lqr: rf.LinearFeedback) -> None:
    """An integrator of a constant error: ZOH gives xi_k = k dt e exactly (Euler would too, but
    a Tustin or matched discretisation of the same A, B would not start at xi_1 = dt e with
    C = 1)."""
    x_trim = lqr.x_trim.copy()
    x_trim[0] = -1.0  # the vehicle sits 1 m north of the target: e_north = 1, constant
    b = np.zeros((1, 12))
    b[0, 0] = 1.0
    lti = rf.Lti(np.zeros((1, 1)), b, np.ones((4, 1)), np.zeros((4, 12)), x_trim, lqr.u_trim)
    tr = sim.run(rf.State(position=(0, 0, -10)), 0.1, controller=lti)
    k = np.arange(len(tr.t))
    np.testing.assert_allclose(tr.rotor_command[:, 0], lqr.u_trim[0] + k * sim.dt_s, rtol=0, atol=1e-12)


def test_non_finite_commands_and_inputs(sim: rf.Simulator) -> None:
    with pytest.raises(ValueError, match=r"initial_command\[0\]: must be finite"):
        sim.run(rf.State(), 1.0, initial_command=[float("nan")] * 4)
    with pytest.raises(TypeError, match="controller: must return a sequence of 4 numbers"):
        sim.run(rf.State(position=(0, 0, -10)), 1.0, controller=lambda t, x: None)
    with pytest.raises(ValueError, match=r"x\[3\]: must be finite"):
        sim.state_derivative([0, 0, 0, float("nan")] + [0] * 8, [3.0] * 4)
    with pytest.raises(ValueError, match="duration_s, dt_s: .* control steps exceed"):
        sim.run(rf.State(), 1e6)
    with pytest.raises(ValueError, match="substeps: .* RK4 steps per run"):
        rf.Simulator(sim.airframe, substeps=10**9).run(rf.State(), 1.0)


def test_a_controller_producing_nan_ends_the_run_with_an_event(sim: rf.Simulator) -> None:
    a = np.array([[1e300]])  # the discrete state overflows to inf within two steps
    b = np.ones((1, 12))
    lti = rf.Lti(a, b, np.ones((4, 1)), np.zeros((4, 12)), np.full(12, -1.0), [3.0] * 4, dt_s=sim.dt_s)
    tr = sim.run(rf.State(position=(0, 0, -10)), 1.0, controller=lti)
    assert tr.diverged and tr.events[0].kind == "non-finite-command"


@pytest.mark.parametrize("lanes", ["auto", "portable"])
@pytest.mark.parametrize("sensing", [None, rf.Sensing(seed=5)], ids=["truth", "mocap"])
def test_batch_lanes_equal_the_scalar_path_bit_for_bit(quad: rf.Airframe, lqr: rf.LinearFeedback,
                                                       sensing: rf.Sensing | None, lanes: BatchLanes) -> None:
    """``lanes="auto"`` (four runs per AVX2 register, issue 32) and ``lanes="portable"`` (the same
    groups in the build a CPU without AVX2 runs; the Rust tests check that it reaches every place
    that chooses) record exactly what ``lanes="scalar"`` records, in every column: lagged rotors, a fault between substeps in one
    group (a dead rotor: that lane leaves its register when it diverges), a group without
    faults and a run left over; on the truth and on sensors with the estimator (the truth in
    the lanes, each run's sensors and estimator per run: every estimate column and count too);
    a bad setting is refused naming the field."""
    sim = rf.Simulator(quad, dt_s=1 / 400, substeps=2, actuator=rf.FixedPitchActuator(time_constant_s=0.02),
                       sensing=sensing)
    starts = [rf.State(position=(0.1 * i, -0.05 * i, -10), velocity=(0.2, 0, 0.1 * i), euler=(0.03 * i, -0.02, 0.1))
              for i in range(9)]
    faults = [[rf.RotorFault(rotor=1 + i % 4, time=0.30013, efficiency=0.0 if i == 1 else 0.5)] if i < 4 else []
              for i in range(9)]
    laned, scalar = (rf.simulate_batch(sim, starts, 1.5, controllers=lqr, faults=faults, record_every=2, lanes=way)
                     for way in (lanes, "scalar"))
    for name in ("position", "velocity", "quaternion", "euler", "omega", "primary_axis", "rotor_command", "rotor_thrust",
                 "efficiency", "rows_on_grid", "off_grid_row"):
        np.testing.assert_array_equal(getattr(laned.columns, name), getattr(scalar.columns, name), err_msg=name)
    if sensing is not None:
        for name in ("estimate_state", "estimate_euler", "estimate_std", "gyro_saturated", "accel_saturated"):
            np.testing.assert_array_equal(getattr(laned.columns, name), getattr(scalar.columns, name), err_msg=name)
        counts = [[c.__getnewargs_ex__() for c in b.columns.sensing_counts if c] for b in (laned, scalar)]
        assert counts[0] == counts[1] and len(counts[0]) == 9
        assert all(c.imu_samples > 0 for c in laned.columns.sensing_counts if c)
    np.testing.assert_array_equal(laned.divergence_time, scalar.divergence_time)
    assert laned.diverged.tolist() == scalar.diverged.tolist()
    assert laned.efficiency[1, -1, 1] == 0.0 or laned.diverged[1]  # the faults acted
    assert laned.efficiency[0, -1, 0] == 0.5
    with pytest.raises(ValueError, match="^lanes"):
        rf.simulate_batch(sim, starts[:1], 0.1, lanes="simd")  # type: ignore[arg-type]
    with pytest.raises(TypeError, match="^lanes"):
        rf.simulate_batch(sim, starts[:1], 0.1, lanes=4)  # type: ignore[arg-type]


def test_batch_matches_single_runs(sim: rf.Simulator, lqr: rf.LinearFeedback) -> None:
    starts = [rf.State(position=(0.1 * i, 0, -10), euler=(0.02 * i, 0, 0)) for i in range(6)]
    faults = [[], [rf.RotorFault(rotor=2, time=0.5)], [], [rf.RotorFault(rotor=1, time=0.2, efficiency=0.7)], [], []]
    batch = rf.simulate_batch(sim, starts, 8.0, controllers=lqr, faults=faults)
    assert batch.position.shape == (6, 3201, 3)
    for i, (s, f) in enumerate(zip(starts, faults)):
        single = sim.run(s, 8.0, controller=lqr, faults=f)
        np.testing.assert_array_equal(batch.trajectories[i].position, single.position)
        np.testing.assert_array_equal(batch.trajectories[i].t, single.t)
        # Stacked by time: a diverged run's last row, at its located time, is off the grid.
        n = len(single.t) - int(single.diverged)
        np.testing.assert_array_equal(batch.t[:n], single.t[:n])
        np.testing.assert_array_equal(batch.position[i, :n], single.position[:n])
        assert np.isnan(batch.position[i, n:]).all()
        assert batch.diverged[i] == single.diverged
    assert batch.diverged[1] and np.isnan(batch.position[1, -1]).all()
    assert not batch.diverged[0] and np.isnan(batch.divergence_time[0])
    with pytest.raises(TypeError, match="Python callables cannot run in a batch"):
        rf.simulate_batch(sim, starts[:1], 1.0, controllers=lambda t, x: [0.0] * 4)


def test_variable_pitch_hover_and_reverse_thrust(quad: rf.Airframe) -> None:
    k = (5e-7, 1e-10, 3e-11, 1e-7)
    actuator = rf.VariablePitchActuator(k=k, speed_bounds=(0, 10_000), pitch_bounds=(-0.3, 0.3))
    sim = rf.Simulator(quad, actuator=actuator)
    assert sim.command_count == 8
    alpha = 0.2
    omega = math.sqrt(1.535 * G / 4 / (k[0] * alpha))
    hover = np.array([omega, alpha] * 4)
    tr = sim.run(rf.State(position=(0, 0, -10)), 5.0, controller=rf.OpenLoop.constant(hover), initial_command=hover)
    assert np.abs(tr.position - [0, 0, -10]).max() < 1e-9
    np.testing.assert_allclose(tr.rotor_thrust[-1], 1.535 * G / 4, rtol=1e-12)
    down = sim.run(rf.State(position=(0, 0, -10)), 0.5, controller=rf.OpenLoop.constant([omega, -alpha] * 4), initial_command=hover)
    assert np.all(down.rotor_thrust[-1] < 0) and down.velocity[-1, 2] > 0.5 * G * 0.5


def test_linearisation_has_the_hover_structure(sim: rf.Simulator, lqr: rf.LinearFeedback) -> None:
    model = rf.linearize(sim, (lqr.x_trim, lqr.u_trim))
    a, b = model.A, model.B
    # NED/FRD at hover: pitching up tilts thrust backwards, rolling right tilts it east.
    assert a[3, 7] == pytest.approx(-G, rel=1e-6)
    assert a[4, 6] == pytest.approx(G, rel=1e-6)
    assert a[0, 3] == pytest.approx(1.0) and a[6, 9] == pytest.approx(1.0) and a[8, 11] == pytest.approx(1.0)
    # Thrust input: each newton accelerates the vehicle upwards by 1/m.
    np.testing.assert_allclose(b[5], -1 / 1.535, rtol=1e-6)
    bf = sim.airframe.effectiveness_matrix()
    np.testing.assert_allclose(b[9], bf[1] / 0.0411, rtol=1e-6, atol=1e-9)


def test_plot_writes_png(sim: rf.Simulator, lqr: rf.LinearFeedback, tmp_path: Path) -> None:
    import matplotlib.pyplot as plt

    tr = sim.run(rf.State(position=(0, 0, -10)), 3.0, controller=lqr, faults=[rf.RotorFault(rotor=1, time=1.0)])
    fig = tr.plot(str(tmp_path / "run.png"))
    assert (tmp_path / "run.png").stat().st_size > 20_000
    plt.close(fig)


@pytest.mark.parametrize(
    ("make", "error", "message"),
    [
        (lambda q: rf.Simulator(q, dt_s=0.0), ValueError, "dt_s: must be > 0"),
        (lambda q: rf.Simulator(q, dt_s=float("nan")), ValueError, "dt_s: must be > 0"),
        (lambda q: rf.Simulator(q, substeps=0), ValueError, "substeps: must be >= 1"),
        (lambda q: rf.Simulator(q, drag=rf.Drag(linear_n_s_m=float("nan"))), ValueError, "drag.linear_n_s_m: must be finite"),
        (lambda q: rf.Simulator(q, drag=rf.Drag(rotational_n_m_s=-1.0)), ValueError, "drag.rotational_n_m_s: must be >= 0"),
        (lambda q: rf.Simulator(q, wind=(0, float("inf"), 0)), ValueError, "wind: must be finite"),
        (lambda q: rf.Simulator(q, noise=rf.Noise(std=(1.0, -1.0, 0.0, 0.0))), ValueError, r"noise.std\[3\]: must be finite and >= 0"),
        (lambda q: rf.Simulator(q, noise=rf.Noise(std=(1.0, 2.0))), ValueError, "noise.std: expected 4 or 12 entries"),
        (lambda q: rf.Simulator(q, noise=rf.Noise(snr_db=float("nan"))), ValueError, "noise.snr_db"),
        (lambda q: rf.Simulator(q, noise=rf.Noise(seed=-1)), ValueError, "noise.seed: must be >= 0"),
        (lambda q: rf.Simulator(q, actuator=rf.FixedPitchActuator(time_constant_s=-1)), ValueError, "actuator.time_constant_s"),
        (lambda q: rf.Simulator(q).run(rf.State(), 2.0, faults=[rf.RotorFault(rotor=5, time=1.0)]), ValueError, r"faults\[0\].rotor: rotor numbers run from 1 to 4, got 5"),
        (lambda q: rf.Simulator(q).run(rf.State(), 2.0, faults=[rf.RotorFault(rotor=1, time=1.0, efficiency=1.5)]), ValueError, r"faults\[0\].efficiency: must lie in \[0, 1\]"),
        (lambda q: rf.Simulator(q).run(rf.State(), 1.0, faults=[rf.RotorFault(rotor=1, time=float("nan"))]), ValueError, r"faults\[0\].time: must be finite"),
        (lambda q: rf.RotorFault(rotor=0, time=1.0), ValueError, "rotor: rotor numbers run from 1"),
        (lambda q: rf.State(position=(0, float("nan"), 0)), ValueError, "position: must be finite"),
        (lambda q: rf.State(quaternion=(2, 0, 0, 0)), ValueError, "quaternion: must have unit norm"),
        (lambda q: rf.Simulator(q).run(rf.State(), float("nan")), ValueError, "duration_s: must be finite"),
        (lambda q: rf.Simulator(q).run(rf.State(), 1.0, controller="lqr"), TypeError, "controller: expected"),
        (lambda q: rf.Simulator(q).run(rf.State(), 1.0, controller=rf.OpenLoop.constant([1.0] * 3)), ValueError, "controller: expected 4 commands"),
        (lambda q: rf.OpenLoop([1.0, 0.5], [[1.0] * 4] * 2), ValueError, r"times\[1\]: times must be strictly increasing"),
        (lambda q: rf.LinearFeedback(np.zeros((4, 11)), np.zeros(12), np.zeros(4)), ValueError, "gain: expected 4 x 12"),
        (lambda q: rf.Simulator(q).run((0, 0, 0), 1.0), TypeError, "x0: expected rotorfault.State"),
    ],
)
def test_bad_input(quad: rf.Airframe, make, error: type[Exception], message: str) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(error, match=message):
        make(quad)


def test_batch_with_progress_flies_every_run_as_one_call_would(quad: rf.Airframe, lqr: rf.LinearFeedback, capsys: pytest.CaptureFixture[str]) -> None:
    """``progress=True`` sends the runs in chunks and shows a bar on standard error; each run,
    sensor noise included (run i uses seed + i), is bit-identical to the single call's."""
    sim = rf.Simulator(quad, dt_s=1 / 400, substeps=2, noise=rf.Noise(snr_db=30.0, seed=7))
    starts = [rf.State(position=(0.01 * i, 0.0, -10.0)) for i in range(40)]
    faults = [[rf.RotorFault(rotor=1 + i % 4, time=0.3, efficiency=0.5)] if i % 3 == 0 else [] for i in range(40)]
    whole = rf.simulate_batch(sim, starts, 0.6, controllers=lqr, faults=faults)
    capsys.readouterr()
    chunked = rf.simulate_batch(sim, starts, 0.6, controllers=lqr, faults=faults, progress=True)
    err = capsys.readouterr().err
    assert "40 runs" in err and "40/40" in err, err
    for a, b in zip(whole.trajectories, chunked.trajectories):
        np.testing.assert_array_equal(a.position, b.position)
        np.testing.assert_array_equal(a.measured, b.measured)
    with pytest.raises(TypeError, match="^progress"):
        rf.simulate_batch(sim, starts[:2], 0.1, controllers=lqr, progress="yes")  # type: ignore[arg-type]


def test_a_substep_too_long_for_the_motion_is_refused_or_ends_the_run(quad: rf.Airframe) -> None:
    """The step-size guard from Python (issue 18 item 5): h max(|omega|, 1 / time_constant) may
    not exceed MAX_RATE_STEP = 0.25. A 75 rad/s spin at h = 0.05 s (3.75) and a 0.02 s rotor lag
    at h = 0.02 s (1.0) are refused before the run with the numbers and the substeps needed; a
    yaw rate that grows past 0.25 / h during the run ends it with a ``step-size`` event, a
    numerical cause, not ``body-rate``."""
    assert rf.MAX_RATE_STEP == 0.25
    coarse = rf.Simulator(quad, dt_s=0.05, substeps=1)
    with pytest.raises(ValueError, match=r"^substeps: .*h = dt / substeps = 0\.05 s .*75 rad/s.* = 3\.75 exceeds 0\.25.*substeps >= 15"):
        coarse.run(rf.State(position=(0, 0, -10), omega=(0, 0, 75)), 1.0)
    with pytest.raises(ValueError, match=r"^substeps: .*1 / time_constant = 50 1/s.* exceeds 0\.25.*substeps >= 4"):
        rf.Simulator(quad, dt_s=0.02, substeps=1, actuator=rf.FixedPitchActuator(time_constant_s=0.02))
    # Accepted at the start (4.9 rad/s x 0.05 s = 0.245), then a yaw torque spins it up past
    # 0.25 / 0.05 = 5 rad/s.
    f = quad.hover_thrust_n / 4
    yaw = rf.OpenLoop.constant([f * 1.2, f * 0.8, f * 1.2, f * 0.8])
    tr = coarse.run(rf.State(position=(0, 0, -10), omega=(0, 0, 4.9)), 2.0, controller=yaw)
    event = tr.events[0]
    assert event.kind == "step-size" and "substeps" in event.description
    assert np.linalg.norm(event.state[9:12]) == pytest.approx(5.0, abs=1e-9)


def test_extra_keywords_may_not_replace_a_recorded_field() -> None:
    """``extra=`` (the keywords a ``Trajectory`` subclass adds, e.g. ``faults``) was merged over
    the record, so ``extra={"position": ...}`` replaced the flown positions: a recorded field's
    name is refused, naming it, before the run (the controller is never called)."""
    from rotorfault import _rfcore

    sim = rf.Simulator(rf.Airframe.preset("quad-x"))
    calls = []

    def controller(t: float, x: np.ndarray) -> np.ndarray:
        calls.append(t)
        return np.full(4, 4.0)

    def run(extra: dict) -> object:
        return _rfcore.simulate(sim.airframe._core, sim.actuator, sim.drag, controller, rf.State(position=(0, 0, -1))._packed(),
                                [], sim.airframe.efficiency, None, sim._config(0.05), trajectory_type=rf.Trajectory, extra=extra)

    for name in ("position", "t", "sensing_counts", "divergence"):
        with pytest.raises(ValueError, match=f'^extra: "{name}" is a field the run records'):
            run({"faults": [], name: np.zeros((1, 3))})
    with pytest.raises(TypeError, match="^extra: names must be strings, got int"):
        run({1: 2})
    assert calls == []
    flown = run({"faults": []})
    assert calls and tuple(flown.faults) == () and len(flown.t) == len(flown.position)

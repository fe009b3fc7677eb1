"""Flight verdicts (rotorfault.flight.outcomes.flight_metrics), on Ke's scenarios and constructed
trajectories: outcomes judged over the last window, a steady circle, runs that never settled,
the settle clock's start, lost runs, and faults outside a run. Exact inputs, so the tolerances are
those of the arithmetic (1e-9) unless stated."""

from __future__ import annotations

import math

import numpy as np
import pytest

import rotorfault as rf
from rotorfault.flight import outcomes
from rotorfault.papers import ke as ke_paper

HOVER = (0.0, 0.0, -10.0)
DT = 0.01


def trajectory(
    t_end: float,
    *,
    position=None,  # type: ignore[no-untyped-def]
    r=None,  # type: ignore[no-untyped-def]
    faults: tuple[rf.RotorFault, ...] = (),
    efficiency0: tuple[float, ...] = (1, 1, 1, 1),
    lost_at: float | None = None,
) -> rf.Trajectory:
    """A level trajectory sampled every 10 ms; ``position(t)`` (N x 3, NED) and ``r(t)`` (yaw
    rate) are functions of time; velocity is the exact derivative by central differences."""
    t = np.arange(0.0, t_end + DT / 2, DT)
    n = len(t)
    pos = np.tile(HOVER, (n, 1)) if position is None else position(t)
    vel = np.gradient(pos, t, axis=0)
    omega = np.zeros((n, 3))
    if r is not None:
        omega[:, 2] = r(t)
    quat = np.tile([1.0, 0, 0, 0], (n, 1))
    eff = np.tile(np.array(efficiency0, dtype=float), (n, 1))
    for f in sorted(faults, key=lambda f: f.time):
        eff[t >= f.time, f.rotor - 1] = f.efficiency
    events = []
    if lost_at is not None:
        events.append(rf.Divergence(time_s=lost_at, kind="tilt", state=np.zeros(12)))
    return rf.Trajectory(
        t=t, position=pos, velocity=vel, quaternion=quat, euler=np.zeros((n, 3)), omega=omega,
        primary_axis=np.tile([0.0, 0, 1], (n, 1)), rotor_command=np.ones((n, 4)), rotor_thrust=np.ones((n, 4)),
        efficiency=eff, recorded_measurements=np.zeros((n, 0)), events=events, faults=tuple(faults),
    )


def scenario(faults: tuple[rf.RotorFault, ...] = (), duration: float = 40.0) -> ke_paper.KeScenario:
    return ke_paper.KeScenario("constructed", "constructed", (1, 1, 1, 1), faults, duration)


def circle(radius: float, speed: float, centre: tuple[float, float] = (radius_default := 7.5, 0.0)):  # type: ignore[no-untyped-def]
    def position(t: np.ndarray) -> np.ndarray:
        w = speed / radius
        return np.stack([centre[0] - radius * np.cos(w * t), centre[1] + radius * np.sin(w * t), np.full_like(t, -10.0)], axis=1)

    return position


def test_holding_is_judged_over_the_window_not_the_last_sample() -> None:
    """Item 1: a 7.5 m circle through the setpoint at 3.6 m/s. At t = 2 pi R / v (one lap) the
    last sample is exactly on the setpoint; the old verdict said "holds position"."""
    lap = 2 * math.pi * 7.5 / 3.6
    tr = trajectory(3 * lap, position=circle(7.5, 3.6))
    m = outcomes.flight_metrics(tr, scenario(duration=3 * lap))
    # The last sample lies within one 10 ms step (3.6 cm) of the setpoint: alone it says "holds".
    assert m.final_horizontal_error_m is not None and m.final_horizontal_error_m < 0.036
    assert m.outcome == "circling" and m.outcome_label == "circling"
    assert m.window_s == 5.0
    assert m.window_speed_m_s == pytest.approx(3.6, rel=1e-3)  # central differences: O(dt^2)
    assert m.window_horizontal_error_m is not None and m.window_horizontal_error_m > outcomes.HOLD_BAND_M[0]
    # Any run length gives the same verdict.
    for end in (3 * lap - 2.0, 3 * lap + 2.0, 3 * lap + 7.3):
        assert outcomes.flight_metrics(trajectory(end, position=circle(7.5, 3.6)), scenario()).outcome == "circling"


def test_a_small_fast_circle_inside_the_band_is_not_holding() -> None:
    """Rotor at 30 %: circling at 3.8 m/s within 2 m of the setpoint is not "holding"."""
    tr = trajectory(60.0, position=circle(1.0, 3.8, centre=(0.0, 0.0)))
    m = outcomes.flight_metrics(tr, scenario())
    assert m.window_horizontal_error_m is not None and m.window_horizontal_error_m <= 1.0 + 1e-9
    assert m.outcome == "circling"


def test_an_oscillation_is_circling() -> None:
    tr = trajectory(40.0, position=lambda t: np.stack([3 * np.sin(t), 0 * t, -10 + 0 * t], axis=1))
    assert outcomes.flight_metrics(tr, scenario()).outcome == "circling"


def test_slow_drift_is_off_station_and_still_is_holding() -> None:
    drift = trajectory(40.0, position=lambda t: np.stack([10 - 0.05 * t, 0 * t, -10 + 0 * t], axis=1))
    assert outcomes.flight_metrics(drift, scenario()).outcome == "off-station"
    near = trajectory(40.0, position=lambda t: np.stack([1.5 + 0 * t, 0 * t, -10.5 + 0 * t], axis=1))
    m = outcomes.flight_metrics(near, scenario())
    assert m.outcome == "holds-position"
    assert m.window_horizontal_error_m == pytest.approx(1.5, abs=1e-9)
    assert m.window_altitude_error_m == pytest.approx(0.5, abs=1e-9)
    # ... but passing through quickly is not (speed bound).
    fast = trajectory(40.0, position=lambda t: np.stack([0.5 * np.sin(2 * t), 0 * t, -10 + 0 * t], axis=1))
    assert outcomes.flight_metrics(fast, scenario()).outcome == "circling"


def test_a_run_that_never_settled_has_no_settle_time_or_steady_values() -> None:
    """Item 2: rotor 1 fails at 35 s of 40 s; r ramps over the whole window."""
    fault = rf.RotorFault(1, 35.0, 0.0)
    tr = trajectory(40.0, r=lambda t: np.where(t < 35.0, 0.0, -(t - 35.0) * 2.6), faults=(fault,))
    m = outcomes.flight_metrics(tr, scenario((fault,)))
    assert m.spin_settle_s is None and not m.settled
    assert m.r_rad_s is None and m.n3z is None and m.rotation_axis is None
    row = ke_paper.report_rows([ke_paper.ScenarioRun(scenario((fault,)), "feedforward", tr)])[0]
    assert ke_paper.cell(row, "spin_settle_s") == "not settled"
    assert ke_paper.cell(row, "r_rad_s") == "not settled"


def test_settled_run_reports_settle_time_from_the_last_fault() -> None:
    fault = rf.RotorFault(1, 2.0, 0.0)
    # r reaches -20 at 2 + 8 = 10 s and stays.
    tr = trajectory(40.0, r=lambda t: -20.0 * np.clip((t - 2.0) / 8.0, 0.0, 1.0), faults=(fault,))
    m = outcomes.flight_metrics(tr, scenario((fault,)))
    assert m.r_rad_s == pytest.approx(-20.0, abs=1e-12)
    # Within 5 % (1 rad/s) from r = -19 at t = 2 + 7.6 s: settle 7.6 s, to one sample (10 ms).
    assert m.spin_settle_s == pytest.approx(7.6, abs=DT + 1e-9)


def test_a_no_op_fault_does_not_restart_the_settle_clock() -> None:
    """Item 3: RotorFault(2, 30.0, 1.0) sets the efficiency rotor 2 already has."""
    faults = (rf.RotorFault(1, 2.0, 0.0), rf.RotorFault(2, 30.0, 1.0))
    tr = trajectory(40.0, r=lambda t: -20.0 * np.clip((t - 2.0) / 8.0, 0.0, 1.0), faults=faults)
    assert outcomes.effective_fault_times(tr) == [2.0]
    m = outcomes.flight_metrics(tr, scenario(faults))
    assert m.spin_settle_s == pytest.approx(7.6, abs=DT + 1e-9)


def test_fault_times_come_from_the_trajectory_not_the_scenario() -> None:
    """Item 3: scoring a run flown with a fault at 2 s against a scenario whose fault is at 10 s
    counts from 2 s (the run's own fault)."""
    flown = (rf.RotorFault(1, 2.0, 0.0),)
    other = ke_paper.KeScenario("x", "x", (0, 1, 1, 1), (rf.RotorFault(1, 10.0, 0.0),))
    tr = trajectory(40.0, r=lambda t: -20.0 * np.clip((t - 2.0) / 8.0, 0.0, 1.0), faults=flown)
    assert outcomes.flight_metrics(tr, other).spin_settle_s == pytest.approx(7.6, abs=DT + 1e-9)


def test_faults_outside_the_run_are_refused() -> None:
    sim = rf.Simulator(rf.Airframe.preset("quad-x"))
    for time, field in ((20.0, "faults\\[0\\].time"), (-1.0, "faults\\[0\\].time"), (10.0, "faults\\[0\\].time")):
        with pytest.raises(ValueError, match=f"^{field}: must lie in \\[0, duration_s\\)"):
            sim.run(rf.State(), 10.0, faults=[rf.RotorFault(1, time)])
    with pytest.raises(ValueError, match="^faults\\[1\\]\\[0\\].time"):
        rf.simulate_batch(sim, [rf.State(), rf.State()], 1.0, faults=[[], [rf.RotorFault(1, 5.0)]])
    with pytest.raises(ValueError, match="^duration_s: must be at least one control period"):
        sim.run(rf.State(), 0.001)
    with pytest.raises(ValueError, match="^faults\\[0\\].time"):
        ke_paper.run_scenario(ke_paper.KeScenario("late", "late", (0, 1, 1, 1), (rf.RotorFault(1, 50.0),), 40.0))


def test_lost_runs_mark_position_columns_lost() -> None:
    """Item 4: the track of a lost run stops at the loss; no altitude loss or error is reported
    as if it were the run's, and the efficiency column shows only faults that happened."""
    faults = (rf.RotorFault(1, 2.0, 0.0), rf.RotorFault(4, 10.0, 0.0))
    tr = trajectory(2.37, faults=faults, lost_at=2.37)
    sc = ke_paper.KeScenario("pair", "pair", (0, 1, 1, 0), faults)
    m = outcomes.flight_metrics(tr, sc)
    assert m.outcome == "tilt" and m.lost_at_s == 2.37
    assert m.max_altitude_loss_m is None and m.max_horizontal_error_m is None and m.final_altitude_error_m is None
    row = ke_paper.report_rows([ke_paper.ScenarioRun(sc, "baseline", tr)])[0]
    for column in ke_paper.POSITION_COLUMNS + ke_paper.STEADY_COLUMNS:
        assert ke_paper.cell(row, column) == "lost at 2.37 s", column
    assert row["efficiency"] == "0 1 1 1" and row["planned_efficiency"] == "0 1 1 0"
    assert row["faults_not_reached"] == "rotor 4 -> 0 at 10 s"


def test_flown_one_failure_verdicts() -> None:
    """The flown scenarios keep their verdicts (README table): one failure drifts back slowly
    (off station, settled); the baseline law is lost; half a rotor circles at about 4 m/s."""
    m = ke_paper.run_scenario("one-failure").metrics
    assert m.outcome == "off-station" and m.settled
    assert m.window_speed_m_s is not None and m.window_speed_m_s < outcomes.HOLD_SPEED_M_S
    lost = ke_paper.run_scenario("one-failure", law="baseline").metrics
    assert lost.outcome == "tilt" and lost.lost_at_s is not None and lost.max_altitude_loss_m is None
    half = ke_paper.run_scenario("partial-0.5").metrics
    assert half.outcome == "circling"  # measured 4.2 m/s mean, turning

"""One verdict per flight, from its whole window (issue 28): holds, drifts, circles, crashed,
diverged; a vehicle that falls without touching the ground is never a success; a moving
reference is judged relative to its own velocity; the core decides the same verdict (its
``Outcome::verdict``, read through the campaign rows in tests/studies). Exact inputs: the
tolerances are the arithmetic's (1e-9) unless stated."""

from __future__ import annotations

import math

import numpy as np
import pytest

import rotorfault as rf
from rotorfault.flight import outcomes

DT = 0.01


def _trajectory(t_end: float, position, events=()) -> rf.Trajectory:  # type: ignore[no-untyped-def]
    t = np.arange(0.0, t_end + DT / 2, DT)
    n = len(t)
    pos = position(t)
    vel = np.gradient(pos, t, axis=0)
    return rf.Trajectory(
        t=t, position=pos, velocity=vel, quaternion=np.tile([1.0, 0, 0, 0], (n, 1)), euler=np.zeros((n, 3)),
        omega=np.zeros((n, 3)), primary_axis=np.tile([0.0, 0, 1], (n, 1)), rotor_command=np.ones((n, 4)),
        rotor_thrust=np.ones((n, 4)), efficiency=np.ones((n, 4)), recorded_measurements=np.zeros((n, 0)),
        events=list(events), faults=(),
    )


class _Setpoint:
    setpoints = ((0.0, (0.0, 0.0, -10.0)),)


def test_each_outcome_has_one_verdict_and_the_thresholds_are_stated() -> None:
    still = _trajectory(20.0, lambda t: np.tile([0.5, 0.0, -10.2], (len(t), 1)))
    away = _trajectory(20.0, lambda t: np.tile([14.4, 0.0, -10.0], (len(t), 1)))
    ring = _trajectory(40.0, lambda t: np.stack([3 * np.cos(t), 3 * np.sin(t), -10 + 0 * t], axis=1))
    verdicts = [outcomes.flight_metrics(tr, _Setpoint()).verdict for tr in (still, away, ring)]
    assert verdicts == ["holds", "drifts", "circles"]
    m = outcomes.flight_metrics(away, _Setpoint())
    assert m.verdict_label == "drifts (window: 14.40 m off, 0.00 m in altitude, up to 0.00 m/s)" and m.cause is None
    falling = np.zeros(12)
    falling[5] = 5.6  # 5.6 m/s down at the impact
    crash = rf.Divergence(time_s=2.3, kind="crashed", state=falling)
    lost = outcomes.flight_metrics(_trajectory(2.3, lambda t: np.tile([0, 0, -10.0], (len(t), 1)), [crash]), _Setpoint())
    assert (lost.verdict, lost.cause, lost.verdict_label) == ("crashed", "crashed", "crashed at 2.30 s (5.6 m/s)")
    tilt = rf.Divergence(time_s=1.52, kind="tilt", state=np.zeros(12))
    gone = outcomes.flight_metrics(_trajectory(1.52, lambda t: np.tile([0, 0, -10.0], (len(t), 1)), [tilt]), _Setpoint())
    assert (gone.verdict, gone.cause, gone.verdict_label) == ("diverged", "tilt", "diverged (tilt) at 1.52 s")
    meanings = outcomes.VERDICT_MEANINGS
    assert "2 m horizontally and 1 m in altitude" in meanings["holds"] and "0.5 m/s" in meanings["holds"]
    assert "90 degrees" in meanings["circles"] and "last 5 s" in meanings["circles"]
    with pytest.raises(ValueError, match="outcome: 'level' is not a flight outcome code"):
        outcomes.verdict_of("level")


def test_a_vehicle_that_falls_most_of_its_height_without_touching_the_ground_drifts() -> None:
    """The issue's case: no controller, 10 m up; after 1.385 s it has fallen 9.40 m (g t^2 / 2
    with g = 9.80) and the run ends in the air. Not "no divergence", not a success: drifts."""
    quad = rf.Airframe.preset("quad-x")
    run = rf.Simulator(quad, dt_s=0.005, substeps=1).run(rf.State(position=(0, 0, -10)), 1.385)
    assert not run.diverged
    fallen = run.position[-1, 2] - run.position[0, 2]
    assert fallen == pytest.approx(0.5 * quad.gravity_m_s2 * 1.385**2, rel=1e-9) and 9.3 < fallen < 9.5
    m = outcomes.flight_metrics(run, _Setpoint())
    assert m.verdict == "drifts" and m.window_altitude_error_m == pytest.approx(fallen, rel=1e-12)
    # With the ground 1 m lower than it fell, the same fall crashes.
    low = rf.Simulator(quad, dt_s=0.005, substeps=1, ground_z_m=-1.0).run(rf.State(position=(0, 0, -10)), 1.385)
    assert outcomes.flight_metrics(low, _Setpoint()).verdict == "crashed"


def test_a_moving_reference_is_judged_relative_to_its_velocity() -> None:
    """A 2 m circle flown at 0.63 m/s exactly: against the circle it holds (speed error 0);
    against a fixed setpoint at its centre it is off and moving: not held."""
    w = 2 * math.pi / 20.0

    def path(t: np.ndarray) -> np.ndarray:
        return np.stack([2 * np.cos(w * t), 2 * np.sin(w * t), -10 + 0 * t], axis=1)

    tr = _trajectory(60.0, path)
    reference = (path(tr.t), np.gradient(path(tr.t), tr.t, axis=0))
    m = outcomes.flight_metrics(tr, reference=reference)
    assert m.verdict == "holds" and m.window_speed_m_s is not None and m.window_speed_m_s < 1e-9
    assert outcomes.flight_metrics(tr, _Setpoint()).verdict != "holds"
    with pytest.raises(ValueError, match="reference: give a scenario with setpoints or a reference"):
        outcomes.flight_metrics(tr)
    with pytest.raises(ValueError, match=r"reference: expected two arrays of shape \(6001, 3\)"):
        outcomes.flight_metrics(tr, reference=(np.zeros((3, 3)), np.zeros((3, 3))))


def test_the_core_decides_the_same_verdicts() -> None:
    """The per-run summary's verdict (Rust, ``Outcome::verdict``) for a fall that crashes, one that
    ends in the air, and a hover: the campaign's rows (tests/studies compare every field with
    :func:`rotorfault.studies.summaries.summarize` on full trajectories)."""
    from rotorfault.studies import Campaign
    from rotorfault.studies.campaign import run_chunk

    rows = run_chunk(Campaign(runs=6, duration_s=16.0, failures=((), (1,), (1, 4)), seed=4), 0)
    assert set(rows["verdict"].tolist()) <= set(outcomes.VERDICTS)
    for outcome, verdict, cause in zip(rows["outcome"], rows["verdict"], rows["cause"]):
        assert outcomes.verdict_of(str(outcome)) == verdict
        assert cause == ("" if verdict in ("holds", "drifts", "circles") else outcome)


def test_a_wind_step_acts_from_exactly_its_time() -> None:
    """A time given twice in ``wind_profile`` is a step (Wang's scenario 3: 4 m/s "when t >= 1").
    The integration ends an RK4 step there, so a drag-only body (rotors off) follows the exact
    solution ``v = w (1 - exp(-(d/m)(t - 1)))`` to rounding, also when the step falls inside a
    control period (0.9 to 1.2 s here) and a substep. Before it nothing moves horizontally."""
    quad = rf.Airframe.preset("quad-x")
    d = 0.5
    sim = rf.Simulator(quad, dt_s=0.3, substeps=7, drag=rf.Drag(linear_n_s_m=d),
                       wind_profile=[(1.0, (0.0, 0.0, 0.0)), (1.0, (4.0, 0.0, 0.0))], ground=False)
    run = sim.run(rf.State(position=(0, 0, -100)), 1.8)
    k = d / quad.mass_kg
    exact = np.where(run.t < 1.0, 0.0, 4.0 * (1 - np.exp(-k * np.clip(run.t - 1.0, 0.0, None))))
    assert np.max(np.abs(run.velocity[:, 0] - exact)) < 1e-9
    assert np.all(run.velocity[run.t <= 0.9, 0] == 0.0)
    with pytest.raises(ValueError, match=r"wind_profile\[2\].time: a time may be given at most twice"):
        rf.Simulator(quad, wind_profile=[(1.0, (0, 0, 0)), (1.0, (1, 0, 0)), (1.0, (2, 0, 0))]).run(rf.State(), 1.0)
    with pytest.raises(ValueError, match=r"wind_profile\[1\].time: times must not decrease"):
        rf.Simulator(quad, wind_profile=[(1.0, (0, 0, 0)), (0.5, (1, 0, 0))]).run(rf.State(), 1.0)


def test_verdicts_are_counted_every_verdict_listed() -> None:
    """Issue 28: count each verdict, the ones that did not occur included, in one order."""
    from rotorfault.flight.outcomes import count_verdicts, verdict_count_text

    assert count_verdicts(["drifts", "crashed", "drifts"]) == {"holds": 0, "drifts": 2, "circles": 0, "crashed": 1, "diverged": 0}
    assert verdict_count_text([]) == "holds 0, drifts 0, circles 0, crashed 0, diverged 0"
    with pytest.raises(ValueError, match="verdicts: 'off-station' not among holds"):
        count_verdicts(["off-station"])

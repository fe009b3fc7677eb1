"""The ground (issue #28): the plane z = ground_z_m (world NED, default 0) ends a run that reaches
it as ``crashed``, at the located time, with the impact. Checked against free fall, where the time
to fall h is sqrt(2 h / g) and the speed at the ground sqrt(u^2 + 2 g h) (u horizontal), to 1e-9;
RK4 integrates the parabola exactly, so only the bisection's rounding remains."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import rotorfault as rf
from rotorfault import _rfcore
from rotorfault.studies.scenario_file import load_scenario

G = 9.80  # the Du presets' gravity


@pytest.fixture(scope="module")
def quad() -> rf.Airframe:
    return rf.Airframe.preset("quad-x")


def _fall(sim: rf.Simulator, height_m: float, *, horizontal_m_s: float = 0.0, roll_rad: float = 0.0,
          duration_s: float = 5.0) -> rf.Trajectory:
    """Rotors off from ``height_m`` above the simulator's ground (at z = 0 without one)."""
    ground = sim.ground_z_m or 0.0
    start = rf.State(position=(1.0, -2.0, ground - height_m), velocity=(0.6 * horizontal_m_s, 0.8 * horizontal_m_s, 0.0),
                     euler=(roll_rad, 0.0, 0.0))
    return sim.run(start, duration_s)


@pytest.mark.parametrize(("ground_z_m", "height_m"), [(None, 10.0), (0.0, 1.0), (-25.0, 10.0), (3.5, 0.2)])
def test_a_free_fall_crashes_at_the_analytic_time_and_speed(quad: rf.Airframe, ground_z_m: float | None, height_m: float) -> None:
    sim = rf.Simulator(quad, dt_s=0.0025, substeps=1, ground_z_m=ground_z_m)
    assert sim.ground_z_m == (0.0 if ground_z_m is None else ground_z_m)
    tr = _fall(sim, height_m)
    event = tr.events[0]
    assert event.kind == "crashed" and event.description == "hit the ground"
    assert event.time_s == pytest.approx(math.sqrt(2 * height_m / G), abs=1e-9)
    assert event.impact_speed_m_s == pytest.approx(math.sqrt(2 * G * height_m), abs=1e-9)
    assert event.impact_vertical_speed_m_s == pytest.approx(math.sqrt(2 * G * height_m), abs=1e-9)
    assert event.impact_tilt_rad == pytest.approx(0.0, abs=1e-12)
    # The recorded run ends at the contact: its last row is the event, at the plane.
    assert tr.t[-1] == event.time_s and tr.t[-2] < event.time_s
    assert 0.0 <= tr.position[-1, 2] - sim.ground_z_m < 1e-9  # type: ignore[operator]
    np.testing.assert_array_equal(tr.position[-1], event.state[:3])
    assert np.all(np.isnan(tr.rotor_command[-1])) and np.all(np.isnan(tr.measured[-1]))
    assert str(event).startswith(f"crashed at t = {event.time_s:.4f} s: hit the ground at ")


@settings(max_examples=25, deadline=None, derandomize=True)
@given(height_m=st.floats(0.05, 60.0), horizontal_m_s=st.floats(0.0, 20.0), roll_rad=st.floats(-1.5, 1.5),
       ground_z_m=st.floats(-100.0, 100.0))
def test_impact_speed_and_attitude_of_any_free_fall(height_m: float, horizontal_m_s: float, roll_rad: float,
                                                    ground_z_m: float) -> None:
    """Speed sqrt(u^2 + 2 g h), of which sqrt(2 g h) into the ground; no torque, so the attitude at
    impact is the start's: for any height, horizontal speed, roll and ground height."""
    sim = rf.Simulator(rf.Airframe.preset("quad-x"), dt_s=0.01, substeps=1, ground_z_m=ground_z_m)
    event = _fall(sim, height_m, horizontal_m_s=horizontal_m_s, roll_rad=roll_rad).events[0]
    vertical = math.sqrt(2 * G * height_m)
    assert event.kind == "crashed"
    assert event.time_s == pytest.approx(math.sqrt(2 * height_m / G), abs=1e-9)
    assert event.impact_vertical_speed_m_s == pytest.approx(vertical, abs=1e-9)
    assert event.impact_speed_m_s == pytest.approx(math.hypot(horizontal_m_s, vertical), abs=1e-9)
    assert event.impact_tilt_rad == pytest.approx(abs(roll_rad), abs=1e-9)
    assert event.state[6] == pytest.approx(roll_rad, abs=1e-9)


def test_without_a_ground_the_fall_goes_through_the_plane(quad: rf.Airframe) -> None:
    sim = rf.Simulator(quad, dt_s=0.0025, substeps=1, ground=False)
    assert sim.ground_z_m is None and sim.ground is False
    tr = _fall(sim, 10.0, duration_s=3.0)
    assert not tr.diverged and tr.t[-1] == 3.0
    assert tr.position[-1, 2] == pytest.approx(-10.0 + 0.5 * G * 9.0, abs=1e-9)  # 34 m below z = 0
    # A start on the plane or below it is a flight without a ground.
    assert not sim.run(rf.State(position=(0, 0, 5.0)), 0.1).diverged


def test_a_hover_stays_clear_of_the_ground(quad: rf.Airframe) -> None:
    """Half a metre up for 20 s under the hover LQR, and open loop at the trim: no contact."""
    sim = rf.Simulator(quad, dt_s=1 / 400, substeps=2)
    lqr = rf.lqr_hover(sim, position=(0, 0, -0.5))
    for controller in (lqr, rf.OpenLoop.constant(lqr.u_trim)):
        tr = sim.run(rf.State(position=(0, 0, -0.5)), 20.0, controller=controller)
        assert not tr.diverged and tr.t[-1] == 20.0
        # Open loop, the trim's rounding torque (~1e-16 N m) drifts it 4e-9 m sideways in 20 s.
        assert np.abs(tr.position[:, 2] + 0.5).max() < 1e-9 and np.abs(tr.position[:, :2]).max() < 1e-7


def test_a_batch_crashes_exactly_like_single_runs(quad: rf.Airframe) -> None:
    sim = rf.Simulator(quad, dt_s=0.01, substeps=2)
    lqr = rf.lqr_hover(sim, position=(0, 0, -5))
    starts = [rf.State(position=(0, 0, -2)), rf.State(position=(0, 0, -5)), rf.State(position=(1, 0, -3), velocity=(2, 0, 0))]
    controllers = [None, lqr, None]
    batch = rf.simulate_batch(sim, starts, 2.0, controllers=controllers, record_every=7)
    assert batch.diverged.tolist() == [True, False, True]
    for i, (start, controller) in enumerate(zip(starts, controllers)):
        single = sim.run(start, 2.0, controller=controller, record_every=7)
        tr = batch.trajectories[i]
        np.testing.assert_array_equal(tr.t, single.t)
        np.testing.assert_array_equal(tr.position, single.position)
        assert [(e.kind, e.time_s, e.impact_speed_m_s, e.state.tolist()) for e in tr.events] == [
            (e.kind, e.time_s, e.impact_speed_m_s, e.state.tolist()) for e in single.events]
    assert batch.divergence_time[0] == pytest.approx(math.sqrt(2 * 2.0 / G), abs=1e-9)
    assert batch.divergence_time[2] == pytest.approx(math.sqrt(2 * 3.0 / G), abs=1e-9)
    assert batch.trajectories[2].events[0].impact_speed_m_s == pytest.approx(math.hypot(2.0, math.sqrt(2 * G * 3.0)), abs=1e-9)


def test_bad_ground_settings_are_refused_by_name(quad: rf.Airframe) -> None:
    for bad in (math.nan, math.inf, -math.inf):
        with pytest.raises(ValueError, match="^ground_z_m: must be finite"):
            rf.Simulator(quad, ground_z_m=bad)
        with pytest.raises(ValueError, match="^ground_z_m: must be finite"):
            _rfcore.SimulationConfig(ground_z_m=bad)
    with pytest.raises(TypeError, match="^ground_z_m: expected a real number"):
        rf.Simulator(quad, ground_z_m="low")  # type: ignore[arg-type]
    with pytest.raises(TypeError, match="^ground: expected True or False"):
        rf.Simulator(quad, ground=1)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match=r"^ground_z_m, ground: a ground height \(2 m\) with ground=False"):
        rf.Simulator(quad, ground_z_m=2.0, ground=False)
    sim = rf.Simulator(quad)
    # On the ground (no ground reaction: the vehicle would sink at once) and below it.
    for z in (0.0, 0.5):
        with pytest.raises(ValueError, match=r"^x0.position\[2\]: the run starts on or below the ground: z = "):
            sim.run(rf.State(position=(0, 0, z)), 1.0)
    with pytest.raises(ValueError, match=r"^x0s\[1\].position\[2\]: the run starts on or below the ground"):
        rf.simulate_batch(sim, [rf.State(position=(0, 0, -1)), rf.State()], 1.0)


def test_defaults_come_from_the_core(quad: rf.Airframe) -> None:
    assert _rfcore.SimulationConfig().ground_z_m == 0.0 == rf.Simulator(quad).ground_z_m
    assert _rfcore.SimulationConfig(ground=False).ground_z_m is None
    assert rf.Simulator(quad).run(duration_s=0.01).position[0].tolist() == [0.0, 0.0, -10.0]


def test_a_scenario_file_sets_the_ground(tmp_path: Path) -> None:
    """``ground_z_m`` and ``ground`` at the top of a scenario file; the start defaults to 10 m up."""
    path = tmp_path / "drop.toml"
    path.write_text('airframe = "quad-x"\nduration_s = 3.0\nground_z_m = -6.0\n[controller]\nkind = "none"\n')
    event = load_scenario(path).run().events[0]
    assert event.kind == "crashed" and event.time_s == pytest.approx(math.sqrt(2 * 4.0 / G), abs=1e-9)
    path.write_text('airframe = "quad-x"\nduration_s = 3.0\nground = false\n[controller]\nkind = "none"\n')
    assert not load_scenario(path).run().diverged

"""Types that cross the Rust/Python boundary once (issue 26): the settings Python users make
(``KeGains``, ``Drag``, ``DivergenceLimits``, the actuators, Lanzon's ``OuterLoopGains``) are the
extension's classes themselves, validated once, by the core, with the core's messages, and the
results the core returns (``DirectionalLimit``, ``HoverMargin``, a controller preset) reach users
as they are; no Python mirror copies them field by field."""

from __future__ import annotations

import dataclasses
import math
import pickle

import numpy as np
import pytest

import rotorfault as rf
from rotorfault import _rfcore
from rotorfault.control import ke, lanzon

SETTINGS = [
    (ke.KeGains, "k_v", 0.5),
    (rf.Drag, "linear_n_s_m", 0.3),
    (rf.DivergenceLimits, "max_tilt_rad", 1.0),
    (rf.FixedPitchActuator, "time_constant_s", 0.025),
    (lanzon.OuterLoopGains, "k_i_z", 0.1),
    (lanzon.LanzonVehicle, "mass_kg", 0.6),
]


def test_the_public_names_are_the_extension_classes() -> None:
    assert ke.KeGains is _rfcore.KeGains and rf.Drag is _rfcore.Drag and rf.DivergenceLimits is _rfcore.DivergenceLimits
    assert rf.FixedPitchActuator is _rfcore.FixedPitchActuator and rf.VariablePitchActuator is _rfcore.VariablePitchActuator
    assert lanzon.OuterLoopGains is _rfcore.OuterLoopGains
    # Lanzon's vehicle: the core's, its defaults the core's LanzonVehicle::default() (no Python
    # literal); the subclass adds only the RFL algebra and the simulator.
    assert issubclass(lanzon.LanzonVehicle, _rfcore.LanzonVehicle) and lanzon.LanzonVehicle.__slots__ == ()
    core_vehicle = _rfcore.LanzonVehicle()
    assert [getattr(lanzon.LanzonVehicle(), f) for f in _rfcore.LanzonVehicle.FIELDS] == [getattr(core_vehicle, f) for f in core_vehicle.FIELDS]
    assert lanzon.LanzonVehicle().model == _rfcore.LanzonModel()
    assert rf.DirectionalLimit is _rfcore.DirectionalLimit and rf.HoverMargin is _rfcore.HoverMargin
    # A preset's gains come out of the core's TOML parser as they are: no conversion.
    assert type(ke.preset("ke-hil").gains) is _rfcore.KeGains
    assert ke.preset("ke-hil").gains == ke.KeGains()  # the core's Default is the ke-hil preset


@pytest.mark.parametrize(("cls", "field", "value"), SETTINGS)
def test_settings_behave_like_frozen_records(cls: type, field: str, value: float) -> None:
    default = cls()
    changed = default.replace(**{field: value})  # type: ignore[attr-defined]
    assert getattr(changed, field) == value and changed != default and changed == cls(**{field: value})
    assert hash(changed) == hash(cls(**{field: value})) and len({default, cls()}) == 1
    assert pickle.loads(pickle.dumps(changed)) == changed
    assert repr(changed).startswith(f"{cls.__name__}({cls.FIELDS[0]}=") and f"{field}={value!r}" in repr(changed)  # type: ignore[attr-defined]
    assert [getattr(default, f) for f in cls.FIELDS] == [getattr(cls(), f) for f in cls.FIELDS]  # type: ignore[attr-defined]
    with pytest.raises(AttributeError):
        setattr(default, field, value)
    with pytest.raises(TypeError, match=f"^k_q: not a field of {cls.__name__}"):
        default.replace(k_q=1.0)  # type: ignore[attr-defined]


def test_values_are_checked_once_by_the_core_with_its_messages() -> None:
    """The same messages as when the Python mirror forwarded them: the core's, naming the field."""
    with pytest.raises(ValueError, match=r"^k_omega: must be > 0.5 \(Theorem 1\), got 0.4"):
        ke.KeGains(k_omega=0.4)
    with pytest.raises(ValueError, match=r"^weights\[2\]"):
        ke.KeGains(weights=(1.0, 20.0, 0.0, 0.01))
    with pytest.raises(ValueError, match="^drag.linear_n_s_m: must be finite"):
        rf.Drag(linear_n_s_m=math.nan)
    with pytest.raises(ValueError, match="^drag.rotational_n_m_s: must be >= 0"):
        rf.Drag(rotational_n_m_s=-1.0)


def test_types_are_checked_at_the_boundary_naming_the_field() -> None:
    with pytest.raises(TypeError, match="^k_p: expected a real number, got str"):
        ke.KeGains(k_p="1")  # type: ignore[arg-type]
    with pytest.raises(TypeError, match="^drag.linear_n_s_m: expected a real number, got bool"):
        rf.Drag(linear_n_s_m=True)  # type: ignore[arg-type]
    with pytest.raises(TypeError, match="^limits.max_speed_m_s: expected a real number, got list"):
        rf.DivergenceLimits(max_speed_m_s=[1.0])  # type: ignore[arg-type]
    with pytest.raises(ValueError, match=r"^weights: expected 4 entries \(w_f, w_p, w_q, w_r\), got 3"):
        ke.KeGains(weights=(1.0, 2.0, 3.0))
    import numpy as np

    assert ke.KeGains(k_p=np.float64(0.5), weights=np.array([1.0, 20.0, 20.0, 0.01])).weights == (1.0, 20.0, 20.0, 0.01)


def test_the_dataclass_functions_still_work_with_a_warning() -> None:
    gains = ke.KeGains()
    with pytest.warns(DeprecationWarning, match=r"KeGains\.replace\(\.\.\.\)"):
        changed = dataclasses.replace(gains, k_v=0.5)
    assert changed == gains.replace(k_v=0.5)
    with pytest.warns(DeprecationWarning):
        assert [f.name for f in dataclasses.fields(rf.Drag())] == list(rf.Drag.FIELDS)


def test_a_campaign_with_its_gains_travels_to_a_worker() -> None:
    """Campaigns are pickled to Dask workers with their gains (the chunk task)."""
    from rotorfault.studies import Campaign

    c = Campaign(runs=2, gains=ke.KeGains(k_v=0.25))
    back = pickle.loads(pickle.dumps(c))
    assert back == c and back.gains == ke.KeGains(k_v=0.25)
    assert Campaign.from_dict(c.to_dict()) == c


def test_the_actuators_are_checked_when_made_by_the_cores_rules() -> None:
    """Before, a bad actuator was accepted and refused by the first simulator: now when it is
    made, with the message the simulator gave (the core's ``check_parameters``)."""
    with pytest.raises(ValueError, match="^actuator.time_constant_s: must"):
        rf.FixedPitchActuator(time_constant_s=-1.0)
    with pytest.raises(ValueError, match="^actuator.rate_limit_n_s: must be > 0 and normal"):
        rf.FixedPitchActuator(rate_limit_n_s=0.0)
    with pytest.raises(ValueError, match="^actuator.k1: must be finite"):
        rf.VariablePitchActuator(k=(math.nan, 0.0, 0.0, 0.0), speed_bounds=(0, 1), pitch_bounds=(0, 1))
    with pytest.raises(ValueError, match=r"^actuator.k: expected 4 entries \(k1, k2, k3, k4\), got 3"):
        rf.VariablePitchActuator(k=(1.0, 0.0, 0.0), speed_bounds=(0, 1), pitch_bounds=(0, 1))
    with pytest.raises(TypeError, match=r"^actuator.speed_bounds\[1\]: expected a real number, got str"):
        rf.VariablePitchActuator(k=(1.0, 0.0, 0.0, 0.0), speed_bounds=(0, "1"), pitch_bounds=(0, 1))
    with pytest.raises(TypeError, match="^actuator.pitch_bounds: required"):
        rf.VariablePitchActuator(k=(1.0, 0.0, 0.0, 0.0), speed_bounds=(0, 1))
    with pytest.raises(ValueError, match="^outer_loop.max_tilt_rad: must be in"):
        lanzon.OuterLoopGains(max_tilt_rad=2.0)
    with pytest.raises(TypeError, match="^outer_loop.k_d_z: expected a real number, got str"):
        lanzon.OuterLoopGains(k_d_z="1")  # type: ignore[arg-type]


def test_a_variable_pitch_actuator_is_a_frozen_record() -> None:
    a = rf.VariablePitchActuator(k=np.array([5e-7, 1e-10, 3e-11, 1e-7]), speed_bounds=[0, 10_000], pitch_bounds=(-0.3, 0.3))
    assert a.k == (5e-7, 1e-10, 3e-11, 1e-7) and a.speed_bounds == (0.0, 10_000.0) and a.speed_to_rad_s == 0.0
    assert a.speed_time_constant_s == a.pitch_time_constant_s == pytest.approx(1 / (20 * math.pi), rel=1e-15)
    b = a.replace(pitch_rate_limit_rad_s=5.0)
    assert b.pitch_rate_limit_rad_s == 5.0 and b != a and pickle.loads(pickle.dumps(b)) == b and hash(b) != hash(a)


def test_the_dataclass_positional_form_works_one_release_with_a_warning() -> None:
    with pytest.warns(DeprecationWarning, match=r"FixedPitchActuator\(time_constant_s=\.\.\., rate_limit_n_s=\.\.\.\)"):
        a = rf.FixedPitchActuator(0.025, 50.0)
    assert a == rf.FixedPitchActuator(time_constant_s=0.025, rate_limit_n_s=50.0)
    with pytest.warns(DeprecationWarning, match="VariablePitchActuator"):
        v = rf.VariablePitchActuator((1.0, 0.0, 0.0, 0.0), (0, 1), (0, 1), speed_to_rad_s=2.0)
    assert v == rf.VariablePitchActuator(k=(1.0, 0.0, 0.0, 0.0), speed_bounds=(0, 1), pitch_bounds=(0, 1), speed_to_rad_s=2.0)
    with pytest.warns(DeprecationWarning), pytest.raises(TypeError, match="time_constant_s given by position and by keyword"):
        rf.FixedPitchActuator(0.025, time_constant_s=0.025)


def test_results_reach_users_as_the_core_returns_them() -> None:
    quad = rf.Airframe.preset("quad-x")
    margin = rf.hover_thrust_margin(quad)
    assert type(margin) is _rfcore.HoverMargin and isinstance(margin.commands, np.ndarray)
    assert margin.thrust_to_weight == margin.max_thrust_n / margin.weight_n
    limit = rf.max_virtual_control(quad, [1.0, 0.0, 0.0, 0.0])
    assert type(limit) is _rfcore.DirectionalLimit and limit.commands.shape == (4,)
    preset = ke.preset("ke-hil")
    assert isinstance(preset, _rfcore.FtcPreset) and preset.airframe_name == "ke-quadcopter"
    assert preset.airframe.name == preset.airframe_name and preset.gains == ke.KeGains()
    stiff = preset.replace(gains=preset.gains.replace(k_v=0.5))
    assert type(stiff) is ke.FtcPreset and stiff.gains.k_v == 0.5 and stiff != preset and pickle.loads(pickle.dumps(stiff)) == stiff
    with pytest.raises(ValueError, match="^vehicle.rotor_time_constant_s: must be >= 0"):
        preset.replace(rotor_time_constant_s=-1.0)
    with pytest.raises(AttributeError):
        preset.name = "other"  # type: ignore[misc]


def test_an_acai_is_a_float_holding_the_cores_result() -> None:
    """``AcaiValue`` stays a float (arithmetic, comparison, ``isinstance``) but copies no field:
    it holds the core's ``AcaiResult`` as returned and reads ``hover`` through it; a value made
    from Python is checked by the core's parser, with its message; pickles keep the old form, so
    a pickle written before this change (protocol 2, below) loads."""
    from rotorfault.analysis import AcaiValue

    value = rf.acai(rf.Airframe.preset("hexa-ppnnpn").with_failed_rotors([5]))
    core = value._core
    assert type(core) is _rfcore.AcaiResult and (core.acai, core.hover) == (0.0, "outside") and rf.acai(rf.Airframe.preset("quad-x"))._core.hover_feasible
    assert isinstance(value, float) and value + 1.0 == 1.0 and value < 0.5 and repr(value) == str(value) == "0.0*"
    assert value.hover == "outside" and not value.hover_feasible and not hasattr(value, "__dict__")
    with pytest.raises(AttributeError):
        value.hover = "inside"  # type: ignore[misc]
    old = b"\x80\x02crotorfault.analysis.acai\nAcaiValue\nq\x00G\x00\x00\x00\x00\x00\x00\x00\x00X\x07\x00\x00\x00outsideq\x01\x86q\x02Rq\x03."
    assert pickle.dumps(value, protocol=2) == old
    back = pickle.loads(old)
    assert type(back) is AcaiValue and back == value and back.hover == "outside" and repr(back) == "0.0*"
    made = AcaiValue(1.25, "boundary")
    assert made._core == _rfcore.AcaiResult(1.25, "boundary") and made.hover_feasible and repr(made) == "1.25"
    with pytest.raises(ValueError, match=r'^hover: must be "inside", "boundary", "outside" or "rank-deficient", got "above"'):
        AcaiValue(1.0, "above")  # type: ignore[arg-type]
    with pytest.raises(TypeError, match="^hover: expected a str, got int"):
        AcaiValue(1.0, 1)  # type: ignore[arg-type]


def test_a_trajectory_is_the_cores_made_once_and_not_copied() -> None:
    """``rf.Trajectory`` subclasses the core's trajectory (issue 26: no field-by-field mirror):
    the simulator's arrays are made once and reach users by reference; the constructor's shapes
    are checked by the core, naming the field; old keyword construction and pickling work."""
    sim = rf.Simulator(rf.Airframe.preset("quad-x"))
    run = sim.run(rf.State(position=(0, 0, -1)), 0.6, faults=[rf.RotorFault(rotor=1, time=0.1, efficiency=0.5)])
    assert isinstance(run, _rfcore.Trajectory) and type(run) is rf.Trajectory
    assert run.position is run.position and run.diverged and run.events[0].kind == "crashed"
    same = rf.Trajectory(**{f: getattr(run, f) for f in run.FIELDS})
    assert same.position is run.position and same.divergence is run.divergence
    back = pickle.loads(pickle.dumps(run))
    assert type(back) is rf.Trajectory and back.faults == run.faults and back.events[0].time_s == run.events[0].time_s
    np.testing.assert_array_equal(back.position, run.position)
    with pytest.raises(AttributeError):
        run.faults = ()  # type: ignore[misc]
    n = len(run.t)
    fields = {f: getattr(run, f) for f in run.FIELDS if f != "divergence"}
    event = rf.Divergence(time_s=0.45, kind="tilt", state=np.zeros(12))
    made = rf.Trajectory(**fields, events=[event])
    assert made.diverged and made.events[0].kind == "tilt" and made.events[0].time_s == 0.45
    with pytest.raises(ValueError, match=rf"^velocity: expected {n} rows \(one per time in t\)"):
        rf.Trajectory(**{**fields, "velocity": np.zeros((n + 1, 3))})
    with pytest.raises(ValueError, match="^quaternion: expected 4 columns"):
        rf.Trajectory(**{**fields, "quaternion": np.zeros((n, 3))})
    with pytest.raises(TypeError, match="^position: expected a NumPy array, got list"):
        rf.Trajectory(**{**fields, "position": [[0.0, 0.0, 0.0]] * n})
    with pytest.raises(ValueError, match="^events: a run ends at most once"):
        rf.Trajectory(**fields, events=[event, event])
    assert repr(run).startswith(f"Trajectory({n} rows to ") and "crashed at" in repr(run)


def test_a_divergence_is_the_cores_and_derives_what_follows_from_its_kind_and_state() -> None:
    """``rf.Divergence`` is the core's class (the old ``Event`` was a Python copy of it): it
    stores the time, the kind and the state; the description and the impact are derived (the
    core's ``Divergence::impact``), so they cannot disagree with them."""
    assert rf.Divergence is _rfcore.Divergence and rf.Divergence.FIELDS == ["time_s", "kind", "state"]
    run = rf.Simulator(rf.Airframe.preset("quad-x")).run(rf.State(position=(0, 0, -1)), 3.0)
    d = run.divergence
    assert run.events == [d] and d.kind == "crashed" and d.description == "hit the ground"
    assert d.impact_speed_m_s == float(np.linalg.norm(d.state[3:6])) and d.impact_vertical_speed_m_s == d.state[5]
    assert str(d).startswith(f"crashed at t = {d.time_s:.4f} s: hit the ground at {d.impact_speed_m_s:.2f} m/s")
    back = pickle.loads(pickle.dumps(d))
    assert (back.time_s, back.kind, back.impact_tilt_rad) == (d.time_s, d.kind, d.impact_tilt_rad)
    np.testing.assert_array_equal(back.state, d.state)
    velocity_down = np.zeros(12)
    velocity_down[5] = 5.6
    made = rf.Divergence(time_s=2.3, kind="crashed", state=velocity_down)
    assert (made.impact_speed_m_s, made.impact_vertical_speed_m_s, made.impact_tilt_rad) == (5.6, 5.6, 0.0)
    tilt = rf.Divergence(time_s=1.0, kind="tilt", state=np.zeros(12))
    assert tilt.impact_speed_m_s is None and str(tilt) == "diverged at t = 1.0000 s: tilt beyond the limit"
    with pytest.raises(ValueError, match="^kind: expected one of crashed, non-finite-state, .*, got \"lost\""):
        rf.Divergence(time_s=1.0, kind="lost", state=np.zeros(12))
    with pytest.raises(TypeError, match="^kind: expected a string, got int"):
        rf.Divergence(time_s=1.0, kind=3, state=np.zeros(12))  # type: ignore[arg-type]
    with pytest.raises(ValueError, match=r"^state: expected 12 entries"):
        rf.Divergence(time_s=1.0, kind="tilt", state=np.zeros(3))
    with pytest.raises(ValueError, match="^time_s: must be finite"):
        rf.Divergence(time_s=math.nan, kind="tilt", state=np.zeros(12))


def test_the_old_event_names_work_one_release_with_a_warning() -> None:
    """``rf.Event(time, kind, description, state, impact...)``, ``.time``, ``.reason`` and the
    stored ``description`` / impact arguments: warned, and checked against what is derived."""
    state = np.zeros(12)
    state[5] = 5.6
    with pytest.warns(DeprecationWarning, match="rotorfault.Event is deprecated"):
        event_type = rf.Event  # type: ignore[attr-defined]
    with pytest.warns(DeprecationWarning) as caught:
        old = event_type(2.3, "crashed", "hit the ground", state, impact_speed_m_s=5.6)
    assert {str(w.message).split(" is deprecated")[0] for w in caught} == {"Divergence(description=...)", "Divergence(impact_speed_m_s=...)"}
    assert type(old) is rf.Divergence and isinstance(old, event_type) and old.impact_speed_m_s == 5.6
    with pytest.warns(DeprecationWarning, match=r"Divergence\.time is deprecated.*Divergence\.time_s"):
        assert old.time == 2.3  # type: ignore[attr-defined]
    with pytest.warns(DeprecationWarning, match=r"Divergence\.reason is deprecated.*Divergence\.kind"):
        assert old.reason == "crashed"  # type: ignore[attr-defined]
    with pytest.warns(DeprecationWarning, match=r"Divergence\(reason=\.\.\.\)"):
        assert rf.Divergence(time_s=1.0, reason="tilt", state=np.zeros(12)).kind == "tilt"
    with pytest.warns(DeprecationWarning), pytest.raises(ValueError, match="^impact_speed_m_s: derived from state as 5.6, got 4.0"):
        rf.Divergence(time_s=2.3, kind="crashed", state=state, impact_speed_m_s=4.0)
    with pytest.warns(DeprecationWarning), pytest.raises(ValueError, match="^impact_tilt_rad: only a crashed run has an impact"):
        rf.Divergence(time_s=2.3, kind="tilt", state=state, impact_tilt_rad=0.1)
    with pytest.warns(DeprecationWarning), pytest.raises(ValueError, match='^description: derived from kind "tilt"'):
        rf.Divergence(time_s=2.3, kind="tilt", state=state, description="hit the ground")


def test_the_old_event_takes_its_dataclass_positional_order_with_the_impact() -> None:
    """The old dataclass's order ``Event(time, kind, description, state, impact_speed_m_s,
    impact_vertical_speed_m_s, impact_tilt_rad)`` by position: each value reaches its own field
    (checked against what is derived, warned), ``None`` impacts (the old default) give none, and
    one positional value too many is a ``TypeError`` (it raised a bare signature error before)."""
    state = np.zeros(12)
    state[5] = 5.6
    with pytest.warns(DeprecationWarning, match="rotorfault.Event is deprecated"):
        event_type = rf.Event  # type: ignore[attr-defined]
    with pytest.warns(DeprecationWarning) as caught:
        old = event_type(2.3, "crashed", "hit the ground", state, 5.6, 5.6, 0.0)
    assert {str(w.message).split(" is deprecated")[0] for w in caught} == {
        "Divergence(description=...)", "Divergence(impact_speed_m_s=...)", "Divergence(impact_vertical_speed_m_s=...)",
        "Divergence(impact_tilt_rad=...)"}
    assert type(old) is rf.Divergence and (old.time_s, old.kind, old.impact_speed_m_s, old.impact_tilt_rad) == (2.3, "crashed", 5.6, 0.0)
    with pytest.warns(DeprecationWarning):
        tilt = event_type(1.0, "tilt", "tilt beyond the limit", np.zeros(12), None, None, None)
    assert tilt.kind == "tilt" and tilt.impact_speed_m_s is None
    with pytest.warns(DeprecationWarning), pytest.raises(ValueError, match="^impact_vertical_speed_m_s: derived from state as 5.6, got 1.0"):
        event_type(2.3, "crashed", "hit the ground", state, 5.6, 1.0, 0.0)
    with pytest.raises(TypeError, match="positional"):
        event_type(2.3, "crashed", "hit the ground", state, 5.6, 5.6, 0.0, 1.0)


def test_the_batch_columns_carry_the_trajectorys_names_and_the_old_ones_warn() -> None:
    sim = rf.Simulator(rf.Airframe.preset("quad-x"))
    batch = rf.simulate_batch(sim, [rf.State(position=(0, 0, -1))], 0.05, controllers=rf.lqr_hover(sim, position=(0, 0, -1)))
    columns = batch.columns
    run = batch.trajectories[0]
    for old, new in (("command", "rotor_command"), ("thrust", "rotor_thrust"), ("measured", "recorded_measurements")):
        np.testing.assert_array_equal(getattr(columns, new)[0, : len(run.t)], getattr(run, new))
        with pytest.warns(DeprecationWarning, match=rf"BatchColumns\.{old} is deprecated.*BatchColumns\.{new}"):
            assert getattr(columns, old) is getattr(columns, new)


def test_an_indi_failure_mode_is_the_cores_numbering_rotors_from_1() -> None:
    from rotorfault.control.indi import IndiFailureMode

    c = rf.IndiController(rf.Airframe.preset("ke-quadcopter"), failures=[rf.RotorFault(1, 2.0)], position=(0, 0, -10))
    healthy, one = c.failure_modes()
    assert IndiFailureMode is _rfcore.IndiFailureMode and type(one) is IndiFailureMode
    assert one.failed == (1,) and one.healthy == (2, 3, 4) and healthy.failed == () and len(one.hover_thrust_n) == 4
    assert one == c.failure_modes()[1] and hash(one) == hash(c.failure_modes()[1]) and one != healthy
    assert repr(one).startswith("IndiFailureMode(failed=(1,), healthy=(2, 3, 4), ")


def test_the_estimates_are_the_cores_views_of_the_run() -> None:
    """``Trajectory.estimate`` is the core's ``Estimates`` (a Python dataclass before), its parts
    views of the run's estimate fields; keyword construction and pickling work as before."""
    from rotorfault.flight import Estimates

    sim = rf.Simulator(rf.Airframe.preset("quad-x"), sensing=rf.Sensing(suite="mocap"))
    run = sim.run(rf.State(position=(0, 0, -1)), 0.1, controller=rf.lqr_hover(sim, position=(0, 0, -1)))
    e = run.estimate
    assert Estimates is _rfcore.Estimates and type(e) is Estimates and e.state is run.estimate_state
    assert np.shares_memory(e.position, run.estimate_state) and np.shares_memory(e.attitude_std_rad, run.estimate_std)
    np.testing.assert_array_equal(e.vector, np.hstack([e.position, e.velocity, e.euler, e.omega]))
    np.testing.assert_array_equal(e.quaternion, run.estimate_state[:, 6:10])
    np.testing.assert_array_equal(e.velocity_std_m_s, run.estimate_std[:, 3:6])
    back = pickle.loads(pickle.dumps(e))
    np.testing.assert_array_equal(back.state, e.state)
    assert back.counts.__getnewargs_ex__() == e.counts.__getnewargs_ex__()
    fields = {f: getattr(run, f) for f in _rfcore.Trajectory.FIELDS if f not in _ESTIMATE_FIELDS}
    again = rf.Trajectory(**fields, estimate=e)
    np.testing.assert_array_equal(again.estimate.state, e.state)
    n = len(run.t)
    parts = {f: getattr(e, f) for f in Estimates.FIELDS}
    with pytest.raises(ValueError, match=rf"^velocity: expected {n} rows \(one per time in t\)"):
        Estimates(**{**parts, "velocity": np.zeros((n + 1, 3))})
    with pytest.raises(ValueError, match="^std: expected 15 columns"):
        Estimates(**{**parts, "std": np.zeros((n, 12))})


_ESTIMATE_FIELDS = ("estimate_state", "estimate_euler", "estimate_std", "gyro_saturated", "accel_saturated", "sensing_counts")


def test_a_divergence_prints_as_the_readme_shows() -> None:
    assert repr(rf.Divergence(time_s=0.5, kind="tilt", state=np.zeros(12))) == "Divergence(time_s=0.5, kind='tilt')"


def test_batch_results_hold_the_cores_result_and_read_through_it() -> None:
    """``AcaiBatch`` and ``Allocation`` keep the core's batch in their one slot (no copied fields):
    each field is read from it, the same object on every read (a change a caller makes stays, as
    with the dataclasses they were), with the dataclasses' repr, equality and frozenness."""
    hexa = rf.Airframe.preset("hexa-ppnnpn")
    batch = rf.acai_batch(hexa, [[1, 1, 1, 1, 1, 1], [0, 0, 1, 1, 1, 1]], with_hover=True)
    assert type(batch._core) is _rfcore.AcaiBatch and not hasattr(batch, "__dict__")
    assert batch.acai is batch.acai and batch.acai is batch._core.acai and batch.hover_code.dtype == np.int8
    assert batch.acai.flags.writeable and batch.formula == "eq13" and batch == batch
    assert repr(batch) == "AcaiBatch(acai=array([ 1.12947199, -0.27791389]), hover_code=array([ 1, -1], dtype=int8), formula='eq13')"
    back = pickle.loads(pickle.dumps(batch))
    np.testing.assert_array_equal(back.acai, batch.acai)
    np.testing.assert_array_equal(back.hover_code, batch.hover_code)
    assert back.formula == "eq13" and back.hover_code.dtype == np.int8
    with pytest.raises(AttributeError):
        batch.formula = "facet-margin"  # type: ignore[misc]

    quad = rf.Airframe.preset("ke-quadcopter")
    one, rows = rf.allocate(quad, [7.0, 0.0, 0.0, 0.1]), rf.allocate(quad, np.array([[7.0, 0, 0, 0], [7.0, 0.1, 0, 0]]))
    by_clarabel = rf.allocate(quad, np.array([7.0, 0.0, 0.0, 0.1]), method="clarabel")
    assert type(one._core) is _rfcore.SingleAllocation and type(rows._core) is _rfcore.AllocationBatch
    for a in (one, rows, by_clarabel):
        assert not hasattr(a, "__dict__") and a.commands is a.commands and a == a
        assert a.commands.flags.writeable and a.commands.dtype == np.float64
    assert one.commands.shape == (4,) and one.status == "optimal" and isinstance(one.iterations, int)
    assert by_clarabel.commands.shape == (4,) and by_clarabel.virtual_control.tolist() == [7.0, 0.0, 0.0, 0.1]
    assert by_clarabel.solved_by == "clarabel" and by_clarabel.fallbacks == 0
    assert rows.commands.shape == (2, 4) and rows.status == ("optimal", "optimal") and len(rows.certificate) == 2
    assert repr(one).startswith("Allocation(commands=array([3.2560241, 0.2439759, 3.2560241, 0.2439759]), achieved=")
    with pytest.raises(TypeError, match="made by allocate"):
        rf.allocation.Allocation()


def test_a_failure_row_holds_the_cores_reports_and_reads_through_them() -> None:
    """A failure-table row keeps the core's row (the failed rotors and the core's reports: all
    axes, giving up yaw, the full wrench) in its one slot and reads every field from those
    reports (no copied fields), with the dataclass' repr, equality, hash and frozenness; it
    pickles through the core's row, and a row pickled as the old dataclass is refused by name."""
    phi = np.radians(np.arange(6) * 60.0)  # a hexacopter with its rotors tilted 20 degrees, alternately: fully actuated
    side = np.array([-1.0, 1.0] * 3)[:, None]
    tilted = rf.Airframe.from_rotors(
        position_m=0.275 * np.stack([np.cos(phi), np.sin(phi), 0 * phi], axis=1), spin=["cw", "ccw"] * 3,
        thrust_axis=np.cos(np.radians(20)) * np.array([0, 0, -1.0]) + np.sin(np.radians(20)) * side * np.stack([-np.sin(phi), np.cos(phi), 0 * phi], axis=1),
        max_thrust_n=[6.125] * 6, mass_kg=1.535, inertia_kg_m2=[0.0411, 0.0478, 0.0599], drag_torque_ratio_m=0.1)
    for frame, wrench in ((rf.Airframe.preset("hexa-ppnnpn"), False), (tilted, True)):
        row = rf.failure_table(frame, max_failed=1, formula="facet-margin").case(2)
        core = row._core
        assert type(core) is _rfcore.FailureCase and not hasattr(row, "__dict__") and core.failed == row.failed == (2,)
        assert core.all_axes.efficiency[1] == 0.0 and core.all_axes.axes == "thrust-roll-pitch-yaw" and core.give_up_yaw.give_up_yaw
        assert (row.acai, row.hover, row.verdict) == (core.all_axes.acai, core.all_axes.hover, core.all_axes.verdict)
        assert (row.acai_give_up_yaw, row.effectiveness_rank_give_up_yaw) == (core.give_up_yaw.acai, core.give_up_yaw.effectiveness_rank)
        assert row.acai == rf.controllability(frame, core.all_axes.efficiency, formula="facet-margin").acai
        assert (core.wrench is not None) == wrench and (row.acai_wrench is not None) == wrench
        if wrench:
            assert core.wrench.axes == "wrench" and (row.acai_wrench, row.hover_wrench) == (core.wrench.acai, core.wrench.hover)
        assert repr(row).startswith(f"FailureCase(failed=(2,), controllability_rank={row.controllability_rank}, ")
        back = pickle.loads(pickle.dumps(row))
        assert type(back) is rf.FailureCase and back == row and hash(back) == hash(row) and back._core == core
        with pytest.raises(AttributeError):
            row.acai = 1.0  # type: ignore[misc]
    with pytest.raises(TypeError, match="made by failure_table"):
        rf.FailureCase()
    # The old dataclass's pickle (class, then its fields as a dict, here only `failed`).
    old = b"\x80\x04\x95\x00\x00\x00\x00\x00\x00\x00\x00\x8c#rotorfault.analysis.controllability\x94\x8c\x0bFailureCase\x94\x93\x94)\x81\x94}\x94\x8c\x06failed\x94K\x01\x85\x94sb."
    with pytest.raises(TypeError, match="pickled before .* make it again with failure_table"):
        pickle.loads(old)
    with pytest.raises(ValueError, match=r"^failed\[0\]: rotors are numbered from 1, got 0"):
        _rfcore._failure_case([0], core.all_axes, core.give_up_yaw, None)


def test_an_acai_batch_is_checked_once_by_the_core() -> None:
    """Made from its fields (``dataclasses.replace``, old pickles), an ``AcaiBatch`` is checked by
    the core: one known hover code per value, a known formula."""
    from rotorfault.analysis import AcaiBatch

    assert AcaiBatch([1.0, -2.0], [1, -1], "facet-margin").hover_code.tolist() == [1, -1]
    with pytest.raises(ValueError, match=r"^hover_code\[0\]: must be a hover code"):
        AcaiBatch([1.0], [5])
    with pytest.raises(ValueError, match=r"^hover_code: expected one code per ACAI \(1\), got 2"):
        AcaiBatch([1.0], [1, 1])
    with pytest.raises(TypeError, match="^hover_code: expected a 1-D array of integer codes"):
        AcaiBatch([1.0], [0.5])
    with pytest.raises(ValueError, match='^formula: must be "eq13" or "facet-margin"'):
        AcaiBatch([1.0], [1], "eq12")  # type: ignore[arg-type]
    old = AcaiBatch.__new__(AcaiBatch)  # what loading a pickle of the old dataclass does
    old.__setstate__({"acai": np.array([0.5]), "hover_code": np.array([0], dtype=np.int8), "formula": "eq13"})
    assert old.acai.tolist() == [0.5] and old.hover_code.tolist() == [0]
    with pytest.warns(DeprecationWarning):
        assert dataclasses.replace(old, formula="facet-margin").formula == "facet-margin"

"""Lanzon et al.'s controller in Rust: the commands against an independent Python computation
(the closed-form RFL of ``LanzonVehicle``, the discrete controller stepped in NumPy, eq. (9)),
the outer loop's rotation (31) against (30d)-(30e), bad designs by field name, and closed-loop
flights with stated bounds (Scenario A from Table 2, a short Scenario B)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

import rotorfault as rf
from rotorfault import _rfcore
from rotorfault.control import lanzon as L


@pytest.fixture(scope="module")
def ours() -> L.LanzonDesign:
    return L.design(L.LanzonVehicle(), crossover_rad_s=30.0)


def _random_states(n: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    rows = []
    for _ in range(n):
        s = rf.State(position=rng.normal(size=3), velocity=rng.normal(size=3),
                     euler=rng.uniform(-0.6, 0.6, 3), omega=rng.normal(size=3) + [0, 0, -2.7])
        rows.append(s._packed())
    return np.array(rows)


def test_rust_commands_equal_the_python_derivation(ours: L.LanzonDesign) -> None:
    dt = 1e-3
    v = ours.vehicle
    a, b, c, d = ours.discretise(dt)
    states = _random_states(25, 3)
    times = np.arange(len(states)) * dt
    reference = np.array([0.05, -0.02, 2.9])
    core = L.LanzonController(ours, attitude_reference=reference).core(dt)
    got = _rfcore.replay(core, times, states, 4)
    xi = np.zeros(a.shape[0])
    for k, row in enumerate(states):
        sv = rf.State(position=row[0:3], velocity=row[3:6], quaternion=row[6:10], omega=row[10:13]).vector()
        x = L.LanzonVehicle.paper_state(sv)
        phi, theta, p, q, r = x[0], x[1], x[3], x[4], x[5]
        e = reference - np.array([phi, theta, r])
        w = c @ xi + d @ e
        xi = a @ xi + b @ e
        alpha, beta = v.rfl([phi, theta, p, q, r - v.spin_rate_rad_s])
        u = alpha + beta @ w + [v.mass_kg * v.gravity_m_s2, 0, v.mass_kg * v.gravity_m_s2 * v.drag_torque_ratio_m]
        np.testing.assert_allclose(got[k], v.rotor_thrusts(u), rtol=1e-9, atol=1e-9)


def test_outer_loop_rotation_cancels_the_yaw() -> None:
    # With the working-point model, (31) then (30d)-(30e) give x'' = z1, y'' = z2 at every yaw:
    # check through the commands' set points (D_K = I, no controller state: v = e).
    v = L.LanzonVehicle()
    gains = L.OuterLoopGains(k_p_xy=0.3, k_d_xy=0.0, k_p_z=0.0, k_d_z=0.0, max_tilt_rad=1.0)
    for psi in (0.0, 0.7, 2.5, -1.9):
        state = rf.State(position=(1.0, 0.0, 0.0), euler=(0, 0, -psi), omega=(0, 0, -v.spin_rate_rad_s))
        ctrl = _rfcore.LanzonController(model=v.model, a_k=np.zeros((0, 0)), b_k=np.zeros((0, 3)),
                                        c_k=np.zeros((3, 0)), d_k=np.zeros((3, 3)),
                                        position=[0.0, 0.0, 0.0], outer_loop=gains)
        # With D_K = 0 the linear input is zero and the command is alpha(x) at the state: hover.
        out = _rfcore.replay(ctrl, np.zeros(1), np.array([state._packed()]), 4)[0]
        assert out[1] == 0.0
        # The set points: x error 1 m north = paper x, so z1 = -0.3, z2 = 0; (31): u1 = S z1, u2 = C z1;
        # (30d): C u2 + S u1 = z1, (30e): S u2 - C u1 = 0.
        u1, u2 = math.sin(psi) * -0.3, math.cos(psi) * -0.3
        assert math.cos(psi) * u2 + math.sin(psi) * u1 == pytest.approx(-0.3)
        assert math.sin(psi) * u2 - math.cos(psi) * u1 == pytest.approx(0.0, abs=1e-15)


def test_scenario_a_without_limits_settles(ours: L.LanzonDesign) -> None:
    v = ours.vehicle
    sim = v.simulator(limits=False)
    # 10 m up (Table 2 prints no position; papers.lanzon.SCENARIO_A_HEIGHT_M): it loses 1.6 m.
    x0 = L.LanzonVehicle.simulator_state([-math.pi / 4, math.pi / 4, math.pi / 4, -0.5, 0.5, 2.7, 0, 0, 10, 0, 0, 0])
    run = sim.run(rf.State.from_vector(x0), 10.0, controller=L.LanzonController(ours), faults=[rf.RotorFault(2, 0.0)])
    assert not run.events
    tilt = np.degrees(np.arccos(np.cos(run.euler[:, 0]) * np.cos(run.euler[:, 1])))
    # Measured: below 1 degree after 3.9 s, spin 2.700 rad/s at the end.
    assert tilt[run.t >= 6.0].max() < 1.0
    assert -run.omega[-1, 2] == pytest.approx(2.7, rel=1e-3)
    assert run.rotor_thrust[:, 1].max() == 0.0


def test_scenario_b_reaches_the_setpoint_with_limits() -> None:
    v = L.LanzonVehicle()
    d = L.design(v, crossover_rad_s=30.0)
    sim = v.simulator(limits=True)
    x0 = L.LanzonVehicle.simulator_state([0.075, 0.025, 0.1, 0.03, 0.02, 2.7, 5, 5, 5, 0, 0, 0])
    ctrl = L.LanzonController(d, position=(0.0, 0.0, -1.0))
    run = sim.run(rf.State.from_vector(x0), 30.0, controller=ctrl, faults=[rf.RotorFault(2, 0.0)])
    assert not run.events
    err = np.linalg.norm(run.position[-1] - [0, 0, -1.0])
    assert err < 0.5, err


def test_bad_designs_name_the_field() -> None:
    v = L.LanzonVehicle()
    m = v.model
    z = dict(a_k=np.zeros((0, 0)), b_k=np.zeros((0, 3)), c_k=np.zeros((3, 0)), d_k=np.zeros((3, 3)))
    with pytest.raises(ValueError, match=r"^A_K: the discretised controller must be stable"):
        _rfcore.LanzonController(model=m, **{**z, "a_k": np.eye(1) * 1.01, "b_k": np.zeros((1, 3)), "c_k": np.zeros((3, 1))})
    with pytest.raises(ValueError, match=r"^C_K: expected 3 x 0"):
        _rfcore.LanzonController(model=m, **{**z, "c_k": np.zeros((2, 0))})
    with pytest.raises(ValueError, match=r"^D_K\[0, 1\]: must be finite"):
        _rfcore.LanzonController(model=m, **{**z, "d_k": np.array([[0, np.inf, 0], [0, 0, 0], [0, 0, 0.0]])})
    with pytest.raises(ValueError, match=r"^outer_loop.max_tilt_rad: must be in"):
        _rfcore.LanzonController(model=m, position=[0, 0, 0], outer_loop=_rfcore.OuterLoopGains(max_tilt_rad=2.0), **z)
    with pytest.raises(ValueError, match=r"^model.mass_kg: must be > 0"):
        _rfcore.LanzonModel(mass_kg=-1.0)
    with pytest.raises(ValueError, match="position, attitude_reference: give one"):
        _rfcore.LanzonController(model=m, position=[0, 0, 0], attitude_reference=[0, 0, 0], **z)
    with pytest.raises(ValueError, match="dt_s: must be > 0"):
        L.design(v).discretise(0.0)
    with pytest.raises(TypeError, match="design: expected a LanzonDesign"):
        L.LanzonController("paper")  # type: ignore[arg-type]


def test_model_defaults_come_from_the_core() -> None:
    core = _rfcore.LanzonModel()
    v = L.LanzonVehicle()
    for name in ("mass_kg", "inertia_zz_kg_m2", "rotational_drag_n_m_s", "linear_drag_n_s_m"):
        assert getattr(core, name) == getattr(v, name)


@pytest.mark.parametrize("field", ["mass_kg", "gravity_m_s2", "inertia_xx_kg_m2", "inertia_zz_kg_m2", "arm_length_m",
                                   "drag_torque_ratio_m", "rotational_drag_n_m_s", "max_thrust_n", "rate_limit_n_s"])
@pytest.mark.parametrize("value", [math.inf, -math.inf, math.nan, 0.0, -1.0])
def test_vehicle_parameters_finite_and_positive(field: str, value: float) -> None:
    # One validation, the core's LanzonVehicle::check, errors naming vehicle.<field>.
    rule = "must be finite" if not math.isfinite(value) else "must be > 0"
    with pytest.raises(ValueError, match=rf"^vehicle\.{field}: {rule}, got"):
        L.LanzonVehicle(**{field: value})


@pytest.mark.parametrize("field", ["mass_kg", "linear_drag_n_s_m", "rotational_drag_n_m_s"])
def test_vehicle_and_core_model_say_the_same_rule(field: str) -> None:
    # The vehicle's message is the core model's, naming the object the caller made.
    with pytest.raises(ValueError) as vehicle:
        L.LanzonVehicle(**{field: -1.0})
    with pytest.raises(ValueError) as model:
        _rfcore.LanzonModel(**{field: -1.0})
    assert str(vehicle.value) == str(model.value).replace("model.", "vehicle.", 1)
    with pytest.raises(TypeError, match=rf"^vehicle\.{field}: expected a real number"):
        L.LanzonVehicle(**{field: "1"})


@pytest.mark.parametrize("field", ["mass_kg", "inertia_zz_kg_m2", "arm_length_m", "rotational_drag_n_m_s"])
@pytest.mark.parametrize("value", [1e-310, 1e300])
def test_vehicle_scales_in_the_cores_range_at_construction(field: str, value: float) -> None:
    # Subnormal and absurd scales: refused when the vehicle is built, by the core's rule.
    with pytest.raises(ValueError, match=rf"^vehicle\.{field}: must lie in \[1e-15, 1e15\]"):
        L.LanzonVehicle(**{field: value})


@pytest.mark.parametrize("field", ["linear_drag_n_s_m", "rotor_inertia_kg_m2", "thrust_coefficient_n_s2"])
@pytest.mark.parametrize("value", [math.inf, math.nan, -1e-9])
def test_vehicle_drag_and_rotor_parameters_finite_and_non_negative(field: str, value: float) -> None:
    rule = "must be finite" if not math.isfinite(value) else "must be >= 0"
    with pytest.raises(ValueError, match=rf"^vehicle\.{field}: {rule}, got"):
        L.LanzonVehicle(**{field: value})


def test_outer_loop_and_design_parameters_are_checked_at_construction() -> None:
    # The outer loop is checked when built (the core's rules, one source), not when first flown.
    with pytest.raises(ValueError, match=r"^outer_loop.k_p_xy: must be finite, got inf"):
        L.OuterLoopGains(k_p_xy=math.inf)
    with pytest.raises(ValueError, match=r"^outer_loop.max_tilt_rad: must be in \(0, pi/2\)"):
        L.OuterLoopGains(max_tilt_rad=2.0)
    with pytest.raises(ValueError, match=r"^outer_loop.max_vertical_accel_m_s2: must be finite"):
        L.OuterLoopGains(max_vertical_accel_m_s2=math.nan)
    with pytest.raises(TypeError, match=r"^outer_loop.k_d_z: expected a real number"):
        L.OuterLoopGains(k_d_z="1")  # type: ignore[arg-type]
    # design(): every parameter before any work.
    for kwargs, message in ((dict(crossover_rad_s=math.inf), r"^crossover_rad_s: must be finite and > 0"),
                            (dict(low_gain_db=math.nan), r"^low_gain_db: must be finite and > 0"),
                            (dict(rolloff_factor=1.0), r"^rolloff_factor: must be finite and > 1"),
                            (dict(factor=math.inf), r"^factor: must be finite and > 1"),
                            (dict(channel_gain=(1.0, math.inf, 1.0)), r"^channel_gain: must be finite and > 0")):
        with pytest.raises(ValueError, match=message):
            L.design(**kwargs)  # type: ignore[arg-type]
    from rotorfault.papers import lanzon as P

    with pytest.raises(ValueError, match=r"^crossover_rad_s: must be finite and > 0"):
        P.DesignCase("x", "bad", math.nan, True)
    with pytest.raises(ValueError, match=r"^channel_gain: expected 3 finite numbers > 0"):
        P.DesignCase("x", "bad", 30.0, True, channel_gain=(1.0, 0.0, 1.0))


def test_controller_matrices_the_schur_iteration_cannot_take_are_refused_not_hung() -> None:
    # Design (c) discretised by Tustin in the realisation python-control's c2d returns: nalgebra's
    # unbounded Schur iteration never converged on this A_K and the constructor hung (issue 25).
    # The core now caps the iteration and says so; discretise() gives real Schur coordinates,
    # which the core takes.
    import control as ct

    d = L.design(crossover_rad_s=30.0)
    k = ct.c2d(d.controller, 1e-3, method="tustin")
    a, b, c, dd = (np.ascontiguousarray(np.asarray(m, dtype=float)) for m in (k.A, k.B, k.C, k.D))
    with pytest.raises(ValueError, match=r"^A_K: the Schur decomposition \(eigenvalues\) did not converge within its cap of"):
        _rfcore.LanzonController(model=d.vehicle.model, a_k=a, b_k=b, c_k=c, d_k=dd, attitude_reference=[0, 0, 2.7])
    a2, b2, c2, d2 = d.discretise(1e-3)
    assert np.allclose(np.tril(a2, -2), 0.0, atol=0.0)  # quasi-triangular
    _rfcore.LanzonController(model=d.vehicle.model, a_k=a2, b_k=b2, c_k=c2, d_k=d2, attitude_reference=[0, 0, 2.7])
    # The same controller: the two realisations have the same frequency response.
    from rotorfault.control.realisation import frequency_response, state_space

    w = np.linspace(0.1, 3000.0, 7)
    r2 = frequency_response(state_space(a2, b2, c2, d2, 1e-3), w)
    r1 = frequency_response(state_space(a, b, c, dd, 1e-3), w)
    for k_ in range(w.size):  # normwise, 1e-9 of the response at that frequency
        assert np.linalg.norm(r2[k_] - r1[k_], 2) <= 1e-9 * np.linalg.norm(r1[k_], 2)


def _hold_5_m(vehicle: L.LanzonVehicle, gains: L.OuterLoopGains, duration_s: float, **sim: object) -> np.ndarray:
    """Lanzon's controller (designed on the nominal vehicle) holding 5 m up with rotor 2 failed:
    the position error over the last 10 s of the flight."""
    nominal = L.LanzonVehicle()
    ctrl = L.LanzonController(L.design(nominal, crossover_rad_s=30.0), position=(0.0, 0.0, -5.0), outer_loop=gains)
    x0 = L.LanzonVehicle.simulator_state([0, 0, 0, 0, 0, nominal.spin_rate_rad_s, 0, 0, 5, 0, 0, 0])
    run = vehicle.simulator(limits=True, **sim).run(rf.State.from_vector(x0), duration_s, controller=ctrl, faults=[rf.RotorFault(2, 0.0)])  # type: ignore[arg-type]
    assert not run.events
    return run.position[run.t >= duration_s - 10.0] - [0.0, 0.0, -5.0]


PID = L.OuterLoopGains(k_i_xy=0.03, k_i_z=0.1)


def test_integral_action_removes_the_steady_error_of_a_mass_error() -> None:
    """10 % more mass than designed for: the paper's PD outer loop sinks to the steady error
    0.1 g / k_p_z = 1.96 m (measured 1.964 m); with integral action the error vanishes
    (measured 3e-6 m)."""
    assert L.OuterLoopGains().k_i_xy == L.OuterLoopGains().k_i_z == 0.0  # the paper's loop is the default
    heavy = L.LanzonVehicle().replace(mass_kg=0.55)
    pd = _hold_5_m(heavy, L.OuterLoopGains(), 60.0)
    assert np.abs(pd[:, 2]).min() == pytest.approx(0.1 * 9.81 / 0.5, rel=0.01)
    assert np.abs(_hold_5_m(heavy, PID, 60.0)[:, 2]).max() < 1e-3


def test_integral_action_removes_the_steady_error_of_a_constant_wind() -> None:
    """A 1 m/s wind on the linear drag: PD drifts 0.8 m downwind (measured), PID holds."""
    pd = _hold_5_m(L.LanzonVehicle(), L.OuterLoopGains(), 90.0, wind=(1.0, 0.0, 0.0))
    pid = _hold_5_m(L.LanzonVehicle(), PID, 90.0, wind=(1.0, 0.0, 0.0))
    assert np.hypot(pd[:, 0], pd[:, 1]).min() > 0.5
    assert np.hypot(pid[:, 0], pid[:, 1]).max() < 1e-2


def test_integral_gains_are_checked() -> None:
    m = _rfcore.LanzonModel()
    z = {"a_k": np.zeros((0, 0)), "b_k": np.zeros((0, 3)), "c_k": np.zeros((3, 0)), "d_k": np.zeros((3, 3))}
    for field, bad in (("k_i_z", -0.1), ("k_i_xy", math.nan), ("integral_limit_m_s", 0.0)):
        with pytest.raises(ValueError, match=rf"^outer_loop.{field}"):
            _rfcore.LanzonController(model=m, position=[0, 0, 0], outer_loop=_rfcore.OuterLoopGains(**{field: bad}), **z)

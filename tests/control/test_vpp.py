"""Wang, Gross, Zhao (2020): VPP quadcopters with a failed propeller. Every number of Sec. 3.1
and the ranks of Sec. 3.3-3.4 are tests here (paper numbers: ../shared/papers/README.md)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import rotorfault as rf
from rotorfault import vpp

K1, K2, K3, K4 = 5e-7, 1e-8, 2e-10, 4e-7
MG = 10.0


def r_of(omega2: float) -> float:
    """Wang eq. (14), written out independently of the module."""
    return 2 * (K2 * omega2**2 + K3 / K1**2 * (MG / (2 * omega2)) ** 2 + K4 * MG / (2 * K1 * omega2))


@pytest.fixture(scope="module")
def wang() -> vpp.VppVehicle:
    return vpp.preset("wang")


def test_preset_holds_the_papers_numbers_and_documented_choices(wang: vpp.VppVehicle) -> None:
    assert wang.coefficients == (K1, K2, K3, K4)
    assert wang.airframe.mass_kg == 1.0 and wang.airframe.gravity_m_s2 == 10.0
    assert np.all(wang.airframe.arm_length_m == 0.35)
    assert tuple(wang.actuator.speed_bounds) == (0.0, 10_000.0)
    assert tuple(wang.actuator.pitch_bounds) == (-0.26, 0.26)
    # 10 Hz first-order actuators on both channels (Sec. 4.2), the core's default.
    assert wang.actuator.speed_time_constant_s == pytest.approx(1 / (20 * math.pi), rel=1e-15)
    default = rf.VariablePitchActuator(k=wang.coefficients, speed_bounds=(0, 1), pitch_bounds=(0, 1))
    assert wang.actuator.pitch_time_constant_s == default.pitch_time_constant_s
    assert wang.drag.linear_n_s_m == 0.25
    # Thrust box: k1 omega_max^2 alpha_max = 13 N either way.
    assert np.all(wang.airframe.max_thrust_n == 13.0) and np.all(wang.airframe.min_thrust_n == -13.0)


def test_speed_and_pitch_channels_lag_separately(wang: vpp.VppVehicle) -> None:
    """A pitch step with a slow speed channel: thrust follows the pitch's own lag (exact
    first-order response, independent closed form), the speed barely moves."""
    act = rf.VariablePitchActuator(
        k=wang.coefficients, speed_bounds=(0, 10_000), pitch_bounds=(-0.26, 0.26),
        speed_time_constant_s=1.0, pitch_time_constant_s=0.01, pitch_rate_limit_rad_s=math.inf,
    )
    sim = rf.Simulator(wang.airframe, actuator=act, dt_s=0.001)
    start = np.tile([8000.0, 0.0], 4)
    step = np.tile([8000.0, 0.1], 4)
    run = sim.run(duration_s=0.02, controller=rf.OpenLoop([0.0], step[None, :]), initial_command=start)
    t = 0.01
    k = int(round(t / 0.001))
    thrust = run.rotor_thrust[k, 0]
    assert thrust == pytest.approx(K1 * 8000.0**2 * 0.1 * (1 - math.exp(-1.0)), rel=1e-9)
    with pytest.raises(ValueError, match="actuator.pitch_rate_limit_rad_s"):
        rf.Simulator(wang.airframe, actuator=rf.VariablePitchActuator(
            k=wang.coefficients, speed_bounds=(0, 1e4), pitch_bounds=(-0.26, 0.26), pitch_rate_limit_rad_s=0.0)
        ).state_derivative(np.zeros(12), np.zeros(8))


def test_trim_reproduces_wang_at_omega3_9000(wang: vpp.VppVehicle) -> None:
    trim = vpp.trim(wang, failed=(1,), speeds={3: 9000.0})
    assert round(trim.speed(2)) == 6355 and round(trim.speed(4)) == 6355
    assert round(trim.pitch(2), 4) == 0.2476 and round(trim.pitch(4), 4) == 0.2476
    assert trim.pitch(3) == 0.0 and trim.speed(1) == 0.0 and trim.pitch(1) == 0.0
    assert trim.free_rotors == (2, 4) and trim.fixed_rotors == (3,)
    # Independent check: eq. (14) balances, and the simulator's own derivative vanishes.
    assert K2 * 9000.0**2 == pytest.approx(r_of(trim.speed(2)), rel=1e-12)
    assert trim.residual < 1e-8


def test_feasible_ranges_are_wangs(wang: vpp.VppVehicle) -> None:
    window = vpp.feasible_speeds(wang, failed=(1,))
    lo2, hi2 = window.free_speed_range
    lo3, hi3 = window.fixed_speed_range
    # omega_2 in [6201, 7067]: the lower end is the pitch bound (eq. (10) at alpha = 0.26).
    assert math.floor(lo2) == 6201 and lo2 == pytest.approx(math.sqrt(MG / 2 / (K1 * 0.26)), rel=1e-12)
    # omega_3 in [8782, 10000]: the paper evaluates r at the rounded 6201 (r = 0.7714) and
    # truncates sqrt(0.7714 / k2) = 8782.9.
    assert math.floor(math.sqrt(round(r_of(6201.0), 4) / K2)) == 8782
    assert lo3 == pytest.approx(math.sqrt(r_of(lo2) / K2), rel=1e-12) and hi3 == pytest.approx(10_000.0, abs=1e-4)
    # Paper's 7067 is not a root of r = 1: r(7067) = 1.0008 (independent evaluation); the root is
    # 7064.2 (0.04 % lower), what we return (README decisions).
    assert r_of(7067.0) > 1.0005
    assert r_of(hi2) == pytest.approx(1.0, rel=1e-12) and round(hi2, 1) == 7064.2
    # r(omega_2) in [0.7714, 2] over omega_2 in [6201, 10000].
    assert round(r_of(6201.0), 4) == 0.7714 and round(r_of(10_000.0), 2) == 2.0
    assert window.free_torque_range_nm[0] == pytest.approx(r_of(lo2), rel=1e-12)
    assert window.torque_range_nm[1] == pytest.approx(1.0, rel=1e-12)


@pytest.mark.parametrize("failed", [(1,), (2,), (3,), (4,), ()])
def test_trim_for_any_failed_propeller(wang: vpp.VppVehicle, failed: tuple[int, ...]) -> None:
    trim = vpp.trim(wang, failed=failed)
    assert trim.residual < 1e-8
    assert np.all(np.abs(trim.command[1::2]) <= 0.26) and np.all(trim.command[0::2] <= 10_000)


def test_no_trim_names_the_bound(wang: vpp.VppVehicle) -> None:
    with pytest.raises(ValueError, match=r"speeds\[3\]: 8000.0? .*no trim|propellers \[3\] at \[8000.0\].*no trim"):
        vpp.trim(wang, failed=(1,), speeds={3: 8000.0})
    with pytest.raises(ValueError, match=r"speeds\[3\]: 12000.0 lies outside speed_bounds"):
        vpp.trim(wang, failed=(1,), speeds={3: 12_000.0})
    with pytest.raises(ValueError, match=r"speeds\[2\]: 5000.0 is below 6201.7"):
        vpp.trim(wang, failed=(1,), speeds={2: 5000.0, 4: 6300.0})
    with pytest.raises(ValueError, match=r"failed: with propeller\(s\) \[1, 2\] failed no thrusts"):
        vpp.trim(wang, failed=(1, 2))
    with pytest.raises(ValueError, match="failed: propeller 5 does not exist"):
        vpp.trim(wang, failed=(5,))
    with pytest.raises(ValueError, match=r"speeds\[1\]: propeller 1 is failed"):
        vpp.trim(wang, failed=(1,), speeds={1: 9000.0})
    with pytest.raises(TypeError, match="failed"):
        vpp.trim(wang, failed=1)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="position"):
        vpp.trim(wang, position=(0, 0, math.nan))


def test_linearisation_is_the_models_jacobian(wang: vpp.VppVehicle) -> None:
    """Against an independent central difference (step 1e-4 relative, our own loop) and against
    Wang's printed structure where it is consistent with the model."""
    trim = vpp.trim(wang, failed=(1,), speeds={3: 9000.0})
    model = vpp.linearize(wang, trim)
    sim = wang.simulator(failed=(1,))
    f = lambda x, u: sim.state_derivative(x, u)  # noqa: E731
    for j, col in enumerate(model.command_columns):
        h = 1e-4 * max(1.0, abs(trim.command[col]))
        e = np.zeros(8)
        e[col] = h
        fd = (f(trim.state, trim.command + e) - f(trim.state, trim.command - e)) / (2 * h)
        np.testing.assert_allclose(model.B[:, j], fd, rtol=1e-6, atol=1e-9 * np.max(np.abs(fd)))
    # Analytic entries (eq. (1)-(4) in our FRD frame, z down): d(p')/d(alpha_3) = l k1 omega_3^2 / Ix
    # (Wang's h3 l / Ix), d(w')/d(alpha_3) = -k1 omega_3^2 / m, d(q')/d(alpha_3) = 0.
    b = dict(zip(model.input_labels, model.B.T))
    assert b["alpha_3"][9] == pytest.approx(0.35 * K1 * 9000.0**2 / 0.03, rel=1e-7)
    assert b["alpha_3"][5] == pytest.approx(-K1 * 9000.0**2, rel=1e-7)
    assert b["alpha_3"][10] == 0.0 and b["omega_3"][9] == 0.0  # alpha_3 = 0: no roll from omega_3
    # d(w')/d(omega_2) = -2 k1 omega_2 alpha_2 / m (z down): Wang's p_2; his printed B puts
    # k1 omega_i^2 / m there in the omega columns, which is d/d(alpha) -- the misprint.
    assert b["omega_2"][5] == pytest.approx(-2 * K1 * trim.speed(2) * trim.pitch(2), rel=1e-7)
    assert b["alpha_2"][5] == pytest.approx(-K1 * trim.speed(2) ** 2, rel=1e-7)
    # A: g couples attitude to velocity (E of Sec. 3.2), drag on the diagonal.
    assert model.A[3, 7] == pytest.approx(-10.0, rel=1e-9) and model.A[4, 6] == pytest.approx(10.0, rel=1e-9)
    assert model.A[3, 3] == pytest.approx(-0.25, rel=1e-9)


def test_controllability_vpp_12_fixed_pitch_8(wang: vpp.VppVehicle) -> None:
    trim = vpp.trim(wang, failed=(1,), speeds={3: 9000.0})
    result = vpp.controllability(vpp.linearize(wang, trim))
    assert result.rank == 12 and result.uncontrollable_states == ()
    fixed = vpp.fixed_pitch(wang)
    ftrim = vpp.fixed_pitch_trim(fixed, failed=(1,))
    assert ftrim.residual < 1e-12 and ftrim.speed(3) == 0.0
    fixed_result = vpp.controllability(vpp.linearize(fixed, ftrim, pitch_fixed=True))
    assert fixed_result.rank == 8
    assert set(fixed_result.uncontrollable_states) == {"y", "v", "phi", "p"}
    # Wang 3.4: y, phi, p, v -- each a direction of its own (the span of four state axes).
    assert [d.text for d in fixed_result.uncontrollable_directions] == [
        "east position y", "east velocity v", "roll phi", "roll rate p"
    ]
    for d, j in zip(fixed_result.uncontrollable_directions, (1, 4, 6, 9)):
        np.testing.assert_array_equal(d.coefficients, np.eye(12)[j])


def test_healthy_fixed_pitch_names_its_two_uncontrollable_directions(wang: vpp.VppVehicle) -> None:
    """Healthy, Sec. 3.4's layout is rank 10 although no single state is uncontrollable: opposite
    motors spin opposite ways, so the yaw torque is a fixed combination of the roll and pitch
    torques, c / l (tau_p - tau_q) up to sign with c = d(tau)/d(f), and r - (c J_x / (l J_z)) (p + q)
    (and its angle) cannot be moved. Independent check: that coefficient from the preset's numbers
    and eq. (3) differentiated at alpha = 0.26, and w^T A^k B = 0 for the directions."""
    fixed = vpp.fixed_pitch(wang)
    model = vpp.linearize(fixed, vpp.fixed_pitch_trim(fixed, failed=()), pitch_fixed=True)
    result = vpp.controllability(model)
    assert result.rank == 10
    angle, rate = result.uncontrollable_directions
    assert angle.text == "yaw psi together with phi and theta: 0.132 phi + 0.132 theta - psi"
    assert rate.text == "yaw rate r together with p and q: 0.132 p + 0.132 q - r"
    omega, alpha = math.sqrt(2.5 / (K1 * 0.26)), 0.26  # each rotor carries m g / 4
    # d(tau)/d(omega) over d(f)/d(omega) at the trim (eq. (3)): the torque a thrust change brings.
    ratio = (2 * K2 * omega + 2 * K3 * omega * alpha**2 + K4 * alpha) / (2 * K1 * alpha * omega)
    coefficient = ratio / 0.35 * 0.03 / 0.05
    np.testing.assert_allclose(rate.coefficients[9:], [coefficient, coefficient, -1.0], rtol=1e-6)
    np.testing.assert_allclose(angle.coefficients[6:9], [coefficient, coefficient, -1.0], rtol=1e-6)
    power = model.B
    for _ in range(12):
        for d in (angle, rate):
            assert np.max(np.abs(d.coefficients @ power)) <= 1e-12 * np.max(np.abs(power))
        power = model.A @ power
    assert set(result.uncontrollable_states) == {"phi", "theta", "psi", "p", "q", "r"}


def test_scale_free_rank_is_exposed_and_scale_free() -> None:
    m = np.diag([1e4, 1e-1, 1e4, 1e-12])
    assert rf._rfcore.scale_free_rank(m) == 4
    assert np.linalg.matrix_rank(m) == 3  # the plain SVD threshold reads 1e-12 as zero
    with pytest.raises(ValueError, match="matrix: must be finite"):
        rf._rfcore.scale_free_rank(np.array([[math.nan]]))


def test_lqr_gain_checks(wang: vpp.VppVehicle) -> None:
    trim = vpp.trim(wang, failed=(1,), speeds={3: 9000.0})
    with pytest.raises(ValueError, match=r"r: expected a 6x6 matrix, got shape \(8, 8\)"):
        vpp.lqr(wang, trim, r=np.eye(8))
    with pytest.raises(ValueError, match=r"q\[0, 0\]: must be finite, got nan"):
        vpp.lqr(wang, trim, q=np.full((12, 12), math.nan))
    feedback = vpp.lqr(wang, trim)
    assert feedback.gain.shape == (8, 12) and np.all(feedback.gain[0:2] == 0.0)


def test_lqr_holds_hover_with_propeller_1_failed_in_rust(wang: vpp.VppVehicle) -> None:
    """Designed in Python, flown in Rust at 1 kHz with the 10 Hz actuators: from (0.5, -0.5, -0.3) m
    off the trim (10 m above the ground) the VPP quadcopter with propeller 1 dead returns.
    Measured: 2.2e-4 m left after 10 s, largest roll/pitch 0.036 rad; bounds 1e-3 m and 0.05 rad."""
    trim = vpp.trim(wang, failed=(1,), speeds={3: 9000.0}, position=(0, 0, -10))
    feedback = vpp.lqr(wang, trim)
    base = wang.simulator(failed=(1,))
    sim = rf.Simulator(base.airframe, actuator=wang.actuator, drag=wang.drag, dt_s=0.001)
    run = sim.run(rf.State(position=(0.5, -0.5, -10.3)), duration_s=10.0, controller=feedback)
    assert np.linalg.norm(run.position[-1] - (0, 0, -10)) < 1e-3
    assert np.max(np.abs(run.euler[:, :2])) < 0.05


def test_printed_numbers_for_the_report() -> None:
    """papers.wang.printed_numbers(): the rows the reproduce-all report shows. Every number
    passes except the three the README's decisions explain (the paper's 7067 is not a root of
    r = 1; its 8782 and 0.7714 come from the rounded 6201), each of which carries its note."""
    from rotorfault.papers import wang as wang_paper

    rows = wang_paper.printed_numbers()
    assert len(rows) == 11
    differs = {r.quantity for r in rows if r.status == "differs"}
    assert differs == {"highest feasible omega2 (r = 1)", "lowest feasible omega3", "lowest r(omega2)"}
    assert all(r.note for r in rows if r.status == "differs")
    assert {r.quantity: r.ours for r in rows}["controllability rank, VPP, propeller 1 failed (the paper's inputs, omega_3 held)"] == 12


@pytest.mark.parametrize(
    ("field", "value", "error", "message"),
    [
        ("drag", {"linear_n_s_m": -1.0}, ValueError, r"^drag.linear_n_s_m: must be >= 0"),
        ("drag", {"linear_n_s_m": math.inf}, ValueError, r"^drag.linear_n_s_m: must be finite"),
        ("actuator.k", (0.0, K2, K3, K4), ValueError, r"^actuator.k: k1 .* must be > 0, got 0.0"),
        ("actuator.k", (math.nan, K2, K3, K4), ValueError, r"^actuator.k1: must be finite"),
        ("actuator.k", (K1, -K2, K3, K4), ValueError, r"^actuator.k: k2 and k3 .* must be >= 0"),
        ("actuator.speed_bounds", (0.0, math.inf), ValueError, r"^actuator.speed_bounds: must be finite"),
        ("actuator.pitch_bounds", (-0.26, 0.0), ValueError, r"^actuator.pitch_bounds: the upper bound must be > 0"),
        ("actuator.speed_time_constant_s", -1.0, ValueError, r"^actuator.speed_time_constant_s: must be >= 0"),
        ("airframe", "wang-vpp", TypeError, r"^airframe: expected Airframe, got str"),
        ("airframe", rf.Airframe.preset("hexa-pnpnpn"), ValueError, r"^airframe: a VPP quadcopter has 4 propellers"),
    ],
)
def test_vpp_vehicle_is_checked_once_when_built(wang: vpp.VppVehicle, field: str, value: object, error: type, message: str) -> None:
    """Every VppVehicle (a preset, vpp.fixed_pitch, a dataclasses.replace) is checked when built:
    finite, and positive where physical (k1, the upper speed and pitch bounds), before any trim."""
    import dataclasses

    with pytest.raises(error, match=message):
        if field == "drag":  # Drag is the core's class: its values are checked when it is made
            dataclasses.replace(wang, drag=rf.Drag(**value))  # type: ignore[arg-type]
        elif field.startswith("actuator."):
            dataclasses.replace(wang, actuator=wang.actuator.replace(**{field.split(".")[1]: value}))
        else:
            dataclasses.replace(wang, **{field: value})

"""Hover trims, linearisation and LQR design at their limits (issue 19, items 3-5): trims in wind
and drag against closed forms and a scipy root solve of the simulator's own dynamics, rotors forced
onto a thrust bound against the null space of B_f, one-sided derivatives at a bound against the
analytic thrust column, LQR refusals, and the Euler-angle singularity against the analytic
Jacobian of the Euler rates. Tolerances are stated at each check."""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.linalg
import scipy.optimize

import rotorfault as rf

SETPOINT = (0.0, 0.0, -10.0)


def readme_simulator() -> rf.Simulator:
    # The README's simulator example without noise: quad-x, linear drag 0.1 N s/m, 2 m/s wind.
    return rf.Simulator(
        rf.Airframe.preset("quad-x"), dt_s=1 / 400, substeps=4,
        actuator=rf.FixedPitchActuator(time_constant_s=0.025, rate_limit_n_s=50.0),
        drag=rf.Drag(linear_n_s_m=0.1), wind=(2.0, 0.0, 0.0),
    )


# -- item 4: trims with the aerodynamics the simulator flies -------------------------------------


def test_trim_in_wind_matches_the_closed_form_and_is_an_equilibrium() -> None:
    sim = readme_simulator()
    frame = sim.airframe
    trim = rf.hover_trim(sim, position=SETPOINT)
    assert isinstance(trim, rf.HoverTrim) and trim.saturated_rotors == () and not trim.saturated
    # Closed form: the wind blows towards north and its drag k_t w pushes the vehicle north, so
    # it pitches nose-up by atan(k_t w / (m g)) to tilt its thrust south; |T| = |(k_t w, m g)|.
    weight, drag = frame.mass_kg * frame.gravity_m_s2, 0.1 * 2.0
    assert trim.state[7] == pytest.approx(math.atan2(drag, weight), rel=1e-12)
    assert trim.state[6] == 0.0 and trim.state[8] == 0.0
    np.testing.assert_allclose(trim.command, math.hypot(weight, drag) / 4, rtol=1e-12)
    np.testing.assert_array_equal(trim.state[0:3], SETPOINT)
    # The old trim (level, m g / 4 each) left v' = 0.130 m/s^2; this one leaves rounding only.
    derivative = sim.state_derivative(trim.state, trim.command)
    assert trim.residual == pytest.approx(float(np.linalg.norm(derivative)), abs=1e-15)
    assert trim.residual < 1e-13


@pytest.mark.parametrize(
    ("drag", "wind", "yaw"),
    [
        (rf.Drag(linear_n_s_m=0.1), (2.0, 0.0, 0.0), 0.0),
        (rf.Drag(linear_n_s_m=0.3, quadratic_n_s2_m2=0.05), (3.0, -4.0, 1.0), 0.7),
        (rf.Drag(quadratic_n_s2_m2=0.02, rotational_n_m_s=1e-3), (-6.0, 2.0, -1.5), -2.5),
    ],
)
def test_trim_agrees_with_a_root_solve_of_the_simulator(drag: rf.Drag, wind: tuple[float, float, float], yaw: float) -> None:
    sim = rf.Simulator(rf.Airframe.preset("quad-x"), drag=drag, wind=wind)
    trim = rf.hover_trim(sim, position=SETPOINT, yaw=yaw)

    def residual(z: np.ndarray) -> np.ndarray:
        x = np.zeros(12)
        x[0:3], x[6], x[7], x[8] = SETPOINT, z[0], z[1], yaw
        d = sim.state_derivative(x, z[2:])
        return np.concatenate([d[3:6], d[9:12]])  # v' = 0, omega' = 0: 6 equations, 6 unknowns

    start = np.array([0.0, 0.0, *[sim.airframe.hover_thrust_n / 4] * 4])
    solved = scipy.optimize.root(residual, start, method="hybr", options={"xtol": 1e-13})
    assert np.abs(residual(solved.x)).max() < 1e-12  # an equilibrium to rounding, whatever hybr's status
    np.testing.assert_allclose(trim.state[6:8], solved.x[:2], rtol=0, atol=1e-12)
    np.testing.assert_allclose(trim.command, solved.x[2:], rtol=1e-11)
    assert trim.residual < 1e-12


def test_lqr_holds_its_setpoint_in_wind() -> None:
    sim = readme_simulator()
    lqr = rf.lqr_hover(sim, position=SETPOINT)
    trim = rf.hover_trim(sim, position=SETPOINT)
    # Started at the trim, the closed loop stays there (the old trim drifted to a 0.196 m offset).
    at_trim = sim.run(rf.State.from_vector(trim.state), 10.0, controller=lqr)
    assert np.abs(at_trim.position - SETPOINT).max() < 1e-9
    # Started level, it settles on the setpoint: a stable linear loop with no constant error left.
    level = sim.run(rf.State(position=SETPOINT), 20.0, controller=lqr)
    assert not level.diverged
    assert np.linalg.norm(level.position[-1] - SETPOINT) < 1e-6
    assert level.euler[-1, 1] == pytest.approx(trim.state[7], abs=1e-8)


def test_trim_reports_every_rotor_at_full_thrust_and_refuses_beyond() -> None:
    frame = rf.Airframe.preset("quad-x")
    weight = frame.mass_kg * frame.gravity_m_s2
    # A wind whose drag needs exactly the four rotors' full thrust: all four on their upper bound.
    limit = math.sqrt(float(frame.max_thrust_n.sum()) ** 2 - weight**2)
    sim = rf.Simulator(frame, drag=rf.Drag(linear_n_s_m=1.0), wind=(limit, 0.0, 0.0))
    trim = rf.hover_trim(sim)
    assert trim.saturated_rotors == (1, 2, 3, 4)
    np.testing.assert_array_equal(trim.command, frame.max_thrust_n)
    with pytest.raises(ValueError, match=r"rotor\(s\) 1, 2, 3, 4 on a thrust bound"):
        rf.lqr_hover(sim)
    stronger = rf.Simulator(frame, drag=rf.Drag(linear_n_s_m=1.0), wind=(1.01 * limit, 0.0, 0.0))
    with pytest.raises(ValueError, match="quad-x: hover needs .* N with zero torque, which no thrusts within the rotors' bounds give"):
        rf.hover_trim(stronger)


# -- item 3: a rotor on its bound ---------------------------------------------------------------


@pytest.fixture(scope="module")
def hexa_one_failed() -> rf.Simulator:
    return rf.Simulator(rf.Airframe.preset("hexa-pnpnpn").with_failed_rotors([1]))


def test_trim_names_the_rotor_that_hover_forces_onto_its_bound(hexa_one_failed: rf.Simulator) -> None:
    frame = hexa_one_failed.airframe
    trim = rf.hover_trim(hexa_one_failed, position=SETPOINT)
    assert trim.saturated_rotors == (4,) and trim.command[3] == 0.0
    # Independently: the hover solutions of the five live rotors form a line u + z n; rotor 4's
    # component of n is zero, so every solution has rotor 4 at the minimum-norm value 0 N = its
    # lower bound, and Du's ACAI is 0.
    b = frame.effectiveness_matrix()[:, 1:]
    wrench = [frame.hover_thrust_n, 0, 0, 0]
    null = scipy.linalg.null_space(b)
    assert null.shape == (5, 1) and abs(null[2, 0]) < 1e-12
    u = np.linalg.lstsq(b, wrench, rcond=None)[0]
    assert abs(u[2]) < 1e-12 and frame.min_thrust_n[3] == 0.0
    assert rf.acai(frame) == 0.0
    np.testing.assert_allclose(trim.command[1:], np.where(np.arange(5) == 2, 0.0, u), rtol=0, atol=1e-12)
    assert trim.residual < 1e-13
    # With every rotor healthy the minimum-norm trim is interior: nothing is named.
    assert rf.hover_trim(rf.Simulator(rf.Airframe.preset("hexa-pnpnpn"))).saturated_rotors == ()


def test_linearize_differentiates_one_sided_into_the_box(hexa_one_failed: rf.Simulator) -> None:
    frame = hexa_one_failed.airframe
    trim = rf.hover_trim(hexa_one_failed, position=SETPOINT)
    b = rf.linearize(hexa_one_failed, trim).B
    # Analytic thrust columns at level hover: v_d' = -eta_i / m per newton, body rates
    # I^-1 [roll, pitch, yaw rows of B_f] (inertia diagonal, no gyroscopic term at rest). The old
    # central difference across rotor 4's clamp halved its column.
    bf = frame.effectiveness_matrix()
    np.testing.assert_allclose(b[5], -frame.efficiency / frame.mass_kg, rtol=1e-8, atol=1e-12)
    np.testing.assert_allclose(b[9:12], bf[1:4] / frame.inertia_kg_m2[:, None], rtol=1e-8, atol=1e-9)
    assert b[5, 3] == pytest.approx(-0.6514658, rel=1e-6) and b[10, 3] == pytest.approx(-5.753138, rel=1e-6)
    # At an upper bound the difference points down into the box.
    quad = rf.Simulator(rf.Airframe.preset("quad-x"))
    x = np.zeros(12)
    b_top = rf.linearize(quad, (x, quad.airframe.max_thrust_n)).B
    np.testing.assert_allclose(b_top[5], -1 / quad.airframe.mass_kg, rtol=1e-8)
    with pytest.raises(ValueError, match=r"u_trim\[2\]: rotor 3's command 7.0 lies outside its bounds \[0.0, 6.125\]"):
        rf.linearize(quad, (x, [3.0, 3.0, 7.0, 3.0]))


def _quad_without_yaw_torque() -> rf.Airframe:
    return rf.Airframe(
        arm_angle_rad=np.radians([45, 135, 225, 315]), arm_length_m=[0.2] * 4, spin=["cw", "ccw", "cw", "ccw"],
        max_thrust_n=[6.0] * 4, mass_kg=1.2, inertia_kg_m2=[0.01, 0.01, 0.02], drag_torque_ratio_m=0.0,
    )


@pytest.mark.parametrize(
    ("frame", "message"),
    [
        (lambda: rf.Airframe.preset("hexa-pnpnpn").with_failed_rotors([1]),
         r"LQR cannot hold this hover: ACAI eq13 = 0 <= 0 .*; hover needs rotor\(s\) 4 on a thrust bound \(0 N\)"),
        (lambda: rf.Airframe.preset("hexa-pnpnpn").with_failed_rotors([1, 4]),
         r"LQR cannot hold this hover: ACAI eq13 = -inf <= 0 \(rank B_f < 4"),
        (_quad_without_yaw_torque, r"LQR cannot hold this hover: ACAI eq13 = -inf <= 0 \(rank B_f < 4"),
    ],
)
def test_lqr_refuses_a_hover_it_cannot_hold(frame: object, message: str) -> None:
    sim = rf.Simulator(frame())  # type: ignore[operator]
    with pytest.raises(ValueError, match=message):
        rf.lqr_hover(sim, position=SETPOINT)
    with pytest.raises(ValueError, match=message):
        rf.lqr_hover_allocated(sim, rf.Allocator(sim.airframe), position=SETPOINT)


def test_trim_moves_off_a_minimum_norm_solution_that_leaves_the_bounds() -> None:
    frame = rf.Airframe.preset("hexa-pnpnpn").with_efficiency([0.486, 0.889, 0.934, 0.358, 0.572, 0.322])
    b, wrench = frame.effectiveness_matrix(), [frame.hover_thrust_n, 0, 0, 0]
    minimum_norm = np.linalg.lstsq(b, wrench, rcond=None)[0]
    assert minimum_norm[4] > frame.max_thrust_n[4] + 1.0  # 7.48 N against 6.125 N
    sim = rf.Simulator(frame)
    trim = rf.hover_trim(sim)
    # Independently: an interior hover exists (ACAI > 0), the trim balances exactly and keeps every
    # rotor at least 1 % of its range off the bounds (the LP maximises that margin).
    assert rf.acai(frame) > 0.04 and trim.saturated_rotors == ()
    np.testing.assert_allclose(b @ trim.command, wrench, rtol=0, atol=1e-12)
    margin = np.minimum(trim.command - frame.min_thrust_n, frame.max_thrust_n - trim.command) / frame.max_thrust_n
    assert margin.min() > 0.01 and trim.residual < 1e-13
    rf.lqr_hover(sim)  # designs
    with pytest.raises(ValueError, match="allocator: its pseudo-inverse gives the hover thrusts .* use lqr_hover"):
        rf.lqr_hover_allocated(sim, rf.Allocator(frame))


# -- item 5: the Euler-angle singularity --------------------------------------------------------


def _euler_rate_jacobian(x: np.ndarray) -> np.ndarray:
    """d(roll', pitch', yaw')/d(roll, pitch) of the Z-Y-X Euler kinematics, by hand."""
    roll, pitch = x[6], x[7]
    p, q, r = x[9:12]
    sr, cr, sp, cp = math.sin(roll), math.cos(roll), math.sin(pitch), math.cos(pitch)
    return np.array([
        [(q * cr - r * sr) * sp / cp, (q * sr + r * cr) / cp**2],
        [-q * sr - r * cr, 0.0],
        [(q * cr - r * sr) / cp, (q * sr + r * cr) * sp / cp**2],
    ])


@pytest.mark.parametrize(("pitch_deg", "limit_deg", "rtol"), [(0.0, 80, 1e-9), (60.0, 80, 1e-9), (80.0, 80, 1e-9), (89.0, 89, 1e-7)])
def test_linearize_matches_the_analytic_euler_rates_within_its_limit(pitch_deg: float, limit_deg: float, rtol: float) -> None:
    # Measured relative errors: 8e-11 at 0-80 degrees, 8e-9 at 89 (1e-6 relative step).
    sim = rf.Simulator(rf.Airframe.preset("quad-x"))
    x = np.zeros(12)
    x[6], x[7], x[9:12] = 0.3, math.radians(pitch_deg), (0.1, 0.2, 0.3)
    a = rf.linearize(sim, (x, np.full(4, 3.0)), max_pitch_rad=math.radians(limit_deg)).A
    exact = _euler_rate_jacobian(x)
    assert np.abs(a[6:9, 6:8] - exact).max() <= rtol * np.abs(exact).max()


@pytest.mark.parametrize("pitch", [math.pi / 2, 1.570796, -math.radians(80.01), math.radians(85)])
def test_linearize_refuses_pitch_near_the_singularity(pitch: float) -> None:
    sim = rf.Simulator(rf.Airframe.preset("quad-x"))
    x = np.zeros(12)
    x[7], x[9:12] = pitch, (0.1, 0.2, 0.3)
    degrees = f"{math.degrees(pitch):.4f}"
    with pytest.raises(ValueError, match=rf"x_trim\[7\]: pitch {degrees} degrees is beyond the 80-degree limit"):
        rf.linearize(sim, (x, np.full(4, 3.0)))


@pytest.mark.parametrize(
    ("kwargs", "error", "message"),
    [
        ({"max_pitch_rad": math.radians(89.5)}, ValueError, r"max_pitch_rad: must lie in \(0, 1.553343\] \(89 degrees\)"),
        ({"max_pitch_rad": 0.0}, ValueError, "max_pitch_rad: must lie in"),
        ({"max_pitch_rad": "80"}, TypeError, "max_pitch_rad: expected a real number"),
        ({"step": 0.0}, ValueError, r"step: must lie in \(0, 0.01\]"),
    ],
)
def test_linearize_bad_options(kwargs: dict[str, object], error: type[Exception], message: str) -> None:
    sim = rf.Simulator(rf.Airframe.preset("quad-x"))
    with pytest.raises(error, match=message):
        rf.linearize(sim, (np.zeros(12), np.full(4, 3.0)), **kwargs)  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("kwargs", "error", "message"),
    [
        ({"position": (0, float("nan"), 0)}, ValueError, "position: must be finite"),
        ({"position": (0, 0)}, ValueError, "position: expected 3 entries, got 2"),
        ({"yaw": float("inf")}, ValueError, "yaw: must be finite"),
        ({"yaw": "north"}, TypeError, "yaw: expected a real number"),
    ],
)
def test_hover_trim_bad_input(kwargs: dict[str, object], error: type[Exception], message: str) -> None:
    with pytest.raises(error, match=message):
        rf.hover_trim(rf.Simulator(rf.Airframe.preset("quad-x")), **kwargs)  # type: ignore[arg-type]


def test_hover_trim_refuses_a_wind_that_lifts_the_vehicle() -> None:
    sim = rf.Simulator(rf.Airframe.preset("quad-x"), drag=rf.Drag(linear_n_s_m=1.0), wind=(0.0, 0.0, -20.0))
    with pytest.raises(ValueError, match="wind: the drag of wind .* outweighs gravity along the vertical"):
        rf.hover_trim(sim)
    vpp = rf.Simulator(rf.Airframe.preset("quad-x"), actuator=rf.VariablePitchActuator(
        k=(5e-7, 1e-10, 3e-11, 1e-7), speed_bounds=(0, 10_000), pitch_bounds=(-0.3, 0.3)))
    with pytest.raises(TypeError, match="simulator: hover_trim needs a rotorfault.Simulator with fixed-pitch rotors"):
        rf.hover_trim(vpp)

"""Lanzon et al.'s robust feedback linearisation (Section III.B), each result against an
independent computation:

- the closed loop under ``u = alpha(x) + beta(x) v``, linearised at the origin by central
  differences, is eq. (26) as printed (typed here from the paper; tolerance 1e-6 relative);
- at random states, the transformed state ``x_r = T^-1 phi_c(x)`` obeys ``x_r' = A_r x_r + B_r v``
  exactly: its derivative from a SymPy derivation of the model (14) (Jacobian of ``phi_c`` by
  symbolic differentiation) matches the linear system to 1e-10 (relative to the terms' size);
- ``b(x)`` and ``M(x)`` against central differences of the model (tolerance 1e-6 relative).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import rotorfault as rf
from rotorfault.control.lanzon import LanzonVehicle
from rotorfault.papers.lanzon_checks import EQ26_RTOL, eq26_check, eq26_jacobian_numbers


@pytest.fixture(scope="module")
def vehicle() -> LanzonVehicle:
    return LanzonVehicle.from_airframe(rf.Airframe.preset("lanzon-quadrotor"))


def test_table_1_and_the_spin_of_table_2(vehicle: LanzonVehicle) -> None:
    assert vehicle.mass_kg == 0.5 and vehicle.inertia_xx_kg_m2 == 5.9e-3 and vehicle.inertia_zz_kg_m2 == 1.16e-3
    assert vehicle.arm_length_m == 0.255 and vehicle.drag_torque_ratio_m == 2.4e-3
    assert vehicle.spin_rate_rad_s == pytest.approx(2.7, rel=1e-14)
    assert vehicle.rotational_drag_n_m_s == pytest.approx(0.5 * 9.81 * 2.4e-3 / 2.7, rel=1e-14)


@pytest.mark.parametrize("izz", [1.16e-3, 1.16e-2])
def test_linearised_closed_loop_is_eq_26(izz: float) -> None:
    """Eq. (26) as printed (``rotorfault.papers.lanzon_checks.eq26_printed``, typed from the
    paper) against our closed form and against central differences of the closed loop under the
    RFL: the same check, through the same function, as the reproduce-all report."""
    check = eq26_check(LanzonVehicle(inertia_zz_kg_m2=izz))
    np.testing.assert_allclose(check.a_ours, check.a_printed, rtol=1e-14, atol=0)
    np.testing.assert_allclose(check.b_ours, check.b_printed, rtol=1e-14, atol=0)
    np.testing.assert_allclose(check.a_fd, check.a_printed, rtol=EQ26_RTOL, atol=EQ26_RTOL * np.max(np.abs(check.a_printed)))
    np.testing.assert_allclose(check.b_fd, check.b_printed, rtol=EQ26_RTOL, atol=EQ26_RTOL * np.max(np.abs(check.b_printed)))


def test_eq_26_numbers_all_pass() -> None:
    numbers = eq26_jacobian_numbers()
    assert len(numbers) == 13  # the non-zero entries: 9 of (26a), 4 of (26b)
    assert all(n.status == "pass" for n in numbers), [n for n in numbers if n.status != "pass"]


def _sympy_phi_c_jacobian(v: LanzonVehicle):  # type: ignore[no-untyped-def]
    """The model (14a)-(14f) in hat coordinates, typed from the paper, and the Jacobian of
    phi_c = [phi, phi', theta, theta', r - r0] by symbolic differentiation."""
    sp = pytest.importorskip("sympy")
    phi, theta, p, q, dr = xs = sp.symbols("phi theta p q dr")
    m, g, d, kr = v.mass_kg, v.gravity_m_s2, v.drag_torque_ratio_m, v.rotational_drag_n_m_s
    ixx, izz, l = v.inertia_xx_kg_m2, v.inertia_zz_kg_m2, v.arm_length_m
    r = dr + m * g * d / kr
    u1, u2, u3 = us = sp.symbols("u1 u2 u3")  # hat inputs (22b)
    uf, tq, tr = u1 + m * g, u2, u3 + m * g * d
    rhs = sp.Matrix([
        p + q * sp.sin(phi) * sp.tan(theta) + r * sp.cos(phi) * sp.tan(theta),
        q * sp.cos(phi) - r * sp.sin(phi),
        (-kr * p - q * r * (izz - ixx) + l / 2 * (uf - tr / d)) / ixx,
        (-kr * q - p * r * (ixx - izz) + tq) / ixx,
        (-kr * r + tr) / izz,
    ])
    phic = sp.Matrix([phi, rhs[0], theta, rhs[1], dr])
    jac = phic.jacobian(sp.Matrix(xs))
    return sp.lambdify([xs, us], (phic, jac, rhs), "numpy")


def test_rfl_is_exact_at_random_states(vehicle: LanzonVehicle) -> None:
    fun = _sympy_phi_c_jacobian(vehicle)
    a_r, b_r = vehicle.linearisation()
    t_inv = np.linalg.inv(vehicle.transform_matrix())
    rng = np.random.default_rng(10)
    for _ in range(50):
        x = np.concatenate([rng.uniform(-1.0, 1.0, 2), rng.uniform(-3, 3, 3)])
        w = rng.normal(size=3) * 10
        alpha, beta = vehicle.rfl(x)
        u = alpha + beta @ w
        phic, jac, rhs = fun(list(x), list(u))
        phic = np.asarray(phic, dtype=float).reshape(-1)
        xdot = np.asarray(rhs, dtype=float).reshape(-1)
        xr = t_inv @ phic
        np.testing.assert_allclose(vehicle.transform(x), xr, rtol=0, atol=1e-12 * (1 + np.max(np.abs(xr))))
        lhs = t_inv @ np.asarray(jac, dtype=float) @ xdot
        expected = a_r @ xr + b_r @ w
        scale = np.max(np.abs(a_r @ xr)) + np.max(np.abs(b_r @ w)) + np.max(np.abs(lhs))
        np.testing.assert_allclose(lhs, expected, rtol=0, atol=1e-10 * scale)


def test_lie_terms_and_decoupling_matrix_against_finite_differences(vehicle: LanzonVehicle) -> None:
    rng = np.random.default_rng(11)
    g = vehicle.input_matrix()

    def a(x: np.ndarray) -> np.ndarray:  # the outputs of relative degree one lower: phi', theta', r - r0
        f = vehicle.drift(x)
        return np.array([f[0], f[1], x[4]])

    h = 1e-6
    for _ in range(20):
        x = np.concatenate([rng.uniform(-1.0, 1.0, 2), rng.uniform(-3, 3, 3)])
        f = vehicle.drift(x)
        b_fd = (a(x + h * f) - a(x - h * f)) / (2 * h)
        b_fd[2] = f[4]
        m_fd = np.column_stack([(a(x + h * g[:, j]) - a(x - h * g[:, j])) / (2 * h) for j in range(3)])
        m_fd[2] = g[4]
        np.testing.assert_allclose(vehicle.lie_terms(x), b_fd, rtol=1e-6, atol=1e-6 * np.max(np.abs(b_fd)))
        np.testing.assert_allclose(vehicle.decoupling_matrix(x), m_fd, rtol=1e-6, atol=1e-6 * np.max(np.abs(m_fd)))
        # alpha, beta from the differenced terms (the formula (21) with finite-difference Lie derivatives)
        l_mat, t_inv, m0 = vehicle.rfl_gains()
        alpha_fd = np.linalg.solve(m_fd, -b_fd + l_mat @ t_inv @ vehicle.brunovsky(x))
        alpha, beta = vehicle.rfl(x)
        np.testing.assert_allclose(alpha, alpha_fd, rtol=1e-5, atol=1e-6 * np.max(np.abs(alpha_fd)))
        np.testing.assert_allclose(beta, np.linalg.solve(m_fd, m0), rtol=1e-5, atol=1e-6)


def test_rfl_vanishes_at_the_working_point(vehicle: LanzonVehicle) -> None:
    alpha, beta = vehicle.rfl(np.zeros(5))
    np.testing.assert_allclose(alpha, 0, atol=1e-15)
    np.testing.assert_allclose(beta, np.eye(3), atol=1e-15)
    # Hover thrusts of eq. (9) at the working point: rotors 1 and 3 carry the weight, 4 is idle.
    f = vehicle.rotor_thrusts([vehicle.mass_kg * vehicle.gravity_m_s2, 0, vehicle.mass_kg * vehicle.gravity_m_s2 * vehicle.drag_torque_ratio_m])
    np.testing.assert_allclose(f, [0.5 * 0.5 * 9.81, 0, 0.5 * 0.5 * 9.81, 0], atol=1e-15)


def test_frame_conversion_round_trips() -> None:
    x = np.arange(12, dtype=float) * 0.1 + 0.05
    np.testing.assert_array_equal(LanzonVehicle.simulator_state(LanzonVehicle.paper_state(x)), x)


def test_bad_vehicle_names_the_field() -> None:
    with pytest.raises(ValueError, match=r"^vehicle\.rotational_drag_n_m_s: must be > 0"):
        LanzonVehicle(rotational_drag_n_m_s=0.0)
    with pytest.raises(ValueError, match="airframe: Lanzon's controller needs a plus quadrotor"):
        LanzonVehicle.from_airframe(rf.Airframe.preset("quad-x"))
    assert math.isfinite(LanzonVehicle().spin_rate_rad_s)

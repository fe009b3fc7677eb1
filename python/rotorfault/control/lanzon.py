"""Lanzon, Freddi and Longhi (JGCD 2014): flying a quadrotor on three rotors by letting it spin.

Design in Python, run in Rust. This module holds

- :class:`LanzonVehicle`: the control model (14) of the quadrotor with rotor 2 failed, in the
  paper's z-up frame, and the parameters the paper does not print (``k_r``, ``k_t``, ``I_R``);
- the robust feedback linearisation (RFL) of the reduced 5-state subsystem (22)-(24), derived
  here (the Appendix of our copy is garbled) and coded in closed form: :meth:`LanzonVehicle.rfl`
  gives ``alpha(x)``, ``beta(x)``, :meth:`LanzonVehicle.transform` the new state
  ``x_r = T^-1 phi_c(x)``, :meth:`LanzonVehicle.linearisation` ``(A_r, B_r)`` of eq. (26);
- :func:`design`: the H-infinity loop-shaping inner controller on ``(A_r, B_r)`` with our
  :func:`~rotorfault.control.robust.ncfsyn`, and the outer-loop gains;
- :class:`LanzonController`: the whole controller (RFL + discretised loop-shaping controller +
  outer loop (28)-(31) with the yaw-synchronised rotation), run by the Rust core.

Derivation (hat coordinates ``x = [phi, theta, p, q, r - r0]``, ``r0 = m g d / k_r``,
``u = [u_f - m g, tau_q, tau_r - m g d]``, outputs ``y = [phi, theta, r - r0]`` of relative
degrees 2, 2, 1)::

    a1 = phi'   = p + q S_phi T_theta + r C_phi T_theta        (14a)
    a2 = theta' = q C_phi - r S_phi                            (14b)
    y'' = b(x) + M(x) u,   b = [L_f a1, L_f a2, f5],   M: eq. (25)
    phi_c = [phi, a1, theta, a2, r - r0],   T = d phi_c / dx (0)
    L = d b / dx (0) = rows 2, 4, 5 of T A_r,   M(0)^-1 = R
    alpha(x) = M(x)^-1 (-b(x) + L T^-1 phi_c(x)),   beta(x) = M(x)^-1 M(0)     (21a, 21b)

so that ``x_r = T^-1 phi_c(x)`` obeys ``x_r' = A_r x_r + B_r v`` exactly. Eq. (24) prints the
(3, 1) and (3, 3) entries of ``G`` without the arm length ``l``; eq. (14d) and (26b) have it, and so
does this module.

Frames: the paper's world and body frames are z up; the simulator's are NED/FRD. With the
``lanzon-quadrotor`` preset (rotor 1 front, 2 right, 3 rear, 4 left in FRD) the two differ by a
rotation of pi about x: ``phi = roll``, ``theta = -pitch``, ``psi = -yaw``, ``(p, q, r)_paper =
(p, -q, -r)``, position ``(x, -y, -z)``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import control as ct  # type: ignore[import-untyped]
import numpy as np
import numpy.typing as npt
import scipy.linalg as sla  # type: ignore[import-untyped]

from .. import _rfcore
from .._util.convert import FloatArray, float_array, real
from .._util.deprecation import dataclass_compat
from ..analysis.airframe import Airframe, require_airframe
from ..flight import Drag, FixedPitchActuator, Simulator
from .realisation import state_space, with_signals
from .systems import LANZON_INPUTS, LANZON_OUTPUTS, LANZON_STATES
from .robust import NcfsynEvidence, NcfsynResult, loop_shape_weight, ncfsyn, target_loop_shape

#: Table 2's initial spin, rad/s: ``k_r = m g d / SPIN_RATE_RAD_S`` reproduces it (the paper
#: gives no ``k_r``).
SPIN_RATE_RAD_S = 2.7
#: The failed rotor of the paper's design (1-based; Section III.A).
FAILED_ROTOR = 2

class LanzonVehicle(_rfcore.LanzonVehicle):
    """The quadrotor of Lanzon et al. with rotor 2 failed: Table 1 values plus the three the paper
    does not give. ``rotational_drag_n_m_s`` (``k_r``) defaults to ``m g d / 2.7``, so the steady
    spin is Table 2's 2.7 rad/s; ``linear_drag_n_s_m`` (``k_t``) to 0.1 N s/m and
    ``rotor_inertia_kg_m2`` (``I_R``, gyroscopic moment (5), verification model only) to 3e-5
    kg m^2 (a 10-inch propeller with its motor bell), with ``thrust_coefficient_n_s2`` 1e-5 N s^2
    (``f = k_f omega^2``: 5 N at 707 rad/s), ``max_thrust_n`` 5 N and ``rate_limit_n_s`` 50 N/s.
    ``inertia_zz_kg_m2`` defaults to Table 1's printed 1.16e-3 (probably a misprint of 1.16e-2;
    both are flown in the report).

    The core's vehicle itself (issue 26: types cross the boundary once): keyword-only, every
    default from the core's ``LanzonVehicle::default()``, all twelve values checked once, by the
    core's ``LanzonVehicle::check``, when the vehicle is made (errors name ``vehicle.<field>``:
    scales finite, > 0 and within [1e-15, 1e15]; thrust and rate limits finite and > 0; ``k_t``,
    ``I_R``, ``k_f`` finite and >= 0). Frozen, comparable, hashable, picklable;
    ``vehicle.replace(mass_kg=0.6)`` gives a checked copy and ``LanzonVehicle.FIELDS`` the names
    (``dataclasses.replace`` and ``dataclasses.fields`` still work, with a
    ``DeprecationWarning``, for one release); ``model`` is the core's ``LanzonModel`` the
    controller flies with. This subclass adds what the design reads in Python ("design in
    Python, run in Rust"): the RFL algebra the loop-shaping design works on and the simulator of
    the verification model.

    Examples:

        >>> from rotorfault.control.lanzon import LanzonVehicle
        >>> v = LanzonVehicle()
        >>> round(v.spin_rate_rad_s, 6), v.max_thrust_n, v.replace(mass_kg=0.6).mass_kg
        (2.7, 5.0, 0.6)
    """

    __slots__ = ()

    @classmethod
    def from_airframe(cls, airframe: Airframe, **overrides: Any) -> LanzonVehicle:
        """The vehicle of a plus-configured quadrotor airframe (rotors at 0, 90, 180, 270 degrees,
        spins cw, ccw, cw, ccw, equal arms, Ixx = Iyy), e.g. ``Airframe.preset("lanzon-quadrotor")``;
        ``k_r`` defaults to ``m g d / 2.7`` of that airframe; other fields as keywords."""
        airframe = require_airframe(airframe)
        angles = np.degrees(airframe.arm_angle_rad) % 360
        if airframe.rotor_count != 4 or not np.allclose(angles, [0, 90, 180, 270], atol=1e-9):
            raise ValueError("airframe: Lanzon's controller needs a plus quadrotor with rotors at 0, 90, 180, 270 degrees")
        if tuple(airframe.spin) != ("cw", "ccw", "cw", "ccw"):
            raise ValueError("airframe: rotor spins must be cw, ccw, cw, ccw (Lanzon Fig. 1)")
        arms = airframe.arm_length_m
        inertia = airframe.inertia_kg_m2
        if not np.allclose(arms, arms[0]) or not math.isclose(inertia[0], inertia[1], rel_tol=1e-12):
            raise ValueError("airframe: equal arm lengths and I_xx = I_yy required (Lanzon's assumption 1)")
        m, g, d = airframe.mass_kg, airframe.gravity_m_s2, airframe.drag_torque_ratio_m
        values: dict[str, Any] = dict(
            mass_kg=m, gravity_m_s2=g, inertia_xx_kg_m2=float(inertia[0]), inertia_zz_kg_m2=float(inertia[2]),
            arm_length_m=float(arms[0]), drag_torque_ratio_m=d, rotational_drag_n_m_s=m * g * d / SPIN_RATE_RAD_S,
            max_thrust_n=float(np.max(airframe.max_thrust_n)),
        )
        values.update(overrides)
        return cls(**values)

    # -- derived quantities ---------------------------------------------------------------------
    @property
    def spin_rate_rad_s(self) -> float:
        """``r0 = m g d / k_r``: the steady spin of the working point."""
        return self.mass_kg * self.gravity_m_s2 * self.drag_torque_ratio_m / self.rotational_drag_n_m_s

    def airframe(self) -> Airframe:
        """The simulator airframe (``lanzon-quadrotor`` geometry with this vehicle's values)."""
        base = Airframe.preset("lanzon-quadrotor")
        ixx, izz = self.inertia_xx_kg_m2, self.inertia_zz_kg_m2
        return Airframe(
            arm_angle_rad=base.arm_angle_rad, arm_length_m=[self.arm_length_m] * 4, spin=list(base.spin),
            max_thrust_n=[self.max_thrust_n] * 4, mass_kg=self.mass_kg, inertia_kg_m2=[ixx, ixx, izz],
            drag_torque_ratio_m=self.drag_torque_ratio_m, gravity_m_s2=self.gravity_m_s2,
            name="lanzon-quadrotor",
        )

    def simulator(self, *, dt_s: float = 1e-3, substeps: int = 2, limits: bool = True, **kwargs: Any) -> Simulator:
        """The verification model (Section II.B): gyroscopic moment (5), Stokes drag, and with
        ``limits`` the thrust saturation [0, f_max] and the rate limit (50 N/s); without, no
        actuator limit at all (thrust in [-1e6, 1e6] N, no rate limit): the model the design
        assumes."""
        airframe = self.airframe()
        if not limits:
            airframe = Airframe(
                arm_angle_rad=airframe.arm_angle_rad, arm_length_m=airframe.arm_length_m, spin=list(airframe.spin),
                max_thrust_n=[1e6] * 4, min_thrust_n=[-1e6] * 4, mass_kg=self.mass_kg, inertia_kg_m2=airframe.inertia_kg_m2,
                drag_torque_ratio_m=self.drag_torque_ratio_m, gravity_m_s2=self.gravity_m_s2, name="lanzon-quadrotor",
            )
        actuator = FixedPitchActuator(rate_limit_n_s=self.rate_limit_n_s if limits else math.inf,
                                      thrust_coefficient_n_s2=self.thrust_coefficient_n_s2)
        drag = Drag(linear_n_s_m=self.linear_drag_n_s_m, rotational_n_m_s=self.rotational_drag_n_m_s,
                    rotor_inertia_kg_m2=self.rotor_inertia_kg_m2)
        return Simulator(airframe, dt_s=dt_s, substeps=substeps, actuator=actuator, drag=drag, **kwargs)

    # -- the reduced model (22)-(24) --------------------------------------------------------------
    def input_matrix(self) -> FloatArray:
        """``G`` of (24) (with the arm length, as in (14d) and (26b)): constant."""
        ixx, izz, l, d = self.inertia_xx_kg_m2, self.inertia_zz_kg_m2, self.arm_length_m, self.drag_torque_ratio_m
        g = np.zeros((5, 3))
        g[2] = [l / (2 * ixx), 0.0, -l / (2 * d * ixx)]
        g[3, 1] = 1 / ixx
        g[4, 2] = 1 / izz
        return g

    def drift(self, x: npt.ArrayLike) -> FloatArray:
        """``f(x)`` of (24) in hat coordinates ``[phi, theta, p, q, r - r0]``."""
        phi, theta, p, q, dr = np.asarray(x, dtype=float)
        r = dr + self.spin_rate_rad_s
        ixx, izz, kr = self.inertia_xx_kg_m2, self.inertia_zz_kg_m2, self.rotational_drag_n_m_s
        sf, cf, tt = math.sin(phi), math.cos(phi), math.tan(theta)
        return np.array([
            p + q * sf * tt + r * cf * tt,
            q * cf - r * sf,
            (-kr * p - q * r * (izz - ixx)) / ixx,
            (-kr * q - p * r * (ixx - izz)) / ixx,
            -kr * dr / izz,
        ])

    def reduced_dynamics(self, x: npt.ArrayLike, u: npt.ArrayLike) -> FloatArray:
        """``x' = f(x) + G u`` (23a) in hat coordinates."""
        out: FloatArray = self.drift(x) + self.input_matrix() @ np.asarray(u, dtype=np.float64)
        return out

    def linearisation(self) -> tuple[FloatArray, FloatArray]:
        """``(A_r, B_r)`` of eq. (26), in closed form."""
        ixx, izz, kr = self.inertia_xx_kg_m2, self.inertia_zz_kg_m2, self.rotational_drag_n_m_s
        r0 = self.spin_rate_rad_s
        c = r0 * (ixx - izz) / ixx
        a = np.array([
            [0, r0, 1, 0, 0],
            [-r0, 0, 0, 1, 0],
            [0, 0, -kr / ixx, c, 0],
            [0, 0, -c, -kr / ixx, 0],
            [0, 0, 0, 0, -kr / izz],
        ])
        return a, self.input_matrix()

    def plant(self) -> ct.StateSpace:
        """The linear plant after RFL: ``(A_r, B_r)`` with outputs ``[phi, theta, r - r0]`` (27)."""
        a, b = self.linearisation()
        c = np.zeros((3, 5))
        c[0, 0] = c[1, 1] = c[2, 4] = 1.0
        return with_signals(state_space(a, b, c, np.zeros((3, 3))), states=LANZON_STATES, inputs=LANZON_INPUTS,
                            outputs=LANZON_OUTPUTS, name="lanzon-plant")

    # -- robust feedback linearisation ------------------------------------------------------------
    def decoupling_matrix(self, x: npt.ArrayLike) -> FloatArray:
        """``M(x)`` of eq. (25)."""
        phi, theta = float(np.asarray(x)[0]), float(np.asarray(x)[1])
        ixx, izz, l, d = self.inertia_xx_kg_m2, self.inertia_zz_kg_m2, self.arm_length_m, self.drag_torque_ratio_m
        sf, cf, tt = math.sin(phi), math.cos(phi), math.tan(theta)
        return np.array([
            [l / (2 * ixx), sf * tt / ixx, cf * tt / izz - l / (2 * d * ixx)],
            [0.0, cf / ixx, -sf / izz],
            [0.0, 0.0, 1 / izz],
        ])

    def brunovsky(self, x: npt.ArrayLike) -> FloatArray:
        """``phi_c(x) = [phi, phi', theta, theta', r - r0]`` (outputs and their derivatives)."""
        f = self.drift(x)
        s = np.asarray(x, dtype=np.float64)
        return np.array([s[0], f[0], s[1], f[1], s[4]], dtype=np.float64)

    def lie_terms(self, x: npt.ArrayLike) -> FloatArray:
        """``b(x) = [L_f^2 h1, L_f^2 h2, L_f h3]``: the output derivatives of order r at u = 0."""
        phi, theta, p, q, dr = np.asarray(x, dtype=float)
        r = dr + self.spin_rate_rad_s
        f = self.drift(x)
        sf, cf, tt, ct_ = math.sin(phi), math.cos(phi), math.tan(theta), math.cos(theta)
        da1_dphi = q * cf * tt - r * sf * tt
        da1_dtheta = (q * sf + r * cf) / ct_**2
        b1 = da1_dphi * f[0] + da1_dtheta * f[1] + f[2] + sf * tt * f[3] + cf * tt * f[4]
        b2 = (-q * sf - r * cf) * f[0] + cf * f[3] - sf * f[4]
        return np.array([b1, b2, f[4]])

    def transform_matrix(self) -> FloatArray:
        """``T = d phi_c / dx (0)`` of (21f)."""
        r0 = self.spin_rate_rad_s
        return np.array([
            [1, 0, 0, 0, 0],
            [0, r0, 1, 0, 0],
            [0, 1, 0, 0, 0],
            [-r0, 0, 0, 1, 0],
            [0, 0, 0, 0, 1.0],
        ])

    def rfl_gains(self) -> tuple[FloatArray, FloatArray, FloatArray]:
        """``(L, T^-1, M(0))``: the constants of (21a), (21b), (21c)."""
        a, _ = self.linearisation()
        t = self.transform_matrix()
        l_mat = (t @ a)[[1, 3, 4]]
        t_inv = np.asarray(np.linalg.inv(t), dtype=np.float64)
        return l_mat, t_inv, self.decoupling_matrix(np.zeros(5))

    def transform(self, x: npt.ArrayLike) -> FloatArray:
        """``x_r = T^-1 phi_c(x)`` (21c, 21g)."""
        _, t_inv, _ = self.rfl_gains()
        return t_inv @ self.brunovsky(x)

    def rfl(self, x: npt.ArrayLike) -> tuple[FloatArray, FloatArray]:
        """``(alpha(x), beta(x))`` of (20)-(21): ``u = alpha(x) + beta(x) v`` makes
        ``x_r' = A_r x_r + B_r v`` exactly."""
        l_mat, t_inv, m0 = self.rfl_gains()
        m = self.decoupling_matrix(x)
        alpha = np.asarray(np.linalg.solve(m, -self.lie_terms(x) + l_mat @ t_inv @ self.brunovsky(x)), dtype=np.float64)
        beta = np.asarray(np.linalg.solve(m, m0), dtype=np.float64)
        return alpha, beta

    # -- frames ---------------------------------------------------------------------------------
    @staticmethod
    def paper_state(x: npt.ArrayLike) -> FloatArray:
        """The paper's 12-state vector (12) ``[phi, theta, psi, p, q, r, x, y, z, x', y', z']``
        (z up) from the simulator's ``[p_ned, v_ned, roll, pitch, yaw, p, q, r]`` (FRD)."""
        s = float_array("x", x, 1)
        return np.array([s[6], -s[7], -s[8], s[9], -s[10], -s[11], s[0], -s[1], -s[2], s[3], -s[4], -s[5]])

    @staticmethod
    def simulator_state(x: npt.ArrayLike) -> FloatArray:
        """The inverse of :meth:`paper_state`."""
        s = float_array("x", x, 1)
        return np.array([s[6], -s[7], -s[8], s[9], -s[10], -s[11], s[0], -s[1], -s[2], s[3], -s[4], -s[5]])

    def rotor_thrusts(self, u: npt.ArrayLike) -> FloatArray:
        """``[f1, f2, f3, f4]`` for ``u = [u_f, tau_q, tau_r]`` by eq. (9) (``f2 = 0``)."""
        uf, tq, tr = np.asarray(u, dtype=float)
        l, d = self.arm_length_m, self.drag_torque_ratio_m
        return np.array([(uf - 2 * tq / l + tr / d) / 4, 0.0, (uf + 2 * tq / l + tr / d) / 4, (2 * uf - 2 * tr / d) / 4])


dataclass_compat(LanzonVehicle)


#: The outer loop (28)-(31), which the paper leaves to "any simple standard linear control
#: technique": the core's class, used directly (keyword-only; defaults from the core's
#: ``LanzonOuterLoop::default()``; types checked by the bindings, values once, by the core's
#: ``check``, when the gains are made, errors naming ``outer_loop.<field>``: finite, gains >= 0,
#: tilt in (0, pi/2), acceleration and integral limit > 0; frozen, ``replace(**changes)``,
#: ``FIELDS``). PD laws ``z~ = -k_p e - k_d e'`` on the horizontal position (``k_p_xy``, 1/s^2;
#: ``k_d_xy``, 1/s) and the altitude (``k_p_z``, ``k_d_z``), the roll/pitch set points limited to
#: ``max_tilt_rad`` (rad) and the vertical acceleration to ``max_vertical_accel_m_s2`` (m/s^2).
#:
#: Integral action, not the paper's (default off: ``k_i_xy = k_i_z = 0``, the PD laws as
#: designed): ``z~ = -k_p e - k_d e' - k_i integral(e)`` with ``k_i_xy``, ``k_i_z`` (1/s^3), each
#: axis's integral clamped to ``integral_limit_m_s`` (m s), removes the steady error a constant
#: disturbance or a model error (mass, thrust coefficient) leaves. With the default PD gains the
#: loops stay stable for ``k_i_z < k_p_z k_d_z`` (0.5) and ``k_i_xy < k_p_xy k_d_xy`` (0.175).
OuterLoopGains = _rfcore.OuterLoopGains
dataclass_compat(OuterLoopGains)


@dataclass(frozen=True)
class LanzonDesign:
    """An inner-loop design: the loop shape (``crossover_rad_s``, ``low_gain_db``,
    ``rolloff_factor``, per-output ``channel_gain`` for phi, theta, r), the weight ``w1`` with
    ``G W1 = diag(channel_gain_i L)``, and the :func:`~rotorfault.control.ncfsyn` result."""

    vehicle: LanzonVehicle
    crossover_rad_s: float
    low_gain_db: float
    rolloff_factor: float
    channel_gain: tuple[float, float, float]
    w1: ct.StateSpace
    synthesis: NcfsynResult

    @property
    def gamma(self) -> float:
        return self.synthesis.gamma

    @property
    def gamma_min(self) -> float:
        return self.synthesis.gamma_min

    @property
    def stability_margin(self) -> float:
        return self.synthesis.stability_margin

    @property
    def evidence(self) -> NcfsynEvidence:
        """What the synthesis checked before returning (achieved norm on the full shaped plant,
        gamma_min two ways, closed-loop poles with the plant): :class:`NcfsynEvidence`."""
        return self.synthesis.evidence

    @property
    def controller(self) -> ct.StateSpace:
        """The continuous controller ``K = W1 Ks`` from the errors ``[phi, theta, r]`` to ``v``,
        named as the plant's signals: inputs ``phi, theta, dr``, outputs ``du_f, tau_q, dtau_r``
        (:func:`~rotorfault.control.lanzon_plant`)."""
        return self.synthesis.controller

    def discretise(self, dt_s: float) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        """``(A, B, C, D)`` of the controller discretised at ``dt_s`` (Tustin, which maps a stable
        continuous controller to a stable discrete one at any period), its states in real Schur
        coordinates (an orthogonal change of the controller's states: ``A`` quasi-triangular,
        so its eigenvalues are read off, by the core's stability check among others)."""
        dt = real("dt_s", dt_s)
        if not (dt > 0 and math.isfinite(dt)):
            raise ValueError(f"dt_s: must be > 0, got {dt}")
        k = ct.c2d(self.controller, dt, method="tustin")
        a, b, c, d = (np.asarray(m, dtype=np.float64) for m in (k.A, k.B, k.C, k.D))
        if a.size:
            try:
                a, z = sla.schur(a, output="real")
            except (np.linalg.LinAlgError, ValueError) as exc:
                raise ValueError(f"dt_s: the discretised controller has no real Schur form (scipy: {exc})") from None
            b, c = z.T @ b, c @ z
        return tuple(np.ascontiguousarray(m) for m in (a, b, c, d))  # type: ignore[return-value]

    def plot_loop_shape(self, path: str | None = None) -> Any:
        """Singular values of the RFL plant and of the shaped plant ``G W1`` (Lanzon Fig. 4)."""
        from .robust import plot_singular_values

        return plot_singular_values(self.vehicle.plant(), self.synthesis.shaped_plant, path,
                                    title=f"loop shape: crossover {self.crossover_rad_s:g} rad/s, gamma = {self.gamma:.3f}")


def design(
    vehicle: LanzonVehicle | None = None,
    *,
    crossover_rad_s: float = 100.0,
    low_gain_db: float = 60.0,
    rolloff_factor: float = 10.0,
    channel_gain: npt.ArrayLike = (1.0, 1.0, 1.0),
    factor: float = 1.1,
) -> LanzonDesign:
    """H-infinity loop shaping of the RFL plant ``(A_r, B_r)``: Lanzon's loop shape (60 dB at low
    frequency, -20 dB/decade through ``crossover_rad_s``, -40 dB/decade above ``rolloff_factor``
    times it) realised by :func:`~rotorfault.control.robust.loop_shape_weight`, then
    :func:`~rotorfault.control.ncfsyn` at ``factor * gamma_min``. The defaults are the paper's
    design (100 rad/s crossover)."""
    vehicle = LanzonVehicle() if vehicle is None else vehicle
    if not isinstance(vehicle, LanzonVehicle):
        raise TypeError(f"vehicle: expected a LanzonVehicle, got {type(vehicle).__name__}")
    gains = float_array("channel_gain", channel_gain, 1)
    if gains.shape != (3,):
        raise ValueError(f"channel_gain: expected 3 entries (phi, theta, r), got {gains.shape[0]}")
    if not np.all(np.isfinite(gains)) or np.any(gains <= 0):
        raise ValueError(f"channel_gain: must be finite and > 0, got {gains.tolist()}")
    factor = real("factor", factor)
    if not (math.isfinite(factor) and factor > 1):
        raise ValueError(f"factor: must be finite and > 1 (gamma = factor * gamma_min), got {factor}")
    shape = target_loop_shape(crossover_rad_s, low_gain_db=low_gain_db, rolloff_factor=rolloff_factor)
    plant = vehicle.plant()
    w1 = loop_shape_weight(plant, shape, channel_gain=gains)
    synthesis = ncfsyn(plant, w1, factor=factor)
    return LanzonDesign(vehicle=vehicle, crossover_rad_s=float(crossover_rad_s), low_gain_db=float(low_gain_db),
                        rolloff_factor=float(rolloff_factor), channel_gain=tuple(float(g) for g in gains),  # type: ignore[arg-type]
                        w1=w1, synthesis=synthesis)


@dataclass(frozen=True)
class DesignCase:
    """One way of flying: the loop shape of :func:`design` (its crossover and channel gains),
    whether the simulator has the paper's actuator limits, and the outer-loop gains (the paper's
    three cases: :func:`rotorfault.papers.lanzon.design_cases`)."""

    label: str
    description: str
    crossover_rad_s: float
    limits: bool
    channel_gain: tuple[float, float, float] = (1.0, 1.0, 1.0)
    outer_loop: OuterLoopGains = field(default_factory=OuterLoopGains)

    def __post_init__(self) -> None:
        crossover = real("crossover_rad_s", self.crossover_rad_s)
        if not (math.isfinite(crossover) and crossover > 0):
            raise ValueError(f"crossover_rad_s: must be finite and > 0, got {crossover}")
        gains = np.asarray(self.channel_gain, dtype=np.float64)
        if gains.shape != (3,) or not np.all(np.isfinite(gains)) or np.any(gains <= 0):
            raise ValueError(f"channel_gain: expected 3 finite numbers > 0 (phi, theta, r), got {self.channel_gain}")
        if not isinstance(self.limits, bool):
            raise TypeError(f"limits: expected True or False, got {type(self.limits).__name__}")
        if not isinstance(self.outer_loop, OuterLoopGains):
            raise TypeError(f"outer_loop: expected OuterLoopGains, got {type(self.outer_loop).__name__}")

    def design(self, vehicle: LanzonVehicle) -> LanzonDesign:
        return design(vehicle, crossover_rad_s=self.crossover_rad_s, channel_gain=self.channel_gain)


class LanzonController:
    """Lanzon et al.'s controller, run in Rust: robust feedback linearisation, the discretised
    loop-shaping controller of ``design`` and, with a ``position`` (world NED, m), the outer loop
    (28)-(31) with the yaw-synchronised rotation; without one, the inner loop holds
    ``attitude_reference`` ``[phi_d, theta_d, r_d]`` (paper frame; default level at the working
    point's spin). Rotor 2 is the failed rotor (commanded 0).

    Examples:

        >>> from rotorfault.control import lanzon
        >>> controller = lanzon.LanzonController(lanzon.design(), position=(0, 0, -1))
        >>> controller.u_trim.round(4).tolist(), controller.core(1e-3) is not None
        ([2.4525, 0.0, 2.4525, 0.0], True)
    """

    def __init__(
        self,
        design: LanzonDesign,
        *,
        position: npt.ArrayLike | None = None,
        attitude_reference: npt.ArrayLike | None = None,
        outer_loop: OuterLoopGains | None = None,
    ) -> None:
        if not isinstance(design, LanzonDesign):
            raise TypeError(f"design: expected a LanzonDesign (rotorfault.control.lanzon.design), got {type(design).__name__}")
        if outer_loop is not None and not isinstance(outer_loop, OuterLoopGains):
            raise TypeError(f"outer_loop: expected OuterLoopGains, got {type(outer_loop).__name__}")
        self.design = design
        self.outer_loop = OuterLoopGains() if outer_loop is None else outer_loop
        self.position = None if position is None else tuple(float(v) for v in _three("position", position))
        self.attitude_reference = None if attitude_reference is None else tuple(
            float(v) for v in _three("attitude_reference", attitude_reference))
        v = design.vehicle
        hover = v.mass_kg * v.gravity_m_s2 / 2
        #: The working point's rotor thrusts (the actuators start there).
        self.u_trim = np.array([hover, 0.0, hover, 0.0])

    def core(self, dt_s: float) -> _rfcore.LanzonController:
        a, b, c, d = self.design.discretise(dt_s)
        return _rfcore.LanzonController(
            model=self.design.vehicle.model, a_k=a, b_k=b, c_k=c, d_k=d,
            attitude_reference=None if self.attitude_reference is None else list(self.attitude_reference),
            position=None if self.position is None else list(self.position),
            outer_loop=self.outer_loop if self.position is not None else None,
        )


def _three(name: str, value: npt.ArrayLike) -> FloatArray:
    arr = float_array(name, value, 1)
    if arr.shape != (3,):
        raise ValueError(f"{name}: expected 3 entries, got {arr.shape[0]}")
    return arr


__all__ = [
    "FAILED_ROTOR",
    "SPIN_RATE_RAD_S",
    "DesignCase",
    "LanzonController",
    "LanzonDesign",
    "LanzonVehicle",
    "OuterLoopGains",
    "design",
]

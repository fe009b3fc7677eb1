"""An LQR about a relaxed hover (Mueller and D'Andrea's cascade), designed here and run in Rust.

The analysis (:func:`rotorfault.relaxed_hover`) gives each solution's linear model, time-invariant
in body axes: state ``x = [a, b, dp, dq, dr, z, w]`` (the up axis seen from the body,
``n + a e1 + b e2``; body-rate deviation; altitude up and its rate), input the carrying rotors'
thrust deviations. :class:`RelaxedHoverLqr` designs ``K`` on it (continuous-time Riccati equation,
checked: residual, closed-loop eigenvalues, and the loop sampled at the control period) and runs
``u = u_trim - K x`` in Rust with an outer loop that tilts the up axis towards the set point
(:class:`rotorfault._rfcore.RelaxedHoverFeedback`). Idle and failed rotors stay at their trim.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from .. import _rfcore
from .._convert import FloatArray, float_array, real
from ..airframe import Airframe, require_airframe
from ..relaxed_hover import RelaxedHoverSolution, circle_offsets

#: Largest relative residual of the Riccati equation a design may have.
RICCATI_RTOL = 1e-8

RelaxedHoverOuterLoop = _rfcore.RelaxedHoverOuterLoop


@dataclass(frozen=True)
class LqrDesign:
    """An LQR gain with its evidence: ``gain`` (inputs x states), the Riccati solution ``x``, its
    relative ``residual`` and the closed-loop eigenvalues (all real parts < 0)."""

    gain: FloatArray
    x: FloatArray
    residual: float
    closed_loop_eigenvalues: npt.NDArray[np.complex128]


def _lqr(a: FloatArray, b: FloatArray, q: FloatArray, r: FloatArray) -> LqrDesign:
    """The one LQR call of this module (scipy's continuous-time Riccati solver), checked: the
    residual of ``A'X + XA - XBR^-1B'X + Q = 0`` relative to its terms, and stable closed-loop
    eigenvalues. A ``ValueError`` names the check that fails."""
    import scipy.linalg  # type: ignore[import-untyped]

    try:
        x = scipy.linalg.solve_continuous_are(a, b, q, r)
    except (np.linalg.LinAlgError, ValueError) as error:
        raise ValueError(f"LQR: the Riccati equation has no stabilising solution ({error})") from error
    gain = np.linalg.solve(r, b.T @ x)
    terms = [a.T @ x, x @ a, x @ b @ gain, q]
    residual_matrix = terms[0] + terms[1] - terms[2] + terms[3]
    size = max(float(np.abs(t).max()) for t in terms)
    residual = float(np.abs(residual_matrix).max()) / size
    if not residual <= RICCATI_RTOL:
        raise ValueError(f"LQR: Riccati residual check failed: {residual:.3e} > {RICCATI_RTOL:g}")
    eigenvalues = np.linalg.eigvals(a - b @ gain).astype(np.complex128)
    if not np.all(eigenvalues.real < 0):
        worst = eigenvalues[np.argmax(eigenvalues.real)]
        raise ValueError(f"LQR: closed-loop eigenvalue check failed: {worst:.6g} has a real part >= 0")
    return LqrDesign(gain=gain, x=x, residual=residual, closed_loop_eigenvalues=eigenvalues)


def bryson_weights(solution: RelaxedHoverSolution, airframe: Airframe) -> tuple[FloatArray, FloatArray]:
    """Default ``(Q, R)`` by Bryson's rule: 0.05 (about 3 degrees) on the up axis, 2 rad/s on the
    body rates, 0.2 m and 0.5 m/s on altitude, against each carrying rotor's room to move: a
    tenth of the largest carrying thrust, or less where the rotor is nearer one of its bounds (a
    rotor carrying 0.03 N above its floor must barely be used to push down; at least a
    thousandth of the largest thrust)."""
    scale = np.array([0.05, 0.05, 2.0, 2.0, 2.0, 0.2, 0.5])
    thrust = np.asarray(solution.thrust_n)
    largest = float(np.max(np.abs(thrust)))
    efficiency = np.asarray(airframe.efficiency)
    room = []
    for i in (j - 1 for j in solution.carrying):
        lo, hi = efficiency[i] * airframe.min_thrust_n[i], efficiency[i] * airframe.max_thrust_n[i]
        room.append(max(min(0.1 * largest, thrust[i] - lo, hi - thrust[i]), 1e-3 * largest))
    return np.diag(1.0 / scale**2), np.diag(1.0 / np.asarray(room) ** 2)


class RelaxedHoverLqr:
    """Holds a relaxed hover ``solution`` of ``airframe`` (the airframe it was computed for, with
    its efficiencies) at ``position`` (world NED): LQR on the solution's linear model with weights
    ``q`` (7 x 7) and ``r`` (carrying rotors square; default :func:`bryson_weights`), commands in
    rotor command units (thrust over efficiency), and the outer loop ``outer_loop``.
    ``linear_drag_n_s_m`` is the simulator's translational drag (it shapes the circle the centre
    of mass describes, which the outer loop must not chase)."""

    def __init__(
        self,
        solution: RelaxedHoverSolution,
        airframe: Airframe,
        *,
        position: npt.ArrayLike = (0.0, 0.0, 0.0),
        q: npt.ArrayLike | None = None,
        r: npt.ArrayLike | None = None,
        outer_loop: RelaxedHoverOuterLoop | None = None,
        linear_drag_n_s_m: float = 0.0,
    ) -> None:
        if not isinstance(solution, RelaxedHoverSolution):
            raise TypeError(f"solution: expected rotorfault.RelaxedHoverSolution, got {type(solution).__name__}")
        self.airframe = require_airframe(airframe)
        if outer_loop is not None and not isinstance(outer_loop, RelaxedHoverOuterLoop):
            raise TypeError(f"outer_loop: expected RelaxedHoverOuterLoop, got {type(outer_loop).__name__}")
        if len(solution.thrust_n) != airframe.rotor_count:
            raise ValueError(
                f"solution: has {len(solution.thrust_n)} rotors, the airframe {airframe.rotor_count}"
            )
        if not solution.stabilizable:
            raise ValueError(
                "solution: a linear feedback cannot hold it (a mode that does not decay is out of reach of its "
                "carrying rotors)"
            )
        self.solution = solution
        self.outer_loop = RelaxedHoverOuterLoop() if outer_loop is None else outer_loop
        pos = float_array("position", position, 1)
        if pos.shape != (3,) or not np.all(np.isfinite(pos)):
            raise ValueError("position: expected 3 finite entries (world NED, m)")
        self.position = pos
        a = np.asarray(solution.linear_a)
        b = np.asarray(solution.linear_b)
        q_default, r_default = bryson_weights(solution, airframe)
        self.q = q_default if q is None else float_array("q", q, 2)
        self.r = r_default if r is None else float_array("r", r, 2)
        if self.q.shape != (7, 7):
            raise ValueError(f"q: expected 7 x 7 (the reduced states), got {self.q.shape}")
        if self.r.shape != (b.shape[1], b.shape[1]):
            raise ValueError(f"r: expected {b.shape[1]} x {b.shape[1]} (the carrying rotors), got {self.r.shape}")
        self.design = _lqr(a, b, self.q, self.r)
        # Commands: a rotor's command is its thrust over its efficiency.
        efficiency = np.asarray(airframe.efficiency)
        carrying = [i - 1 for i in solution.carrying]
        gain = np.zeros((airframe.rotor_count, 7))
        for row, i in enumerate(carrying):
            gain[i] = self.design.gain[row] / efficiency[i]
        self.gain = gain
        #: The trim commands (the actuators start there).
        self.u_trim = np.asarray(solution.command_n, dtype=np.float64)
        self.linear_drag_n_s_m = real("linear_drag_n_s_m", linear_drag_n_s_m)
        self.offsets = circle_offsets(solution, airframe, linear_drag_n_s_m=self.linear_drag_n_s_m)

    def check_sampled(self, dt_s: float) -> npt.NDArray[np.complex128]:
        """Eigenvalues of the loop sampled at ``dt_s`` (zero-order hold): ``ValueError`` unless all
        lie inside the unit circle."""
        import scipy.linalg

        dt = real("dt_s", dt_s)
        if not (dt > 0 and math.isfinite(dt)):
            raise ValueError(f"dt_s: must be > 0, got {dt}")
        a = np.asarray(self.solution.linear_a)
        b = np.asarray(self.solution.linear_b)
        n, m = b.shape
        block = np.zeros((n + m, n + m))
        block[:n, :n], block[:n, n:] = a, b
        phi = scipy.linalg.expm(block * dt)
        sampled = phi[:n, :n] - phi[:n, n:] @ self.design.gain
        eigenvalues = np.linalg.eigvals(sampled).astype(np.complex128)
        if not np.all(np.abs(eigenvalues) < 1.0):
            worst = float(np.max(np.abs(eigenvalues)))
            raise ValueError(f"LQR: sampled-loop check failed at dt_s = {dt:g}: an eigenvalue of modulus {worst:.6g} >= 1")
        return eigenvalues

    def core(self, dt_s: float) -> _rfcore.RelaxedHoverFeedback:
        self.check_sampled(dt_s)
        s = self.solution
        basis = np.asarray(s.tangent_basis)
        return _rfcore.RelaxedHoverFeedback(
            axis=_triple(s.spin_axis),
            e1=_triple(basis[0]),
            e2=_triple(basis[1]),
            body_rate_rad_s=_triple(s.body_rate_rad_s),
            circle_offset_m=_triple(self.offsets.position_m),
            circle_velocity_m_s=_triple(self.offsets.velocity_m_s),
            gravity_m_s2=float(self.airframe.gravity_m_s2),
            u_trim=self.u_trim,
            gain=np.ascontiguousarray(self.gain),
            position_m=_triple(self.position),
            outer_loop=self.outer_loop,
        )


def _triple(v: npt.ArrayLike) -> tuple[float, float, float]:
    a = np.asarray(v, dtype=np.float64)
    return (float(a[0]), float(a[1]), float(a[2]))


__all__ = ["LqrDesign", "RICCATI_RTOL", "RelaxedHoverLqr", "RelaxedHoverOuterLoop", "bryson_weights"]

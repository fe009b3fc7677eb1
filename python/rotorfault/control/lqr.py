"""Trim, linearisation and LQR about hover: design in Python, run in Rust.

The linear model is the numerical Jacobian (central differences) of the simulator's own
12-state dynamics (``Simulator.state_derivative``), so it matches exactly what the Rust loop
flies: frames, drag, rotor geometry, rotor efficiency.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from .._convert import FloatArray, float_array, real
from ..allocation import Allocator
from ..simulation import FixedPitchActuator, Simulator
from .allocated import Allocated
from .linear import STATE_DIM, LinearFeedback


def hover_trim(
    simulator: Simulator, *, position: npt.ArrayLike = (0.0, 0.0, 0.0), yaw: float = 0.0
) -> tuple[FloatArray, FloatArray]:
    """``(x_trim, u_trim)``: hover at ``position`` (world NED, m) with heading ``yaw`` (rad), rotor
    thrusts the minimum-norm solution of ``B_f u = [m g, 0, 0, 0]`` with the airframe's efficiency.
    Raises ``ValueError`` if that solution leaves the thrust bounds or does not balance."""
    if not isinstance(simulator, Simulator) or not isinstance(simulator.actuator, FixedPitchActuator):
        raise TypeError("simulator: hover_trim needs a Simulator with fixed-pitch rotors")
    airframe = simulator.airframe
    b = airframe.effectiveness_matrix()
    g = np.array([airframe.hover_thrust_n, 0.0, 0.0, 0.0])
    u, *_ = np.linalg.lstsq(b, g, rcond=None)
    if np.linalg.norm(b @ u - g) > 1e-9 * airframe.hover_thrust_n:
        raise ValueError(f"{airframe.name}: no thrusts balance the weight with zero torque (rank B_f < 4)")
    if np.any(u < airframe.min_thrust_n - 1e-12) or np.any(u > airframe.max_thrust_n + 1e-12):
        raise ValueError(f"{airframe.name}: the minimum-norm hover thrusts {u} leave the thrust bounds")
    pos = float_array("position", position, 1)
    if pos.shape != (3,):
        raise ValueError("position: expected 3 entries")
    x_trim = np.zeros(STATE_DIM)
    x_trim[0:3] = pos
    x_trim[8] = real("yaw", yaw)
    return x_trim, u


def linearize(
    simulator: Simulator,
    x_trim: npt.ArrayLike,
    u_trim: npt.ArrayLike,
    efficiency: npt.ArrayLike | None = None,
    *,
    step: float = 1e-6,
) -> tuple[FloatArray, FloatArray]:
    """``(A, B)`` with ``dx/dt ~ A (x - x_trim) + B (u - u_trim)``, by central differences of
    the simulator's dynamics (relative step ``step``) with rotor ``efficiency`` (default: the
    airframe's own)."""
    x0 = float_array("x_trim", x_trim, 1)
    u0 = float_array("u_trim", u_trim, 1)
    if x0.shape != (STATE_DIM,):
        raise ValueError(f"x_trim: expected {STATE_DIM} entries, got {x0.shape[0]}")
    h = real("step", step)

    def f(x: FloatArray, u: FloatArray) -> FloatArray:
        return simulator.state_derivative(x, u, efficiency)

    a = np.empty((STATE_DIM, STATE_DIM))
    for j in range(STATE_DIM):
        d = h * max(1.0, abs(x0[j]))
        e = np.zeros(STATE_DIM)
        e[j] = d
        a[:, j] = (f(x0 + e, u0) - f(x0 - e, u0)) / (2 * d)
    b = np.empty((STATE_DIM, u0.shape[0]))
    for j in range(u0.shape[0]):
        d = h * max(1.0, abs(u0[j]))
        e = np.zeros(u0.shape[0])
        e[j] = d
        b[:, j] = (f(x0, u0 + e) - f(x0, u0 - e)) / (2 * d)
    return a, b


def lqr_hover(
    simulator: Simulator,
    *,
    q: npt.ArrayLike | None = None,
    r: npt.ArrayLike | None = None,
    position: npt.ArrayLike = (0.0, 0.0, 0.0),
    yaw: float = 0.0,
) -> LinearFeedback:
    """An LQR hover controller (python-control's ``lqr``) on the linearisation about
    :func:`hover_trim`. Default weights (Bryson's rule): 1 m position, 1 m/s velocity, 0.1 rad
    attitude, 1 rad/s rate errors against 10 % of the hover thrust per rotor."""
    import control  # type: ignore[import-untyped]

    x_trim, u_trim = hover_trim(simulator, position=position, yaw=yaw)
    a, b = linearize(simulator, x_trim, u_trim)
    q_state, r_rotor = _bryson_weights(simulator, q, r)
    gain, _, _ = control.lqr(a, b, q_state, r_rotor)
    return LinearFeedback(np.asarray(gain), x_trim, u_trim)


def lqr_hover_allocated(
    simulator: Simulator,
    allocator: Allocator,
    *,
    q: npt.ArrayLike | None = None,
    r: npt.ArrayLike | None = None,
    position: npt.ArrayLike = (0.0, 0.0, 0.0),
    yaw: float = 0.0,
) -> Allocated:
    """An LQR hover controller on the virtual control, followed by constrained allocation.

    The design model is the linearisation of :func:`lqr_hover` with the rotor thrusts replaced by
    ``T = P v`` (``P`` the allocator's weighted pseudo-inverse, which the constrained allocation
    equals while no bound is active), so ``B_v = B P``. ``r`` (rotor units, default as
    :func:`lqr_hover`) becomes ``P^T r P``. The virtual trim is ``M u_trim``. Returns an
    :class:`~rotorfault.control.Allocated` that runs entirely in Rust."""
    import control

    if not isinstance(allocator, Allocator):
        raise TypeError(f"allocator: expected a rotorfault.allocation.Allocator, got {type(allocator).__name__}")
    if allocator.virtual_dimension != 4:
        raise ValueError(
            "allocator: LQR on the virtual control needs thrust, roll, pitch and yaw rows (a vehicle "
            "that gives up yaw spins, which a hover linearisation cannot describe)"
        )
    if np.any(allocator.weights == 0):
        raise ValueError("allocator.weights: LQR on the virtual control needs every weight > 0")
    if allocator.regularization != 0:
        raise ValueError("allocator.regularization: must be 0 here (the trim would not map back to itself)")
    x_trim, u_trim = hover_trim(simulator, position=position, yaw=yaw)
    if allocator.actuator_count != u_trim.shape[0]:
        raise ValueError(
            f"allocator: has {allocator.actuator_count} actuators, the simulator's airframe {u_trim.shape[0]}"
        )
    a, b = linearize(simulator, x_trim, u_trim)
    n = allocator.virtual_dimension
    offset = allocator.allocate(np.zeros(n), method="pinv").commands
    p = allocator.allocate(np.eye(n), method="pinv").commands.T - offset[:, None]
    q_state, r_rotor = _bryson_weights(simulator, q, r)
    r_virtual = p.T @ r_rotor @ p
    gain, _, _ = control.lqr(a, b @ p, q_state, 0.5 * (r_virtual + r_virtual.T))
    v_trim = allocator.matrix @ u_trim
    return Allocated(LinearFeedback(np.asarray(gain), x_trim, v_trim), allocator)


def _bryson_weights(
    simulator: Simulator, q: npt.ArrayLike | None, r: npt.ArrayLike | None
) -> tuple[FloatArray, FloatArray]:
    """``q`` and ``r`` (rotor units) as given, or Bryson's rule: 1 m position, 1 m/s velocity,
    0.1 rad attitude, 1 rad/s rate errors against 10 % of the hover thrust per rotor."""
    if q is None:
        scale = np.array([1.0] * 3 + [1.0] * 3 + [0.1] * 3 + [1.0] * 3)
        q = np.diag(1.0 / scale**2)
    if r is None:
        per_rotor = 0.1 * simulator.airframe.hover_thrust_n / simulator.airframe.rotor_count
        r = np.eye(simulator.command_count) / per_rotor**2
    return float_array("q", q, 2), float_array("r", r, 2)


__all__ = ["hover_trim", "linearize", "lqr_hover", "lqr_hover_allocated"]

"""Trim, linearisation and LQR about hover: design in Python, run in Rust.

The trim is the equilibrium of the simulator's own dynamics (``Simulator.state_derivative``):
drag of the constant ``wind`` included, so the hover attitude leans into the wind. The linear model
is the numerical Jacobian of the same dynamics, so it matches what the Rust loop flies: frames,
drag, rotor geometry, rotor efficiency.

Rules (README, "Decisions"):

- a hover trim whose thrusts must put a rotor on a thrust bound is returned with that rotor named
  in :attr:`HoverTrim.saturated_rotors`; :func:`lqr_hover` refuses it (and any airframe whose ACAI is
  <= 0), because a linear controller about a saturated trim loses the directions it would need;
- the gains are :func:`~rotorfault.control.riccati.design_lqr`'s, the one LQR on every install,
  checked before they are returned (stabilisability with the modes named, detectability of the
  weights, Riccati residual, closed loop, and the sampled loop at ``simulator.dt_s``);
- :func:`linearize` never differentiates across a command bound: at a bound it takes the one-sided
  difference pointing into the box;
- :func:`linearize` refuses ``|pitch| > max_pitch_rad`` (default 80 degrees): the Euler rates divide
  by ``cos(pitch)``, so the model's entries grow as ``1 / cos^2(pitch)`` and its range of validity
  shrinks as ``cos(pitch)`` (beyond 80 degrees a 1-degree pitch change moves the yaw rate 11 % away
  from the linear prediction).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Protocol, cast, overload

import numpy as np
import numpy.typing as npt

from .._util.convert import FloatArray, float_array, frozen_array, real
from .._util.deprecation import warn
from .._util.numeric import scaled_norm
from ..analysis.airframe import Airframe, rotor_labels
from ..allocation import Allocator
from ..analysis.acai import acai, acai_label
from ..flight import FixedPitchActuator, Simulator, VariablePitchActuator
from .allocated import Allocated
from .linear import STATE_DIM, STATE_LABELS, STATE_NAMES, LinearFeedback
from .riccati import LqrDesign, design_lqr

if TYPE_CHECKING:
    from .systems import LinearModel

#: A rotor whose hover thrust cannot be moved further than this fraction of its thrust range from
#: a bound is on that bound (the same relative size as ``ZERO_RTOL`` for the ACAI).
SATURATION_RTOL = 1e-9

#: Default largest ``|pitch|`` :func:`linearize` accepts, rad (80 degrees; see the module notes).
MAX_PITCH_RAD = math.radians(80.0)

#: The largest ``max_pitch_rad`` allowed: central differences of the Euler rates stay within 1e-8
#: (relative) of the analytic derivatives up to 89 degrees, 8e-5 at 89.99 and 430 % at 89.9999.
PITCH_LIMIT_CAP_RAD = math.radians(89.0)


#: Largest ``||f(state, command)||`` a trim may leave (m/s^2 and rad/s^2 together): the presets'
#: trims leave 1e-13; a trim above this is not an equilibrium and is never returned as one.
TRIM_RESIDUAL_TOL = 1e-8


@dataclass(frozen=True)
class HoverTrim:
    """A hover equilibrium of a simulator.

    ``state``: the 12-element state vector (position as asked, zero velocity and body rates,
    the roll and pitch that lean the thrust into the wind, yaw as asked); ``command``: rotor
    thrusts (N); ``residual``: ``||f(state, command)||`` of ``Simulator.state_derivative``, the
    size of the acceleration the trim leaves unbalanced; ``saturated_rotors``: the 1-based rotors
    that every hover solution puts on a thrust bound (empty when an interior trim exists).

    Examples:

        >>> import rotorfault as rf
        >>> trim = rf.hover_trim(rf.Simulator(rf.Airframe.preset("quad-x")), position=(0, 0, -2), yaw=0.5)
        >>> trim.state[[2, 8]].tolist(), trim.residual < 1e-9
        ([-2.0, 0.5], True)
    """

    state: FloatArray
    command: FloatArray
    residual: float
    saturated_rotors: tuple[int, ...]

    @property
    def saturated(self) -> bool:
        """Whether hover needs a rotor on a thrust bound."""
        return bool(self.saturated_rotors)

    @property
    def balanced(self) -> bool:
        """The evidence holds: ``residual`` at most :data:`TRIM_RESIDUAL_TOL` (a returned trim
        always is: :func:`hover_trim` raises otherwise)."""
        return bool(self.residual <= TRIM_RESIDUAL_TOL)


def hover_trim(simulator: Simulator, *, position: npt.ArrayLike = (0.0, 0.0, 0.0), yaw: float = 0.0) -> HoverTrim:
    """The hover equilibrium at ``position`` (world NED, m) with heading ``yaw`` (rad): zero
    velocity and body rates, the attitude whose thrust balances gravity plus the drag of the
    simulator's constant ``wind`` (a ``wind_profile`` is a disturbance, not part of the trim), and
    rotor thrusts that give that total thrust with zero torque.

    Thrusts: the minimum-norm solution of ``B_f u = [T, 0, 0, 0]`` (``B_f`` with the airframe's
    efficiency; failed rotors at the in-bounds thrust closest to 0) when it lies strictly inside
    the thrust bounds; otherwise the solution farthest from the bounds (an LP). When every solution
    has a rotor on a bound, those rotors are named in ``saturated_rotors`` (and sit exactly on it).
    Raises ``ValueError`` when no thrusts within the bounds balance the vehicle.

    Examples:

        >>> import rotorfault as rf
        >>> trim = rf.hover_trim(rf.Simulator(rf.Airframe.preset("quad-x")))
        >>> trim.command.round(4).tolist(), trim.saturated_rotors
        ([3.7607, 3.7608, 3.7608, 3.7608], ())
    """
    if not isinstance(simulator, Simulator) or not isinstance(simulator.actuator, FixedPitchActuator):
        raise TypeError("simulator: hover_trim needs a rotorfault.Simulator with fixed-pitch rotors")
    pos = float_array("position", position, 1)
    if pos.shape != (3,):
        raise ValueError(f"position: expected 3 entries, got {pos.shape[0]}")
    if not np.all(np.isfinite(pos)):
        raise ValueError("position: must be finite")
    heading = real("yaw", yaw)
    if not math.isfinite(heading):
        raise ValueError(f"yaw: must be finite, got {heading}")
    airframe = simulator.airframe
    lower, upper = airframe.min_thrust_n, airframe.max_thrust_n
    x = np.zeros(STATE_DIM)
    x[0:3] = pos
    x[8] = heading
    # Gravity and drag at rest with every rotor's thrust switched off: the acceleration the
    # thrust must cancel (drag does not depend on the attitude, only on v - wind).
    m = airframe.rotor_count
    passive = simulator.state_derivative(x, np.clip(np.zeros(m), lower, upper), np.zeros(m))[3:6]
    if not passive[2] > 0:
        raise ValueError(
            f"wind: the drag of wind {simulator.wind} m/s outweighs gravity along the vertical "
            f"(passive acceleration {passive} m/s^2): no upright hover"
        )
    thrust = airframe.mass_kg * scaled_norm(passive)
    # Body z (down) in the world must point along the passive acceleration; undo the heading.
    c, s = math.cos(heading), math.sin(heading)
    axis = passive / scaled_norm(passive)
    n, e, d = c * axis[0] + s * axis[1], -s * axis[0] + c * axis[1], axis[2]
    x[6] = math.asin(max(-1.0, min(1.0, -e))) + 0.0  # roll (+ 0.0: no -0.0)
    x[7] = math.atan2(n, d)  # pitch
    command, saturated = _hover_thrusts(airframe, thrust)
    residual = scaled_norm(simulator.state_derivative(x, command))
    if not residual <= TRIM_RESIDUAL_TOL:
        raise ValueError(
            f"trim residual: the hover of {airframe.name} leaves ||f(x, u)|| = {residual:.3g} (at most "
            f"{TRIM_RESIDUAL_TOL:g}): the thrusts found do not balance the model at this attitude"
        )
    return HoverTrim(frozen_array("state", x, 1), frozen_array("command", command, 1), residual, saturated)


def _hover_thrusts(airframe: Airframe, thrust: float) -> tuple[FloatArray, tuple[int, ...]]:
    """Rotor thrusts for ``B_f u = [thrust, 0, 0, 0]`` within the bounds, and the rotors every
    solution puts on a bound (rules in :func:`hover_trim`)."""
    from scipy.optimize import linprog  # type: ignore[import-untyped]

    lower, upper = airframe.min_thrust_n, airframe.max_thrust_n
    command = np.clip(np.zeros(airframe.rotor_count), lower, upper)
    active = np.flatnonzero(airframe.efficiency > 0)
    b = airframe.effectiveness_matrix()[:, active]
    wrench = np.array([thrust, 0.0, 0.0, 0.0])
    lo, hi = lower[active], upper[active]
    span = hi - lo
    u, *_ = np.linalg.lstsq(b, wrench, rcond=None)
    if scaled_norm(b @ u - wrench) > 1e-9 * thrust:
        raise ValueError(
            f"{airframe.name}: no rotor thrusts give {thrust:.6g} N with zero torque (rank B_f < 4 "
            "and the hover wrench outside its range)"
        )
    if np.min(np.minimum(u - lo, hi - u) / span) > SATURATION_RTOL:
        command[active] = u
        return command, ()
    k = active.shape[0]
    options = {"primal_feasibility_tolerance": 1e-10, "dual_feasibility_tolerance": 1e-10}

    def farthest(weights: FloatArray, free_bounds: bool) -> tuple[float, FloatArray]:
        # max t  s.t.  B u = w,  t span_i <= u_i - lo_i,  t span_i <= hi_i - u_i  (i weighted)
        rows = np.flatnonzero(weights)
        a_ub = np.zeros((2 * rows.shape[0], k + 1))
        a_ub[: rows.shape[0], rows] = -np.eye(k)[rows][:, rows]
        a_ub[rows.shape[0] :, rows] = np.eye(k)[rows][:, rows]
        a_ub[:, k] = np.concatenate([span[rows], span[rows]])
        b_ub = np.concatenate([-lo[rows], hi[rows]])
        box = [(None, None)] * k if free_bounds else list(zip(lo, hi))
        result = linprog(
            np.eye(k + 1)[k] * -1.0, A_ub=a_ub, b_ub=b_ub, A_eq=np.hstack([b, np.zeros((4, 1))]), b_eq=wrench,
            bounds=[*box, (None, 0.5)], method="highs", options=options,
        )
        if result.status != 0:
            raise ValueError(f"{airframe.name}: the hover-thrust LP failed ({result.message})")
        return -float(result.fun), np.asarray(result.x[:k], dtype=np.float64)

    margin, u = farthest(np.ones(k), free_bounds=True)
    if margin < -SATURATION_RTOL:
        raise ValueError(
            f"{airframe.name}: hover needs {thrust:.6g} N with zero torque, which no thrusts within the "
            f"rotors' bounds give (the best solution is {-margin:.3g} of a rotor's thrust range beyond a bound)"
        )
    if margin <= SATURATION_RTOL:
        # Which rotors can no solution move off their bound? One LP per rotor.
        forced = np.array([farthest(np.eye(k)[i], free_bounds=False)[0] <= SATURATION_RTOL for i in range(k)])
        if not np.all(forced):
            margin, u = farthest((~forced).astype(np.float64), free_bounds=False)
        near_lower = np.abs(u - lo) <= np.abs(hi - u)
        u = np.where(forced, np.where(near_lower, lo, hi), u)
        saturated = tuple(int(active[i]) + 1 for i in np.flatnonzero(forced))
    else:
        saturated = ()
    command[active] = u
    return command, saturated


def _command_bounds(simulator: Simulator) -> tuple[FloatArray, FloatArray, list[str]]:
    """Per-channel command bounds and a label for each channel (errors name the rotor)."""
    m = simulator.airframe.rotor_count
    actuator = simulator.actuator
    if isinstance(actuator, VariablePitchActuator):
        lo = np.tile([actuator.speed_bounds[0], actuator.pitch_bounds[0]], m).astype(np.float64)
        hi = np.tile([actuator.speed_bounds[1], actuator.pitch_bounds[1]], m).astype(np.float64)
        return lo, hi, [f"rotor {j // 2 + 1} {'pitch' if j % 2 else 'speed'}" for j in range(2 * m)]
    return simulator.airframe.min_thrust_n, simulator.airframe.max_thrust_n, [f"rotor {j + 1}" for j in range(m)]


class OperatingPoint(Protocol):
    """What :func:`linearize` linearises about: a state and a command (:class:`HoverTrim`,
    :class:`rotorfault.vpp.VppTrim`)."""

    @property
    def state(self) -> FloatArray: ...
    @property
    def command(self) -> FloatArray: ...


@overload
def linearize(
    simulator: Simulator,
    trim: OperatingPoint | tuple[npt.ArrayLike, npt.ArrayLike],
    u_trim: None = None,
    efficiency: npt.ArrayLike | None = None,
    *,
    step: float = ...,
    max_pitch_rad: float = ...,
) -> LinearModel: ...
@overload
def linearize(
    simulator: Simulator,
    trim: npt.ArrayLike,
    u_trim: npt.ArrayLike,
    efficiency: npt.ArrayLike | None = None,
    *,
    step: float = ...,
    max_pitch_rad: float = ...,
) -> tuple[FloatArray, FloatArray]: ...
def linearize(
    simulator: Simulator,
    trim: OperatingPoint | tuple[npt.ArrayLike, npt.ArrayLike] | npt.ArrayLike,
    u_trim: npt.ArrayLike | None = None,
    efficiency: npt.ArrayLike | None = None,
    *,
    step: float = 1e-6,
    max_pitch_rad: float = MAX_PITCH_RAD,
) -> LinearModel | tuple[FloatArray, FloatArray]:
    """The linear model ``dx/dt ~ A (x - x_trim) + B (u - u_trim)`` of the simulator about
    ``trim``, a python-control ``StateSpace``: ``linearize(simulator, trim)`` with ``trim`` from
    :func:`hover_trim` (or :func:`rotorfault.vpp.trim`; anything with ``state`` and ``command``,
    or a pair ``(state, command)``) returns a
    :class:`~rotorfault.control.systems.LinearModel` (states ``x ... r``, inputs ``thrust_<i>`` or
    ``omega_<i>``/``alpha_<i>``, outputs the states, and the operating point ``x_trim``,
    ``u_trim``). ``efficiency``: the rotors' (default: the airframe's own).

    ``A`` and ``B`` are central differences of the simulator's dynamics (relative step ``step``).
    A command on one of its bounds is differentiated one-sidedly into the box (second order), never
    across the clamp; a command outside its bounds is a ``ValueError``. ``|pitch|`` beyond
    ``max_pitch_rad`` (default 80 degrees, at most 89) is a ``ValueError``: the Euler-angle model is
    singular at 90 degrees (module notes).

    Deprecated (one release): ``linearize(simulator, x_trim, u_trim[, efficiency])`` with arrays
    returns the tuple ``(A, B)``.

    Examples:

        >>> import rotorfault as rf
        >>> sim = rf.Simulator(rf.Airframe.preset("quad-x"))
        >>> model = rf.linearize(sim, rf.hover_trim(sim))
        >>> model.nstates, model.input_labels
        (12, ['thrust_1', 'thrust_2', 'thrust_3', 'thrust_4'])
    """
    if not isinstance(simulator, Simulator):
        raise TypeError(f"simulator: expected rotorfault.Simulator, got {type(simulator).__name__}")
    if u_trim is not None:
        warn("linearize(simulator, x_trim, u_trim) returning (A, B)", "linearize(simulator, trim), a control.StateSpace (.A, .B)")
        return _jacobians(simulator, cast(Any, trim), u_trim, efficiency, step, max_pitch_rad)
    point: Any = trim
    if hasattr(point, "state") and hasattr(point, "command"):
        x0, u0 = point.state, point.command
    elif isinstance(point, tuple) and len(point) == 2:
        x0, u0 = point
    else:
        raise TypeError(
            f"trim: expected a HoverTrim (rotorfault.hover_trim), a VppTrim or a pair (state, command), got {type(trim).__name__}"
        )
    a, b = _jacobians(simulator, x0, u0, efficiency, step, max_pitch_rad)
    return linear_model(simulator, a, b, x0, u0, range(b.shape[1]))


def linear_model(simulator: Simulator, a: FloatArray, b: FloatArray, x_trim: npt.ArrayLike, u_trim: npt.ArrayLike, columns: Any) -> LinearModel:
    """``(a, b)`` of ``simulator`` about ``(x_trim, u_trim)`` as a named
    :class:`~rotorfault.control.systems.LinearModel`, ``b``'s columns being the command channels
    ``columns`` (all of them, or a subset: ``b`` then has only those)."""
    from .systems import LinearModel, input_names

    names = input_names(simulator.command_count, simulator.airframe.rotor_count)
    kept = list(columns)
    return LinearModel(a, b, inputs=[names[j] for j in kept], x_trim=x_trim, u_trim=u_trim, command_columns=kept,
                       name=f"{simulator.airframe.name} linearisation")


def _jacobians(
    simulator: Simulator, x_trim: npt.ArrayLike, u_trim: npt.ArrayLike, efficiency: npt.ArrayLike | None, step: float, max_pitch_rad: float,
) -> tuple[FloatArray, FloatArray]:
    """``(A, B)`` by central differences (the rules of :func:`linearize`)."""
    x0 = float_array("x_trim", x_trim, 1)
    u0 = float_array("u_trim", u_trim, 1)
    if x0.shape != (STATE_DIM,):
        raise ValueError(f"x_trim: expected {STATE_DIM} entries, got {x0.shape[0]}")
    if u0.shape != (simulator.command_count,):
        raise ValueError(f"u_trim: expected {simulator.command_count} entries (one per command channel), got {u0.shape[0]}")
    if not (np.all(np.isfinite(x0)) and np.all(np.isfinite(u0))):
        raise ValueError("x_trim, u_trim: must be finite")
    h = real("step", step)
    if not (math.isfinite(h) and 0 < h <= 1e-2):
        raise ValueError(f"step: must lie in (0, 0.01], got {h}")
    limit = real("max_pitch_rad", max_pitch_rad)
    if not 0 < limit <= PITCH_LIMIT_CAP_RAD:
        raise ValueError(f"max_pitch_rad: must lie in (0, {PITCH_LIMIT_CAP_RAD:.6f}] (89 degrees), got {limit}")
    if abs(x0[7]) > limit:
        raise ValueError(
            f"x_trim[7]: pitch {math.degrees(x0[7]):.4f} degrees is beyond the {math.degrees(limit):.4g}-degree "
            "limit of the Euler-angle linearisation (the Euler rates divide by cos(pitch), singular at 90 degrees)"
        )
    lower, upper, labels = _command_bounds(simulator)
    for j in range(u0.shape[0]):
        slack = 1e-12 * max(1.0, abs(lower[j]), abs(upper[j]))
        if not lower[j] - slack <= u0[j] <= upper[j] + slack:
            raise ValueError(
                f"u_trim[{j}]: {labels[j]}'s command {u0[j]} lies outside its bounds [{lower[j]}, {upper[j]}] "
                "(the simulator clamps it: there is no derivative to take)"
            )
    u0 = np.clip(u0, lower, upper)

    def f(x: FloatArray, u: FloatArray) -> FloatArray:
        return simulator.state_derivative(x, u, efficiency)

    a = np.empty((STATE_DIM, STATE_DIM))
    for j in range(STATE_DIM):
        d = h * max(1.0, abs(x0[j]))
        e = np.zeros(STATE_DIM)
        e[j] = d
        a[:, j] = (f(x0 + e, u0) - f(x0 - e, u0)) / (2 * d)
    b = np.empty((STATE_DIM, u0.shape[0]))
    f0 = f(x0, u0)
    for j in range(u0.shape[0]):
        d = h * max(1.0, abs(u0[j]))
        e = np.zeros(u0.shape[0])
        e[j] = d
        if u0[j] - d >= lower[j] and u0[j] + d <= upper[j]:
            b[:, j] = (f(x0, u0 + e) - f(x0, u0 - e)) / (2 * d)
        elif u0[j] + 2 * d <= upper[j]:
            b[:, j] = (-3 * f0 + 4 * f(x0, u0 + e) - f(x0, u0 + 2 * e)) / (2 * d)
        elif u0[j] - 2 * d >= lower[j]:
            b[:, j] = (3 * f0 - 4 * f(x0, u0 - e) + f(x0, u0 - 2 * e)) / (2 * d)
        else:
            raise ValueError(f"u_trim[{j}]: {labels[j]}'s bounds [{lower[j]}, {upper[j]}] are narrower than the step")
    return a, b


def lqr_hover(
    simulator: Simulator,
    *,
    q: npt.ArrayLike | None = None,
    r: npt.ArrayLike | None = None,
    position: npt.ArrayLike = (0.0, 0.0, 0.0),
    yaw: float = 0.0,
) -> LinearFeedback:
    """An LQR hover controller (:func:`~rotorfault.control.riccati.design_lqr`) on the
    linearisation about :func:`hover_trim` at ``position`` (NED, m) and ``yaw`` (rad). Default weights (Bryson's rule): 1 m position, 1 m/s
    velocity, 0.1 rad attitude, 1 rad/s rate errors against 10 % of the hover thrust per rotor.
    The returned feedback's ``design`` carries the evidence (Riccati residual, closed-loop
    eigenvalues, the sampled loop at ``simulator.dt_s``, the PBH tests).

    Raises ``ValueError`` for a hover it cannot hold: an airframe whose ACAI is <= 0 (Du et al.:
    no control authority around hover; ``-inf`` when ``rank B_f < 4``), a trim with a rotor on a
    thrust bound, or a design check that fails (a model that is not stabilisable, named by its
    modes; weights that do not see an unstable mode; a gain whose sampled loop at
    ``simulator.dt_s`` is unstable).

    Examples:

        >>> import rotorfault as rf
        >>> feedback = rf.lqr_hover(rf.Simulator(rf.Airframe.preset("quad-x")))
        >>> feedback.gain.shape, bool(feedback.design.closed_loop_eigenvalues.real.max() < 0)
        ((4, 12), True)
    """
    trim = hover_trim(simulator, position=position, yaw=yaw)
    _require_holdable(simulator, trim)
    model = linearize(simulator, trim)
    q_state, r_rotor = _bryson_weights(simulator, q, r)
    design = _lqr_design(simulator, model.A, model.B, q_state, r_rotor, "rotor thrusts")
    return LinearFeedback(design.gain, trim.state, trim.command, design=design)


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
    :func:`lqr_hover`) becomes ``P^T r P``. The virtual trim is ``M u_trim``. The hover held: ``position`` (NED, m)
    and ``yaw`` (rad), as for :func:`lqr_hover`. Refuses what
    :func:`lqr_hover` refuses. Returns an :class:`~rotorfault.control.Allocated` that runs entirely
    in Rust.

    Examples:

        >>> import rotorfault as rf
        >>> quad = rf.Airframe.preset("quad-x")
        >>> sim = rf.Simulator(quad)
        >>> controller = rf.lqr_hover_allocated(sim, rf.Allocator(quad), position=(0, 0, -1))
        >>> run = sim.run(rf.State(position=(0, 0, -1)), 1.0, controller=controller)
        >>> round(float(abs(run.position[-1] - (0, 0, -1)).max()), 6)
        0.0
    """
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
    trim = hover_trim(simulator, position=position, yaw=yaw)
    if allocator.actuator_count != trim.command.shape[0]:
        raise ValueError(
            f"allocator: has {allocator.actuator_count} actuators, the simulator's airframe {trim.command.shape[0]}"
        )
    _require_holdable(simulator, trim)
    model = linearize(simulator, trim)
    a, b = model.A, model.B
    n = allocator.virtual_dimension
    offset = allocator._pinv_commands(np.zeros((1, n)))[0]
    p = allocator._pinv_commands(np.eye(n)).T - offset[:, None]
    q_state, r_rotor = _bryson_weights(simulator, q, r)
    r_virtual = p.T @ r_rotor @ p
    v_trim = allocator.matrix @ trim.command
    pinv_trim = offset + p @ v_trim
    if np.max(np.abs(pinv_trim - trim.command)) > 1e-9 * max(1.0, float(np.max(np.abs(trim.command)))):
        raise ValueError(
            f"allocator: its pseudo-inverse gives the hover thrusts {pinv_trim}, not the trim {trim.command} "
            "(the minimum-norm hover thrusts leave the bounds), so the design model B P does not hold at "
            "the trim; use lqr_hover"
        )
    design = _lqr_design(simulator, a, b @ p, q_state, 0.5 * (r_virtual + r_virtual.T), "virtual control through the allocator")
    return Allocated(LinearFeedback(design.gain, trim.state, v_trim, design=design), allocator)


def _hover_lqi(simulator: Simulator, position: npt.ArrayLike, integral_scale_m_s: npt.ArrayLike, model: str) -> tuple[HoverTrim, LqrDesign]:
    """The hover LQR of :func:`lqr_hover` (its trim, holdability check and Bryson weights) on the
    model augmented by the integral of the position error (north, east, down; LQI), the integrals
    weighted by ``integral_scale_m_s`` (m s, Bryson); designed and checked by
    :func:`~rotorfault.control.riccati.design_lqr`, the sampled loop included. Returns the trim and
    the design, whose gain is commands x (12 states + 3 integrals)."""
    trim = hover_trim(simulator, position=position)
    _require_holdable(simulator, trim)
    linear = linearize(simulator, trim)
    a, b = np.asarray(linear.A), np.asarray(linear.B)
    n, m = a.shape[0], b.shape[1]
    a_aug = np.zeros((n + 3, n + 3))
    a_aug[:n, :n] = a
    a_aug[n:, :3] = np.eye(3)  # d/dt of the integral is the position error
    b_aug = np.vstack([b, np.zeros((3, m))])
    q, r = _bryson_weights(simulator, None, None)
    q_aug = np.zeros((n + 3, n + 3))
    q_aug[:n, :n] = q
    q_aug[n:, n:] = np.diag(1.0 / np.asarray(integral_scale_m_s, dtype=np.float64) ** 2)
    design = design_lqr((a_aug, b_aug), q_aug, r, dt_s=simulator.dt_s,
                        state_names=(*STATE_NAMES, "int_x", "int_y", "int_z"), model=model)
    return trim, design


def _require_holdable(simulator: Simulator, trim: HoverTrim) -> None:
    """``ValueError`` unless the airframe has control authority around hover (ACAI > 0) and the
    trim leaves every rotor off its bounds."""
    airframe = simulator.airframe
    reasons = []
    index = float(acai(airframe))
    if not index > 0:
        why = "rank B_f < 4: some axis has no control at all" if index == -math.inf else "no control authority margin around hover"
        reasons.append(f"{acai_label('eq13')} = {index:.6g} <= 0 ({why})")
    if trim.saturated_rotors:
        bounds = [
            f"{trim.command[i - 1]:.6g} N" for i in trim.saturated_rotors
        ]
        reasons.append(
            f"hover needs rotor(s) {rotor_labels(trim.saturated_rotors)} on a thrust bound ({', '.join(bounds)}), "
            "where a linear controller cannot push both ways"
        )
    if reasons:
        raise ValueError(
            f"{airframe.name} (efficiency {list(map(float, airframe.efficiency))}): LQR cannot hold this hover: "
            + "; ".join(reasons)
        )


def _lqr_design(simulator: Simulator, a: FloatArray, b: FloatArray, q: FloatArray, r: FloatArray, what: str) -> LqrDesign:
    """The checked LQR (:func:`~rotorfault.control.riccati.design_lqr`) of the hover model, its
    sampled loop at the simulator's control period; errors name the airframe and the check."""
    airframe = simulator.airframe
    return design_lqr(
        (a, b), q, r, dt_s=simulator.dt_s, state_names=STATE_NAMES, state_labels=STATE_LABELS,
        model=f"the hover linearisation of {airframe.name} ({what}, efficiency {list(map(float, airframe.efficiency))})",
    )


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


__all__ = [
    "MAX_PITCH_RAD",
    "PITCH_LIMIT_CAP_RAD",
    "SATURATION_RTOL",
    "HoverTrim",
    "hover_trim",
    "linear_model",
    "linearize",
    "lqr_hover",
    "lqr_hover_allocated",
]

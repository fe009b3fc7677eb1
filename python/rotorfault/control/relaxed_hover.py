"""An LQR about a relaxed hover (Mueller and D'Andrea's cascade), designed here and run in Rust.

The analysis (:func:`rotorfault.relaxed_hover`) gives each solution's linear model, time-invariant
in body axes: state ``x = [a, b, dp, dq, dr, z, w]`` (the up axis seen from the body,
``n + a e1 + b e2``; body-rate deviation; altitude up and its rate), input the carrying rotors'
thrust deviations. :class:`RelaxedHoverFeedback` designs ``K`` on it (continuous-time Riccati equation,
checked: residual, closed-loop eigenvalues, and the loop sampled at the control period) and runs
``u = u_trim - K x`` in Rust with an outer loop that tilts the up axis towards the set point
(:class:`rotorfault._rfcore.RelaxedHoverFeedback`). Idle and failed rotors stay at their trim.

A failure-time switch (``before_failure=``, ``failure_time_s=``): before the failure the vehicle is flown
by the healthy-vehicle design (a hover LQR, :func:`rotorfault.control.lqr_hover` on the healthy
airframe), from the first control step at or after ``failure_time_s`` by the relaxed hover LQR.
This is passive fault-tolerant control with the failure (which rotors, how deep) and its time
known in advance, as a perfect fault detection would report them: the switch is not a detector.

Integral action before the failure and a bumpless hand-over (``before_failure_integral_gain=``,
``before_failure_integral_limit_m_s=``): the healthy design also feeds back the integral of the
position error (``u = u_lqr - K_I`` times the integral of ``p - p_set``, ``K_I`` from an LQR on the hover model
augmented by the integral), so a vehicle heavier or weaker than its design does not sit metres
below its set point when the failure comes; at the failure the relaxed hover's altitude integral
starts where it gives the same vertical acceleration as the healthy loop's
(:attr:`RelaxedHoverFeedback.handover_altitude_ratio`), its horizontal integral where it gives
the steady acceleration the healthy loop's horizontal integral gave
(:attr:`RelaxedHoverFeedback.handover_horizontal_ratio`): what the integrals learnt (weight, wind)
is carried on, not a transient such as the braking tilt of a failure in forward flight
(``rotorfault._rfcore`` ``hover_handover``).
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from .. import _rfcore
from .._util.convert import FloatArray, float_array, real
from ..analysis.airframe import Airframe, require_airframe
from ..analysis.relaxed_hover import RelaxedHoverSolution, _three, circle_offsets
from ..flight.state import State
from .linear import LinearFeedback
from .riccati import CLOSED_LOOP_RTOL, LqrDesign, design_lqr, sampled_spectral_radius

RelaxedHoverOuterLoop = _rfcore.RelaxedHoverOuterLoop

#: The states of a relaxed hover's linear model (module notes), as the LQR's refusals name them.
LINEAR_STATE_NAMES = ("a", "b", "dp", "dq", "dr", "z", "w")


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


class RelaxedHoverFeedback:
    """Holds a relaxed hover ``solution`` of ``airframe`` (the airframe it was computed for, with
    its efficiencies) at ``position`` (world NED, m): LQR on the solution's linear model with weights
    ``q`` (7 x 7) and ``r`` (carrying rotors square; default :func:`bryson_weights`), commands in
    rotor command units (thrust over efficiency), and the outer loop ``outer_loop``.
    ``linear_drag_n_s_m`` is the simulator's translational drag (it shapes the circle the centre
    of mass describes, which the outer loop must not chase). ``before_failure`` (a
    :class:`~rotorfault.control.LinearFeedback`, the healthy vehicle's hover LQR) and
    ``failure_time_s`` (s, >= 0), given together: ``before_failure`` flies until the failure time, this
    LQR from then on (the module notes: the failure and its time are known).
    ``before_failure_integral_gain`` (commands x 3, rotor command units per m s of the north,
    east, down position error's integral) and ``before_failure_integral_limit_m_s`` (3 limits,
    m s, > 0), given together and with ``before_failure``: integral action before the failure and
    a bumpless hand-over of the integrals (module notes).

    Examples:

        >>> import rotorfault as rf
        >>> quad = rf.Airframe.preset("ke-quadcopter").with_failed_rotors([1])
        >>> drag = rf.Drag(rotational_n_m_s=2.8e-3)
        >>> solution = rf.relaxed_hover(quad, rf.RelaxedHoverSettings(rotational_drag_n_m_s=2.8e-3, grid_points=21)).best
        >>> hold = rf.RelaxedHoverFeedback(solution, quad, position=(0, 0, -2))
        >>> run = rf.Simulator(quad, drag=drag).run(rf.periodic_state(solution, quad, position=(0, 0, -2)), 2.0, controller=hold)
        >>> run.events, round(float(abs(run.position[-1, 2] + 2)), 2)
        ([], 0.0)
    """

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
        before_failure: LinearFeedback | None = None,
        failure_time_s: float | None = None,
        before_failure_integral_gain: npt.ArrayLike | None = None,
        before_failure_integral_limit_m_s: npt.ArrayLike | None = None,
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
        self.design: LqrDesign = design_lqr(
            (a, b), self.q, self.r, state_names=LINEAR_STATE_NAMES, model="the relaxed hover's linear model"
        )
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
        if before_failure is not None and not isinstance(before_failure, LinearFeedback):
            raise TypeError(f"before_failure: expected rotorfault.control.LinearFeedback (a hover LQR), got {type(before_failure).__name__}")
        if (before_failure is None) != (failure_time_s is None):
            raise ValueError("before_failure, failure_time_s: give both (the healthy-vehicle design and when it hands over) or neither")
        if failure_time_s is not None:
            failure_time_s = real("failure_time_s", failure_time_s)
            if not (math.isfinite(failure_time_s) and failure_time_s >= 0):
                raise ValueError(f"failure_time_s: must be finite and >= 0, got {failure_time_s}")
        if before_failure is not None and before_failure.u_trim.shape != self.u_trim.shape:
            raise ValueError(f"before_failure: commands {before_failure.u_trim.shape[0]} rotors, the relaxed hover {self.u_trim.shape[0]}")
        #: The healthy-vehicle design flying until ``failure_time_s`` (s); ``None``: no switch.
        #: The actuators start at its trim (:func:`rotorfault.flight.simulator.trim_command`).
        self.before_failure = before_failure
        self.failure_time_s = failure_time_s
        if (before_failure_integral_gain is None) != (before_failure_integral_limit_m_s is None):
            raise ValueError("before_failure_integral_gain, before_failure_integral_limit_m_s: give both or neither")
        if before_failure_integral_gain is not None and before_failure is None:
            raise ValueError("before_failure_integral_gain: needs before_failure and failure_time_s (the design it adds to)")
        #: ``K_I`` of the healthy design (commands x 3) and each axis's integral limit (m s); None: no integral.
        self.before_failure_integral_gain = None if before_failure_integral_gain is None else float_array(
            "before_failure_integral_gain", before_failure_integral_gain, 2)
        self.before_failure_integral_limit_m_s = None if before_failure_integral_limit_m_s is None else float_array(
            "before_failure_integral_limit_m_s", before_failure_integral_limit_m_s, 1)
        if self.before_failure_integral_gain is not None:
            if self.before_failure_integral_gain.shape != (self.u_trim.shape[0], 3):
                raise ValueError(f"before_failure_integral_gain: expected {self.u_trim.shape[0]} x 3 (commands x north, east, down), "
                                 f"got {self.before_failure_integral_gain.shape}")
            if self.before_failure_integral_limit_m_s is None or self.before_failure_integral_limit_m_s.shape != (3,):
                raise ValueError("before_failure_integral_limit_m_s: expected 3 entries (north, east, down; m s)")
            # Checked here, before any run: the core would refuse them only when a run starts.
            if not np.all(np.isfinite(self.before_failure_integral_gain)):
                raise ValueError("before_failure_integral_gain: every entry must be finite")
            limits = self.before_failure_integral_limit_m_s
            if not np.all(np.isfinite(limits) & (limits > 0)):
                raise ValueError(f"before_failure_integral_limit_m_s: every entry must be finite and > 0 (m s), got {limits.tolist()}")
        #: The relaxed hover's altitude integral (m s, up) per the healthy design's altitude integral
        #: (m s, down) at the hand-over: the ratio of the vertical accelerations the two loops give per
        #: unit of integral (healthy: level, rotors at full efficiency; relaxed: its linear model), so
        #: the weight the healthy integral carried is carried on. 0 without an altitude integral.
        self.handover_altitude_ratio = self._handover_altitude_ratio()
        #: The relaxed hover's horizontal integral (m s, north and east) per the healthy design's
        #: (2 x 2) at the hand-over: both give the same steady horizontal acceleration (healthy: the
        #: integral its closed loop holds against a constant horizontal force, from the healthy
        #: airframe's hover linearisation; relaxed: ``-k_i`` times its integral), so the wind the
        #: healthy integral learnt is carried on, and a transient (braking from forward flight) is
        #: not. Zeros without a horizontal integral.
        self.handover_horizontal_ratio = self._handover_horizontal_ratio()

    def _handover_altitude_ratio(self) -> float:
        k_z = self.outer_loop.altitude_integral_gain_s
        if self.before_failure_integral_gain is None or k_z == 0.0:
            return 0.0
        axis = np.asarray(self.airframe.thrust_axis)
        # Healthy, level: a command change du along the rotor axes, up component -axis_z, per kg.
        healthy = float(np.sum(-self.before_failure_integral_gain[:, 2] * -axis[:, 2])) / float(self.airframe.mass_kg)
        b = np.asarray(self.solution.linear_b)
        relaxed = float(-(b[6] @ self.design.gain[:, 5]) * k_z)
        if not (math.isfinite(healthy) and math.isfinite(relaxed) and relaxed != 0.0):
            raise ValueError(f"before_failure_integral_gain: no hand-over ratio (healthy {healthy:g}, relaxed {relaxed:g} m/s^2 per m s)")
        return healthy / relaxed

    def _handover_horizontal_ratio(self) -> FloatArray:
        k_i = self.outer_loop.integral_gain_s3
        if self.before_failure is None or self.before_failure_integral_gain is None or k_i == 0.0:
            return np.zeros((2, 2))
        if not np.any(np.asarray(self.before_failure_integral_gain)[:, :2]):
            # An altitude-only healthy integral learnt no wind: nothing to carry (and the steady
            # state below would be singular).
            return np.zeros((2, 2))
        from ..flight import Simulator
        from .lqr import linearize

        healthy = self.airframe.with_efficiency(np.ones(self.airframe.rotor_count))
        model = linearize(Simulator(healthy), (self.before_failure.x_trim, self.before_failure.u_trim))
        a, b = np.asarray(model.A), np.asarray(model.B)
        n = a.shape[0]
        # The healthy loop with integral action, d/dt [x; I] = closed [x; I] + E d, in steady state
        # under a constant horizontal acceleration d: position error 0, the integral holding d.
        closed = np.zeros((n + 3, n + 3))
        closed[:n, :n] = a - b @ np.asarray(self.before_failure.gain)
        closed[:n, n:] = -b @ self.before_failure_integral_gain
        closed[n:, :3] = np.eye(3)
        force = np.zeros((n + 3, 2))
        force[3, 0] = force[4, 1] = 1.0  # north and east velocity rows
        try:
            integral_per_accel = np.linalg.solve(closed, -force)[n:n + 2]
            ratio = np.linalg.inv(integral_per_accel) / k_i
        except np.linalg.LinAlgError:
            ratio = np.full((2, 2), np.nan)
        if not np.all(np.isfinite(ratio)):
            raise ValueError("before_failure_integral_gain: no horizontal hand-over ratio (the healthy loop holds no steady "
                             "integral against a horizontal force)")
        return np.asarray(ratio, dtype=np.float64)

    def check_sampled(self, dt_s: float) -> float:
        """The spectral radius of the loop sampled at ``dt_s`` (zero-order hold,
        :func:`rotorfault.control.riccati.sampled_spectral_radius`): ``ValueError`` unless < 1."""
        dt = real("dt_s", dt_s)
        if not (dt > 0 and math.isfinite(dt)):
            raise ValueError(f"dt_s: must be finite and > 0, got {dt}")
        a = np.asarray(self.solution.linear_a)
        b = np.asarray(self.solution.linear_b)
        radius = sampled_spectral_radius(a, b, self.design.gain, dt)
        if not radius < 1.0 - CLOSED_LOOP_RTOL:
            raise ValueError(
                f"sampled loop: the relaxed hover LQR held over dt_s = {dt:g} s (zero-order hold) has spectral "
                f"radius {radius:.6g} >= 1: shorten dt_s or slow the design (larger r)"
            )
        return radius

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
            before_failure=None if self.before_failure is None else self.before_failure.core(dt_s),
            failure_time_s=self.failure_time_s,
            before_failure_integral_gain=None if self.before_failure_integral_gain is None
            else np.ascontiguousarray(self.before_failure_integral_gain),
            before_failure_integral_limit_m_s=None if self.before_failure_integral_limit_m_s is None
            else _triple(self.before_failure_integral_limit_m_s),
            handover_altitude_ratio=None if self.before_failure_integral_gain is None else self.handover_altitude_ratio,
            handover_horizontal_ratio=None if self.before_failure_integral_gain is None
            else np.ascontiguousarray(self.handover_horizontal_ratio),
        )


def _triple(v: npt.ArrayLike) -> tuple[float, float, float]:
    a = np.asarray(v, dtype=np.float64)
    return (float(a[0]), float(a[1]), float(a[2]))


def periodic_state(
    solution: RelaxedHoverSolution,
    airframe: Airframe,
    *,
    position: npt.ArrayLike = (0.0, 0.0, 0.0),
    yaw: float = 0.0,
    linear_drag_n_s_m: float = 0.0,
) -> State:
    """A state on the periodic solution whose circle is centred at ``position`` (world NED, m): the
    attitude turns the spin axis to world up (then ``yaw`` about it, rad), the body rate is the
    solution's, position and velocity are on the circle (:func:`circle_offsets`).

    Examples:

        >>> import rotorfault as rf
        >>> quad = rf.Airframe.preset("ke-quadcopter").with_failed_rotors([1])
        >>> settings = rf.RelaxedHoverSettings(rotational_drag_n_m_s=2.8e-3, grid_points=21)
        >>> solution = rf.relaxed_hover(quad, settings).best
        >>> state = rf.periodic_state(solution, quad, position=(0, 0, -2))
        >>> round(max(abs(w) for w in state.omega), 2), [round(p, 3) for p in state.position]
        (14.58, [-0.009, -0.009, -2.0])
    """
    centre = np.asarray(_three("position", position))
    yaw = real("yaw", yaw)
    if not math.isfinite(yaw):  # long hostile run: inf reached math.sin as a bare domain error
        raise ValueError(f"yaw: must be finite (rad), got {yaw}")
    n = np.asarray(solution.spin_axis)
    rotation = _rotation_between(n, np.array([0.0, 0.0, -1.0]))
    turn = _axis_angle(np.array([0.0, 0.0, -1.0]), yaw)
    attitude = turn @ rotation
    offsets = circle_offsets(solution, airframe, linear_drag_n_s_m=linear_drag_n_s_m)
    return State(
        position=centre + attitude @ offsets.position_m,
        velocity=attitude @ offsets.velocity_m_s,
        quaternion=_quaternion(attitude),
        omega=np.asarray(solution.body_rate_rad_s),
    )


def _axis_angle(axis: FloatArray, angle: float) -> FloatArray:
    k = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]])
    result: FloatArray = np.eye(3) + math.sin(angle) * k + (1.0 - math.cos(angle)) * k @ k
    return result


def _rotation_between(a: FloatArray, b: FloatArray) -> FloatArray:
    """The shortest rotation taking unit ``a`` to unit ``b``."""
    axis = np.cross(a, b)
    size = float(np.linalg.norm(axis))
    cosine = float(np.clip(a @ b, -1.0, 1.0))
    if size < 1e-15:
        if cosine > 0:
            return np.eye(3)
        other = np.array([1.0, 0.0, 0.0]) if abs(a[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
        axis = np.cross(a, other)
        return _axis_angle(axis / np.linalg.norm(axis), math.pi)
    return _axis_angle(axis / size, math.atan2(size, cosine))


def _quaternion(r: FloatArray) -> tuple[float, float, float, float]:
    """Unit quaternion (w, x, y, z) of a rotation matrix (Shepperd's method)."""
    trace = float(np.trace(r))
    candidates = [trace, r[0, 0], r[1, 1], r[2, 2]]
    k = int(np.argmax(candidates))
    if k == 0:
        w = 0.5 * math.sqrt(1.0 + trace)
        q = (w, (r[2, 1] - r[1, 2]) / (4 * w), (r[0, 2] - r[2, 0]) / (4 * w), (r[1, 0] - r[0, 1]) / (4 * w))
    elif k == 1:
        x = 0.5 * math.sqrt(1.0 + 2 * r[0, 0] - trace)
        q = ((r[2, 1] - r[1, 2]) / (4 * x), x, (r[0, 1] + r[1, 0]) / (4 * x), (r[0, 2] + r[2, 0]) / (4 * x))
    elif k == 2:
        y = 0.5 * math.sqrt(1.0 + 2 * r[1, 1] - trace)
        q = ((r[0, 2] - r[2, 0]) / (4 * y), (r[0, 1] + r[1, 0]) / (4 * y), y, (r[1, 2] + r[2, 1]) / (4 * y))
    else:
        z = 0.5 * math.sqrt(1.0 + 2 * r[2, 2] - trace)
        q = ((r[1, 0] - r[0, 1]) / (4 * z), (r[0, 2] + r[2, 0]) / (4 * z), (r[1, 2] + r[2, 1]) / (4 * z), z)
    norm = math.sqrt(sum(v * v for v in q))
    sign = 1.0 if q[0] >= 0 else -1.0
    return (sign * q[0] / norm, sign * q[1] / norm, sign * q[2] / norm, sign * q[3] / norm)


__all__ = ["RelaxedHoverFeedback", "RelaxedHoverOuterLoop", "bryson_weights", "periodic_state"]

"""The flight simulator: a Rust 6-DOF rigid body integrated with RK4, rotor actuators with lag,
saturation, rate limits and faults, drag and wind, closed by a controller at its own rate.

Frames: world NED (north, east, down; altitude is ``-position[2]``), body FRD. Rotor numbers in
faults are 1-based like the papers; arrays are ordered rotor 1..m.
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, TypeAlias, cast

import numpy as np
import numpy.typing as npt

from . import _rfcore
from ._convert import FloatArray, count, float_array, real
from ._typing import Controller, CoreController, DivergenceKind
from ._progress import chunks
from .airframe import Airframe, require_airframe

if TYPE_CHECKING:
    from matplotlib.figure import Figure


#: A controller the simulator flies: a built-in one (anything with ``core(dt_s)``, see
#: :class:`rotorfault.control.Controller`), a Python callable ``f(t, x) -> commands`` (the slow
#: path) or ``None`` (all rotors at zero).
AnyController: TypeAlias = Controller | Callable[[float, FloatArray], npt.ArrayLike] | None

#: The Rust controller objects :func:`core_controller` can return (all can run in a batch).
CORE_TYPES: tuple[type, ...] = (
    _rfcore.OpenLoop,
    _rfcore.LinearFeedback,
    _rfcore.Lti,
    _rfcore.Allocated,
    _rfcore.UniformPassiveFtc,
    _rfcore.LanzonController,
    _rfcore.TrackingFeedback,
    _rfcore.RelaxedHoverFeedback,
)


def core_controller(controller: AnyController, dt_s: float) -> CoreController | Callable[[float, FloatArray], npt.ArrayLike] | None:
    """The object the Rust loop runs for ``controller`` (``None``: all rotors at zero): a built-in
    controller's ``core(dt_s)``, or the callable itself."""
    if controller is None:
        return None
    core = getattr(controller, "core", None)
    if callable(core):
        return cast(Controller, controller).core(dt_s)
    if callable(controller):
        return controller
    raise TypeError(
        "controller: expected OpenLoop, LinearFeedback, Lti, TrackingFeedback, Allocated, UniformPassiveFtc, LanzonController (anything with "
        f"core(dt_s)), a callable f(t, x) or None, got {type(controller).__name__}"
    )


def trim_command(controller: object) -> FloatArray | None:
    """The trim command a controller holds, if any (the actuators start there)."""
    u_trim = getattr(controller, "u_trim", None)
    return None if u_trim is None else np.asarray(u_trim, dtype=np.float64)


#: Largest ``h max(|omega|, 1 / time_constant)`` the simulator accepts, ``h = dt_s / substeps``
#: the RK4 substep: a run whose initial spin or actuator lag is faster is refused (``ValueError``
#: naming ``substeps`` and the numbers), and one whose body rate grows past ``MAX_RATE_STEP / h``
#: ends with a ``step-size`` event (a numerical cause, not the vehicle's).
MAX_RATE_STEP: float = _rfcore.MAX_RATE_STEP

#: The core's defaults, read once: the one source of every default below.
_DEFAULT_DRAG = _rfcore.Drag()
_DEFAULT_LIMITS = _rfcore.DivergenceLimits()
_DEFAULT_CONFIG = _rfcore.SimulationConfig()
_DEFAULT_VPP = _rfcore.VariablePitchActuator((0.0, 0.0, 0.0, 0.0), (0.0, 0.0), (0.0, 0.0), 0.0)


def _vector3(field_name: str, value: Any) -> tuple[float, float, float]:
    v = float_array(field_name, value, 1)
    if v.shape != (3,):
        raise ValueError(f"{field_name}: expected 3 entries, got {v.shape[0]}")
    if not np.all(np.isfinite(v)):
        raise ValueError(f"{field_name}: must be finite")
    return (float(v[0]), float(v[1]), float(v[2]))


class State:
    """A vehicle state: ``position`` (m, world NED), ``velocity`` (m/s, world), attitude as a unit
    ``quaternion`` (w, x, y, z; body to world) or ``euler`` (roll, pitch, yaw, rad, Z-Y-X), and
    ``omega`` (body rates, rad/s). Omitted fields are zero / level."""

    __slots__ = ("position", "velocity", "quaternion", "omega")

    def __init__(
        self,
        position: npt.ArrayLike = (0.0, 0.0, 0.0),
        velocity: npt.ArrayLike = (0.0, 0.0, 0.0),
        quaternion: npt.ArrayLike | None = None,
        euler: npt.ArrayLike | None = None,
        omega: npt.ArrayLike = (0.0, 0.0, 0.0),
    ) -> None:
        self.position = _vector3("position", position)
        self.velocity = _vector3("velocity", velocity)
        self.omega = _vector3("omega", omega)
        if quaternion is not None and euler is not None:
            raise ValueError("quaternion, euler: give at most one attitude")
        if euler is not None:
            roll, pitch, yaw = _vector3("euler", euler)
            cr, sr = math.cos(roll / 2), math.sin(roll / 2)
            cp, sp = math.cos(pitch / 2), math.sin(pitch / 2)
            cy, sy = math.cos(yaw / 2), math.sin(yaw / 2)
            q = (
                cr * cp * cy + sr * sp * sy,
                sr * cp * cy - cr * sp * sy,
                cr * sp * cy + sr * cp * sy,
                cr * cp * sy - sr * sp * cy,
            )
        elif quaternion is not None:
            arr = float_array("quaternion", quaternion, 1)
            if arr.shape != (4,) or not np.all(np.isfinite(arr)):
                raise ValueError("quaternion: expected 4 finite entries (w, x, y, z)")
            norm = float(np.linalg.norm(arr))
            if abs(norm - 1.0) > 1e-6:
                raise ValueError(f"quaternion: must have unit norm (within 1e-6), got norm {norm}")
            q = tuple(float(v) / norm for v in arr)  # type: ignore[assignment]
        else:
            q = (1.0, 0.0, 0.0, 0.0)
        self.quaternion: tuple[float, float, float, float] = q

    @classmethod
    def from_vector(cls, x: npt.ArrayLike) -> State:
        """From the 12-element state vector ``[p, v, roll, pitch, yaw, omega]``."""
        v = float_array("x", x, 1)
        if v.shape != (12,):
            raise ValueError(f"x: expected 12 entries, got {v.shape[0]}")
        return cls(position=v[0:3], velocity=v[3:6], euler=v[6:9], omega=v[9:12])

    def vector(self) -> FloatArray:
        """The 12-element state vector the controllers use."""
        w, x, y, z = self.quaternion
        roll = math.atan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y))
        pitch = math.asin(max(-1.0, min(1.0, 2 * (w * y - z * x))))
        yaw = math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
        return np.array([*self.position, *self.velocity, roll, pitch, yaw, *self.omega])

    def _packed(self) -> list[float]:
        return [*self.position, *self.velocity, *self.quaternion, *self.omega]

    def __repr__(self) -> str:
        return f"State(position={self.position}, velocity={self.velocity}, quaternion={self.quaternion}, omega={self.omega})"


@dataclass(frozen=True)
class RotorFault:
    """Rotor ``rotor`` (1-based) has efficiency ``efficiency`` (0 failed, 1 healthy) from ``time``
    (s) on. The controller never sees it."""

    rotor: int
    time: float
    efficiency: float = 0.0

    def __post_init__(self) -> None:
        if isinstance(self.rotor, bool) or not isinstance(self.rotor, (int, np.integer)):
            raise TypeError(f"rotor: expected a 1-based rotor number, got {self.rotor!r}")
        if not 1 <= self.rotor <= 2**31:
            raise ValueError(f"rotor: rotor numbers run from 1 to the airframe's rotor count, got {self.rotor}")
        real("time", self.time)
        real("efficiency", self.efficiency)

    def _packed(self) -> tuple[int, float, float]:
        return (int(self.rotor) - 1, float(self.time), float(self.efficiency))


@dataclass(frozen=True)
class Drag:
    """Aerodynamic damping and rotor inertia (the papers give none; all default to 0)."""

    #: ``k_t``: force ``-k_t (v - wind)``, N s/m (Lanzon's Stokes drag).
    linear_n_s_m: float = _DEFAULT_DRAG.linear_n_s_m
    #: force ``-c |v - wind| (v - wind)``, N s^2/m^2.
    quadratic_n_s2_m2: float = _DEFAULT_DRAG.quadratic_n_s2_m2
    #: ``k_r``: torque ``-k_r omega``, N m s (sets a spinning vehicle's yaw rate).
    rotational_n_m_s: float = _DEFAULT_DRAG.rotational_n_m_s
    #: ``I_R``: rotor inertia about its axis, kg m^2 (gyroscopic moment, Lanzon eq. (5)).
    rotor_inertia_kg_m2: float = _DEFAULT_DRAG.rotor_inertia_kg_m2

    def _core(self) -> _rfcore.Drag:
        return _rfcore.Drag(
            linear_n_s_m=real("drag.linear_n_s_m", self.linear_n_s_m),
            quadratic_n_s2_m2=real("drag.quadratic_n_s2_m2", self.quadratic_n_s2_m2),
            rotational_n_m_s=real("drag.rotational_n_m_s", self.rotational_n_m_s),
            rotor_inertia_kg_m2=real("drag.rotor_inertia_kg_m2", self.rotor_inertia_kg_m2),
        )


@dataclass(frozen=True)
class FixedPitchActuator:
    """Rotors commanded in thrust (N): first-order lag ``time_constant_s`` (Ke Table III: 0.025),
    rate limit (Lanzon: 50 N/s), thrust saturation from the airframe; ``thrust_coefficient_n_s2``
    (``f = k_f omega^2``) gives rotor speed for the gyroscopic moment (0: not modelled)."""

    time_constant_s: float = 0.0
    rate_limit_n_s: float = math.inf
    thrust_coefficient_n_s2: float = 0.0

    def _core(self) -> Any:
        return _rfcore.FixedPitchActuator(
            real("actuator.time_constant_s", self.time_constant_s),
            real("actuator.rate_limit_n_s", self.rate_limit_n_s),
            real("actuator.thrust_coefficient_n_s2", self.thrust_coefficient_n_s2),
        )


@dataclass(frozen=True)
class VariablePitchActuator:
    """Variable-pitch propellers (Wang et al. eq. (3)), commanded per rotor in speed and pitch
    (interleaved ``[omega_1, alpha_1, omega_2, ...]``): thrust ``k1 omega^2 alpha``, torque
    ``k2 omega^2 + k3 omega^2 alpha^2 + k4 omega alpha``.

    The speed and pitch channels have their own first-order lag and rate limit (a motor's speed
    loop and a pitch servo are different hardware). Defaults (the core's): Wang's "first-order
    transfer function ... cut-off frequency 10 Hz" for both, ``time_constant_s = 1 / (2 pi 10)``,
    and no rate limit (the paper gives none). ``speed_rate_limit_per_s`` is in speed units per
    second, ``pitch_rate_limit_rad_s`` in rad/s."""

    k: tuple[float, float, float, float]
    speed_bounds: tuple[float, float]
    pitch_bounds: tuple[float, float]
    speed_to_rad_s: float = 0.0
    speed_time_constant_s: float = _DEFAULT_VPP.speed_time_constant_s
    speed_rate_limit_per_s: float = _DEFAULT_VPP.speed_rate_limit_per_s
    pitch_time_constant_s: float = _DEFAULT_VPP.pitch_time_constant_s
    pitch_rate_limit_rad_s: float = _DEFAULT_VPP.pitch_rate_limit_rad_s

    def _core(self) -> Any:
        k = float_array("actuator.k", self.k, 1)
        if k.shape != (4,):
            raise ValueError(f"actuator.k: expected 4 coefficients (k1..k4), got {k.shape[0]}")
        speed = float_array("actuator.speed_bounds", self.speed_bounds, 1)
        pitch = float_array("actuator.pitch_bounds", self.pitch_bounds, 1)
        if speed.shape != (2,) or pitch.shape != (2,):
            raise ValueError("actuator.speed_bounds, actuator.pitch_bounds: expected (lower, upper)")
        return _rfcore.VariablePitchActuator(
            (float(k[0]), float(k[1]), float(k[2]), float(k[3])),
            (float(speed[0]), float(speed[1])),
            (float(pitch[0]), float(pitch[1])),
            real("actuator.speed_to_rad_s", self.speed_to_rad_s),
            speed_time_constant_s=real("actuator.speed_time_constant_s", self.speed_time_constant_s),
            speed_rate_limit_per_s=real("actuator.speed_rate_limit_per_s", self.speed_rate_limit_per_s),
            pitch_time_constant_s=real("actuator.pitch_time_constant_s", self.pitch_time_constant_s),
            pitch_rate_limit_rad_s=real("actuator.pitch_rate_limit_rad_s", self.pitch_rate_limit_rad_s),
        )


@dataclass(frozen=True)
class DivergenceLimits:
    """A run ends with an event when it passes one of these (``math.inf``: no limit)."""

    max_tilt_rad: float = _DEFAULT_LIMITS.max_tilt_rad
    max_altitude_loss_m: float = _DEFAULT_LIMITS.max_altitude_loss_m
    max_speed_m_s: float = _DEFAULT_LIMITS.max_speed_m_s
    max_rate_rad_s: float = _DEFAULT_LIMITS.max_rate_rad_s

    def _core(self) -> _rfcore.DivergenceLimits:
        return _rfcore.DivergenceLimits(
            max_tilt_rad=real("limits.max_tilt_rad", self.max_tilt_rad),
            max_altitude_loss_m=real("limits.max_altitude_loss_m", self.max_altitude_loss_m),
            max_speed_m_s=real("limits.max_speed_m_s", self.max_speed_m_s),
            max_rate_rad_s=real("limits.max_rate_rad_s", self.max_rate_rad_s),
        )


@dataclass(frozen=True)
class Noise:
    """Additive Gaussian sensor noise on the 12 measured state components (position, velocity,
    Euler angles, body rates), standard deviation ``10^(-snr_db / 20) |x_i| + std_i``.

    ``snr_db`` is a per-sample signal-to-noise ratio (Wang et al.'s scenarios use 15 dB; they do
    not say how signal power is measured, and per sample is the causal reading). ``std`` adds an
    absolute floor: 12 values, or 4 (position m, velocity m/s, angle rad, rate rad/s). Seeded and
    reproducible on every platform; in a batch, run ``i`` uses ``seed + i``."""

    snr_db: float | None = None
    std: npt.ArrayLike | None = None
    seed: int = 0

    def _core(self, seed_offset: int = 0) -> _rfcore.SensorNoise:
        relative = 0.0 if self.snr_db is None else 10.0 ** (-real("noise.snr_db", self.snr_db) / 20.0)
        if self.std is None:
            absolute = np.zeros(12)
        else:
            absolute = float_array("noise.std", self.std, 1)
            if absolute.shape == (4,):
                absolute = np.repeat(absolute, 3)
            if absolute.shape != (12,):
                raise ValueError(f"noise.std: expected 4 or 12 entries, got {absolute.shape[0]}")
        seed = count("noise.seed", self.seed)
        if seed + seed_offset >= 2**64:
            raise ValueError("noise.seed: must be below 2**64")
        return _rfcore.SensorNoise(relative_std=relative, absolute_std=[float(v) for v in absolute], seed=seed + seed_offset)


@dataclass(frozen=True)
class Event:
    """Why and when a run ended early, with the state (12-vector) at that moment."""

    time: float
    #: A kebab-case code (``"tilt"``, ``"non-finite-state"``, ...); ``description`` is the
    #: human-readable text.
    kind: DivergenceKind
    description: str
    state: FloatArray

    def __str__(self) -> str:
        return f"diverged at t = {self.time:.4f} s: {self.description}"


@dataclass(frozen=True)
class Trajectory:
    """A run sampled at the control rate. Arrays have one row per control step."""

    t: FloatArray
    position: FloatArray
    velocity: FloatArray
    quaternion: FloatArray
    euler: FloatArray
    omega: FloatArray
    #: Body z in the world frame (Ke's n3).
    primary_axis: FloatArray
    rotor_command: FloatArray
    rotor_thrust: FloatArray
    #: Rotor efficiencies applied by the simulator at each step (faults included).
    efficiency: FloatArray
    #: Sensor readings as recorded by the core (empty without noise); see :attr:`measured`.
    recorded_measurements: FloatArray
    events: list[Event] = field(default_factory=list)
    faults: tuple[RotorFault, ...] = ()

    @property
    def diverged(self) -> bool:
        return bool(self.events)

    @property
    def measured(self) -> FloatArray:
        """What the controller saw: the 12-element state vector per step (with sensor noise;
        without noise the true state, built on demand). The divergence row is NaN."""
        if self.recorded_measurements.shape[1] > 0:
            return self.recorded_measurements
        measured = np.hstack([self.position, self.velocity, self.euler, self.omega])
        if self.events:
            measured[-1] = np.nan  # no command was computed at the divergence
        return measured

    @property
    def rotation(self) -> FloatArray:
        """Rotation matrices body -> world (N x 3 x 3) from the quaternions."""
        w, x, y, z = self.quaternion.T
        return np.stack(
            [
                np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], axis=-1),
                np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], axis=-1),
                np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], axis=-1),
            ],
            axis=1,
        )

    @classmethod
    def _from_core(cls, raw: _rfcore.Trajectory, faults: tuple[RotorFault, ...]) -> Trajectory:
        events = []
        d = raw.divergence
        if d is not None:
            kind = cast(DivergenceKind, d.reason)
            events.append(Event(d.time_s, kind, d.description, np.asarray(d.state)))
        return cls(
            t=raw.t,
            position=raw.position,
            velocity=raw.velocity,
            quaternion=raw.quaternion,
            euler=raw.euler,
            omega=raw.omega,
            primary_axis=raw.primary_axis,
            rotor_command=raw.command,
            rotor_thrust=raw.thrust,
            efficiency=raw.efficiency,
            recorded_measurements=raw.measured,
            events=events,
            faults=faults,
        )

    def plot(
        self,
        path: str | None = None,
        *,
        title: str | None = None,
        setpoints: Sequence[tuple[float, npt.ArrayLike]] | None = None,
    ) -> Figure:
        """Position (with the setpoint, if given as ``(time, NED position)`` steps), roll and
        pitch, yaw unwrapped, body rates and rotor thrusts against time, with fault and loss
        markers. ``title`` says what the run is (default: the faults); the faults and the loss,
        if any, are always added. Returns the figure (not registered with pyplot), saved to
        ``path`` (``.png``, ``.pdf`` or ``.svg``, written atomically) if given."""
        from ._output import MIN_FONT_PT, new_figure, save_figure

        fig = new_figure(figsize=(10, 12.5), layout="constrained")
        axes = fig.subplots(5, 1, sharex=True)
        styles = ["-", "--", ":", "-.", (0, (5, 1, 1, 1, 1, 1)), (0, (1, 3)), (0, (8, 2)), (0, (3, 1, 3, 3))]
        euler_deg = np.degrees(self.euler)
        yaw = np.degrees(np.unwrap(self.euler[:, 2])) if len(self.t) else euler_deg[:, 2]
        m = self.rotor_thrust.shape[1]
        # (data, series names, axis label, smallest y span shown: round-off is not magnified)
        panels: list[tuple[FloatArray, list[str], str, float]] = [
            (self.position * np.array([1, 1, -1]), ["north", "east", "altitude"], "position (m)\n(altitude = -down)", 1.0),
            (euler_deg[:, :2], ["roll", "pitch"], "roll, pitch (deg)", 2.0),
            (yaw[:, None], ["yaw (unwrapped)"], "yaw (deg)", 2.0),
            (self.omega, ["p (roll rate)", "q (pitch rate)", "r (yaw rate)"], "body rate (rad/s)", 0.2),
            (self.rotor_thrust, [f"rotor {i + 1}" for i in range(m)], "rotor thrust (N)", 0.2),
        ]
        for k, (ax, (data, labels, ylabel, span)) in enumerate(zip(axes, panels)):
            for j, (column, label) in enumerate(zip(data.T, labels)):
                ax.plot(self.t, column, label=label, linestyle=styles[j % len(styles)], color=f"C{j}", lw=1.3)
            if k == 0 and setpoints:
                _plot_setpoints(ax, self.t, setpoints, styles)
            _at_least_span(ax, data, span)
            ax.set_ylabel(ylabel, fontsize=10)
            ax.grid(True, alpha=0.3)
            ax.tick_params(labelsize=9)
            for fault in self.faults:
                ax.axvline(fault.time, color="0.35", linestyle=(0, (4, 2)), lw=1.0, label=None)
            for event in self.events:
                ax.axvline(event.time, color="black", linestyle="-", lw=2.0, alpha=0.5)
            ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=max(MIN_FONT_PT, 8.5), frameon=False)
        axes[-1].set_xlabel("time (s)", fontsize=10)
        lines = [title if title else "rotorfault simulation"]
        if self.faults:
            lines.append(
                "faults (thin dashed lines): "
                + ", ".join(f"rotor {f.rotor} -> {f.efficiency:g} at {f.time:g} s" for f in self.faults)
            )
        if self.events:
            e = self.events[0]
            lines.append(f"lost at t = {e.time:.2f} s (thick line): {e.description}")
        elif len(self.t):
            lines.append(f"flown for {self.t[-1]:g} s, not lost")
        import textwrap

        fig.suptitle("\n".join(textwrap.fill(line, 110) for line in "\n".join(lines).splitlines()), fontsize=11)
        if path is not None:
            save_figure(fig, path)
        return fig


def _plot_setpoints(ax: Any, t: FloatArray, setpoints: Sequence[tuple[float, npt.ArrayLike]], styles: list[Any]) -> None:
    """The setpoint of each position series as a thin step line in its colour, labelled once."""
    if not len(t):
        return
    times = np.array([float(s) for s, _ in setpoints])
    points = np.array([np.asarray(p, dtype=np.float64) for _, p in setpoints]) * np.array([1, 1, -1])
    k = np.clip(np.searchsorted(times, t, side="right") - 1, 0, len(times) - 1)
    every = max(1, len(t) // 12)
    for j, (name, marker) in enumerate(zip(["north", "east", "altitude"], ["x", "+", "1"])):
        # Staggered markers: equal setpoints (east 10 m, altitude 10 m) stay distinguishable.
        ax.plot(t, points[k, j], color=f"C{j}", lw=0.7, linestyle=styles[j], alpha=0.8, marker=marker,
                markevery=(j * every // 3, every), markersize=7, label=f"{name} setpoint")


def _at_least_span(ax: Any, data: FloatArray, span: float) -> None:
    """Shows at least ``span`` on the y axis, so round-off (1e-11 N, 1e-8 deg) around a constant
    is drawn as the flat line it is, not autoscaled into apparent chatter."""
    finite = data[np.isfinite(data)]
    if finite.size == 0:
        return
    lo, hi = float(finite.min()), float(finite.max())
    if hi - lo < span:
        mid = 0.5 * (lo + hi)
        ax.set_ylim(mid - 0.6 * span, mid + 0.6 * span)
    ax.ticklabel_format(axis="y", useOffset=False)


def _faults(faults: Iterable[RotorFault] | None, duration_s: float, field_name: str = "faults") -> tuple[RotorFault, ...]:
    """The fault list, each fault inside the run: ``0 <= time < duration_s`` (a fault the run
    would never apply is refused, not silently dropped)."""
    if faults is None:
        return ()
    items = tuple(faults)
    for k, f in enumerate(items):
        if not isinstance(f, RotorFault):
            raise TypeError(f"{field_name}: expected rotorfault.RotorFault items, got {type(f).__name__}")
        if math.isfinite(f.time) and not 0.0 <= f.time < duration_s:  # (the core reports non-finite times)
            raise ValueError(
                f"{field_name}[{k}].time: must lie in [0, duration_s) = [0, {duration_s:g}) s, the run's span, got {f.time:g}"
            )
    return items


def _check_duration(duration_s: Any, dt_s: float) -> float:
    duration = real("duration_s", duration_s)
    if not math.isfinite(duration):
        raise ValueError(f"duration_s: must be finite, got {duration}")
    if not duration >= dt_s:
        raise ValueError(f"duration_s: must be at least one control period (dt_s = {dt_s:g} s), got {duration:g}")
    return duration


class Simulator:
    """One airframe with its actuators, drag and wind, ready to fly controllers through faults.

    ``dt_s`` is the control period (s); the rigid body takes ``substeps`` RK4 steps per period.
    ``wind`` is a constant world-frame (NED) wind in m/s; ``wind_profile`` an optional sequence of
    ``(time_s, (n, e, d))`` points added to it, interpolated linearly.
    """

    def __init__(
        self,
        airframe: Airframe,
        *,
        dt_s: float = _DEFAULT_CONFIG.dt_s,
        substeps: int = _DEFAULT_CONFIG.substeps,
        drag: Drag | None = None,
        wind: npt.ArrayLike = (0.0, 0.0, 0.0),
        wind_profile: Sequence[tuple[float, npt.ArrayLike]] | None = None,
        actuator: FixedPitchActuator | VariablePitchActuator | None = None,
        limits: DivergenceLimits | None = None,
        noise: Noise | None = None,
    ) -> None:
        self.airframe = require_airframe(airframe)
        self.dt_s = real("dt_s", dt_s)
        self.substeps = count("substeps", substeps)
        self.drag = Drag() if drag is None else drag
        if not isinstance(self.drag, Drag):
            raise TypeError(f"drag: expected rotorfault.Drag, got {type(drag).__name__}")
        self.wind = _vector3("wind", wind)
        self.wind_profile = [
            (real(f"wind_profile[{k}].time", t), _vector3(f"wind_profile[{k}]", w))
            for k, (t, w) in enumerate(wind_profile or [])
        ]
        self.actuator = FixedPitchActuator() if actuator is None else actuator
        if not isinstance(self.actuator, (FixedPitchActuator, VariablePitchActuator)):
            raise TypeError(f"actuator: expected FixedPitchActuator or VariablePitchActuator, got {type(actuator).__name__}")
        self.limits = DivergenceLimits() if limits is None else limits
        if noise is not None and not isinstance(noise, Noise):
            raise TypeError(f"noise: expected rotorfault.Noise, got {type(noise).__name__}")
        self.noise = noise
        # Fail early on bad parameters: the core validates them in a zero-length run. (Every run
        # rebuilds the core objects from these attributes, so changing one later takes effect.)
        _rfcore.simulate(
            self.airframe._core, self.actuator._core(), self.drag._core(), None, State()._packed(), [],
            self.airframe.efficiency, None, self._config(0.0),
        )

    @property
    def command_count(self) -> int:
        """Commands per control step: one per rotor (thrust) or two (speed, pitch)."""
        per_rotor = 2 if isinstance(self.actuator, VariablePitchActuator) else 1
        return per_rotor * self.airframe.rotor_count

    def _config(self, duration_s: float, record_every: int = 1, seed_offset: int = 0) -> _rfcore.SimulationConfig:
        """The core's run settings; ``seed_offset`` shifts the noise seed (run ``i`` of a batch
        uses ``seed + i``, so a batch sent in chunks flies every run exactly as one call would)."""
        return _rfcore.SimulationConfig(
            dt_s=self.dt_s,
            substeps=self.substeps,
            duration_s=real("duration_s", duration_s),
            limits=self.limits._core(),
            wind_m_s=self.wind,
            wind_profile=self.wind_profile,
            noise=None if self.noise is None else self.noise._core(seed_offset),
            record_every=count("record_every", record_every),
        )

    def _start(self, controller: AnyController, initial_command: npt.ArrayLike | None) -> FloatArray | None:
        if initial_command is not None:
            return float_array("initial_command", initial_command, 1)
        trim = trim_command(controller)
        # A trim of the wrong length is the controller's error; the core reports it as such.
        return trim if trim is not None and trim.shape == (self.command_count,) else None

    def run(
        self,
        x0: State | None = None,
        duration_s: float = 10.0,
        *,
        controller: AnyController = None,
        faults: Iterable[RotorFault] | None = None,
        initial_command: npt.ArrayLike | None = None,
        record_every: int = 1,
    ) -> Trajectory:
        """Flies from ``x0`` for ``duration_s`` seconds. The actuators start settled at
        ``initial_command`` (default: the controller's trim command if it has one, else zero).
        Rotor efficiency starts at the airframe's own; ``faults`` change it on schedule.
        ``record_every`` keeps every n-th control step (plus the last and any divergence)."""
        x0 = State() if x0 is None else x0
        if not isinstance(x0, State):
            raise TypeError(f"x0: expected rotorfault.State, got {type(x0).__name__}")
        duration_s = _check_duration(duration_s, self.dt_s)
        fault_list = _faults(faults, duration_s)
        core = core_controller(controller, self.dt_s)
        start = self._start(controller, initial_command)
        config = self._config(duration_s, record_every)
        raw = _rfcore.simulate(
            self.airframe._core,
            self.actuator._core(),
            self.drag._core(),
            core,
            x0._packed(),
            [f._packed() for f in fault_list],
            self.airframe.efficiency,
            start,
            config,
        )
        return Trajectory._from_core(raw, fault_list)

    def state_derivative(self, x: npt.ArrayLike, command: npt.ArrayLike, efficiency: npt.ArrayLike | None = None) -> FloatArray:
        """d/dt of the 12-element state vector with the actuators settled at ``command`` (clamped to
        its bounds, as the actuators do) and rotor ``efficiency`` (default: the airframe's own), in
        the constant ``wind`` (``wind_profile`` is a time-varying disturbance and is left out): the
        model :func:`rotorfault.control.lqr.hover_trim` balances and ``linearize`` differentiates."""
        eff = self.airframe.efficiency if efficiency is None else float_array("efficiency", efficiency, 1)
        return _rfcore.state_derivative(
            self.airframe._core,
            self.actuator._core(),
            self.drag._core(),
            list(float_array("x", x, 1)),
            float_array("command", command, 1),
            eff,
            list(self.wind),
        )


@dataclass(frozen=True)
class BatchResult:
    """Runs stacked along axis 0 on one time axis ``t``, the recording grid: the recorded control
    steps (``k dt_s`` for every ``record_every``-th ``k``) and the end, exactly ``duration_s``;
    equal to the ``t`` of every run that does not diverge. A run that diverges fills the rows up
    to its last recorded step before the divergence and NaN after: its divergence row, at the
    located crossing time, is stacked only when that time is a grid time (never into a row of
    another time); it is always the last row of ``trajectories[i]``, and ``divergence_time[i]``
    is its time."""

    t: FloatArray
    position: FloatArray
    velocity: FloatArray
    euler: FloatArray
    omega: FloatArray
    rotor_thrust: FloatArray
    efficiency: FloatArray
    diverged: np.ndarray[Any, np.dtype[np.bool_]]
    divergence_time: FloatArray
    trajectories: list[Trajectory]


#: Bytes one recorded row costs, measured: the core's row, the Python trajectory's arrays and the
#: stacked batch arrays (a 10 s quadcopter run at 400 Hz: about 2.4 MB), per rotor and fixed.
ROW_BYTES_FIXED = 8 * (1 + 13 + 19 + 12 + 12)
ROW_BYTES_PER_ROTOR = 8 * (3 + 2 + 3 + 2)


def recording_bytes(simulator: Simulator, runs: int, duration_s: float, record_every: int = 1) -> int:
    """Estimated peak memory of a :func:`simulate_batch` of ``runs`` runs: recorded rows times
    the bytes each costs (the core's row, the Python arrays, the stacked copies)."""
    steps = math.ceil(duration_s / simulator.dt_s - 1e-9)
    rows = steps // max(record_every, 1) + 3
    noise = 12 * 8 if simulator.noise is not None else 0
    return int(runs * rows * (ROW_BYTES_FIXED + ROW_BYTES_PER_ROTOR * simulator.airframe.rotor_count + noise))


def available_memory_bytes() -> int:
    """Memory available to new allocations (``MemAvailable`` on Linux, else total physical)."""
    try:
        with open("/proc/meminfo", encoding="ascii") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    return int(os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES"))


def _check_memory(simulator: Simulator, runs: int, duration_s: float, record_every: int, budget: int | None) -> None:
    if budget is None:
        budget = available_memory_bytes() // 2
    else:
        budget = count("memory_budget_bytes", budget)
    need = recording_bytes(simulator, runs, duration_s, record_every)
    if need > budget:
        raise ValueError(
            f"memory_budget_bytes: recording {runs:,} runs of {duration_s:g} s with record_every={record_every} "
            f"needs about {need / 2**30:.2f} GiB, more than the budget of {budget / 2**30:.2f} GiB "
            f"(default: half the available memory): record less (record_every), fewer runs per call, "
            f"or keep per-run summaries only (rotorfault.campaign)"
        )


def simulate_batch(
    simulator: Simulator,
    x0s: Sequence[State],
    duration_s: float,
    *,
    controllers: AnyController | Sequence[AnyController] = None,
    faults: Sequence[Iterable[RotorFault] | None] | None = None,
    initial_command: npt.ArrayLike | None = None,
    record_every: int = 1,
    progress: bool | None = None,
    memory_budget_bytes: int | None = None,
) -> BatchResult:
    """Many runs in parallel (Rust threads, GIL released). ``controllers`` is one controller for
    every run or a sequence with one per run; ``faults`` one fault list per run. Python callables
    cannot run in a batch (they would serialise on the GIL). ``record_every`` thins what is
    recorded (every n-th control step, plus the last and any divergence): large batches need it
    to keep memory bounded; the stacked arrays then sit on the thinned grid ``BatchResult.t``
    (times, not step indices; see :class:`BatchResult`). ``progress=True`` shows a progress bar
    (runs done, rate, ETA) on standard error; the runs then go to the core in chunks, with
    identical results. ``memory_budget_bytes`` (default: half the available memory): a batch
    whose recordings would need more is refused up front with the estimate (see
    :func:`recording_bytes`)."""
    if not isinstance(simulator, Simulator):
        raise TypeError(f"simulator: expected rotorfault.Simulator, got {type(simulator).__name__}")
    states = list(x0s)
    n = len(states)
    for s in states:
        if not isinstance(s, State):
            raise TypeError(f"x0s: expected rotorfault.State items, got {type(s).__name__}")
    per_run: list[AnyController] = list(controllers) if isinstance(controllers, (list, tuple)) else [controllers] * n  # type: ignore[list-item]
    duration_s = _check_duration(duration_s, simulator.dt_s)
    fault_lists = [_faults(f, duration_s, f"faults[{i}]") for i, f in enumerate(faults if faults is not None else [None] * n)]
    if len(per_run) != n or len(fault_lists) != n:
        raise ValueError(f"controllers, faults: expected one entry per run ({n})")
    cores: list[CoreController | None] = []
    for c in per_run:
        core = core_controller(c, simulator.dt_s)
        if core is not None and not isinstance(core, CORE_TYPES):
            raise TypeError("controllers: Python callables cannot run in a batch; use Simulator.run")
        cores.append(cast(CoreController | None, core))
    # Each run's actuators start at initial_command, else at its own controller's trim.
    starts = []
    for c in per_run:
        start = simulator._start(c, initial_command)
        starts.append(None if start is None else [float(v) for v in start])
    simulator._config(duration_s, record_every)  # checks the settings before any run
    _check_memory(simulator, n, duration_s, record_every, memory_budget_bytes)
    actuator, drag = simulator.actuator._core(), simulator.drag._core()
    packed_states = [s._packed() for s in states]
    packed_faults = [[f._packed() for f in fl] for fl in fault_lists]
    # Chunks of a few runs per thread keep the bar moving and cost nothing measurable.
    size = n if not progress else max(8 * (os.cpu_count() or 1), n // 100)
    raws: list[_rfcore.Trajectory] = []
    for first, last in chunks(n, size, description=f"{n:,} runs", show=progress):
        raws += _rfcore.simulate_batch(
            simulator.airframe._core,
            actuator,
            drag,
            cores[first:last],
            packed_states[first:last],
            packed_faults[first:last],
            simulator.airframe.efficiency,
            starts[first:last],
            simulator._config(duration_s, record_every, seed_offset=first),
        )
    trajectories = [Trajectory._from_core(raw, fl) for raw, fl in zip(raws, fault_lists)]
    # The common recording grid (the core's record_times, bit-identical to a completed run's t).
    # A run's rows are a prefix of it but for a divergence row, which is stacked only when its
    # time is the next grid time: a crossing located between two grid times stays in its
    # Trajectory, never in a row of another time.
    grid = simulator._config(duration_s, record_every).record_times()
    stacked = []
    for tr in trajectories:
        rows = len(tr.t)
        if rows and not (rows <= len(grid) and tr.t[rows - 1] == grid[rows - 1]):
            rows -= 1
        if not np.array_equal(tr.t[:rows], grid[:rows]):
            raise RuntimeError("internal: a run's recorded times left the recording grid")
        stacked.append(rows)

    def stack(name: str) -> FloatArray:
        arrays = [getattr(tr, name) for tr in trajectories]
        shape = (n, len(grid), *arrays[0].shape[1:]) if arrays else (0, len(grid))
        out = np.full(shape, np.nan)
        for i, (a, rows) in enumerate(zip(arrays, stacked)):
            out[i, :rows] = a[:rows]
        return out

    return BatchResult(
        t=grid,
        position=stack("position"),
        velocity=stack("velocity"),
        euler=stack("euler"),
        omega=stack("omega"),
        rotor_thrust=stack("rotor_thrust"),
        efficiency=stack("efficiency"),
        diverged=np.array([tr.diverged for tr in trajectories], dtype=bool),
        divergence_time=np.array([tr.events[0].time if tr.events else np.nan for tr in trajectories]),
        trajectories=trajectories,
    )

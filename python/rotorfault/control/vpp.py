"""Variable-pitch-propeller (VPP) quadcopters that lose propellers (Wang, Gross, Zhao 2020).

Design in Python, run in Rust: the vehicle is a preset (``presets/vpp/*.toml`` through the core's
parser), the trim solves Wang's equilibrium (5)-(16) for any failed propeller set, the linear
model is the Jacobian of the simulator's own dynamics (:func:`rotorfault.control.lqr.linearize`;
the B matrix printed in Wang's Sec. 3.2 is not consistent with eq. (1)-(4), README decisions), the
rank test is the core's scale-free one, and the LQR gain is handed to the Rust simulator as a
:class:`~rotorfault.control.LinearFeedback`.

Trim (Sec. 3.1, generalised). Hover upright at rest needs ``u = [m g, 0, 0, 0]`` (eq. (5)):

1. thrusts: the healthy propellers' minimum-norm thrusts giving ``m g`` with zero roll and pitch
   torque (unique with one failure: the failed propeller's opposite carries nothing, the other two
   ``m g / 2`` each, eq. (7), (10));
2. yaw (eq. (9)): with each thrust fixed, ``alpha = f / (k1 omega^2)`` and a propeller's torque is a
   function of its speed alone, ``tau(omega) = k2 omega^2 + k3 f^2 / (k1^2 omega^2) + k4 f / (k1 omega)``
   (Wang's ``r(omega_2) / 2``, eq. (14)). The propellers of one spin direction (the *fixed* group,
   by default the failed propeller's direction: Wang's propeller 3) are given a speed; the other
   group (*free*: Wang's 2 and 4, ``omega_2 = omega_4``, eq. (11)) shares the one speed that
   balances yaw, found by bisection on its feasible interval (``tau`` is increasing there: checked).

Every bound that makes a request infeasible is named in the ``ValueError``: a pitch past
``pitch_bounds`` (a speed too low for its thrust), a speed past ``speed_bounds``, or a yaw torque
the free group cannot match within its speed interval.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from importlib import resources
from typing import TYPE_CHECKING, get_args

import numpy as np
import numpy.typing as npt

from .. import _rfcore
from .._typing import VppInputs
from .._util.convert import FloatArray, float_array, frozen_array, real, rotor_numbers
from .._util.deprecation import warn
from .._util.numeric import scaled_norm
from ..analysis.airframe import Airframe
from ..flight import Drag, Simulator, VariablePitchActuator
from .linear import STATE_DIM, STATE_LABELS, LinearFeedback
from .linear import STATE_NAMES as _STATE_NAMES
from .lqr import TRIM_RESIDUAL_TOL
from .lqr import linearize as _linearize
from .riccati import design_lqr
from .stabilisability import Direction, describe_directions, left_null_space

if TYPE_CHECKING:
    from .systems import LinearModel

#: Names of the 12 states in rotorfault's order (NED position, velocity, roll/pitch/yaw, body rates)
#: with Wang's symbols (his y/v are our east position/velocity up to the frame's sign): the
#: control layer's :data:`~rotorfault.control.linear.STATE_NAMES`.
STATE_NAMES = _STATE_NAMES

#: Characteristic sizes used to scale the linear model before rank and decomposition (not the
#: rank itself, which is scale-free): 1 m, 1 m/s, 0.1 rad, 1 rad/s.
STATE_SCALE = np.array([1.0] * 3 + [1.0] * 3 + [0.1] * 3 + [1.0] * 3)

#: Linearisation entries below this fraction of their column's largest are finite-difference
#: round-off (see :func:`linearize`; the noise is ~1e-16 relative here, e.g. 2e-18 beside 2e2),
#: far below every physical entry of these models (the smallest relative one, the yaw row's
#: 1.6e-3 / 2.4e-2 in an omega column, is 1e-1).
ROUNDOFF_RTOL = 1e-9

#: Bisection stops when the speed interval is this narrow relative to the upper speed bound
#: (a few ulps: the torque balance then holds to ~1e-13 relative).
SPEED_TOLERANCE = 1e-14


def _vpp_dir() -> resources.abc.Traversable:
    return resources.files("rotorfault").joinpath("presets", "vpp")


def presets() -> list[str]:
    """Names of the shipped VPP vehicle presets (``wang``)."""
    return sorted(p.name[: -len(".toml")] for p in _vpp_dir().iterdir() if p.name.endswith(".toml"))


@dataclass(frozen=True)
class VppVehicle:
    """A VPP quadcopter: airframe (geometry, mass, inertia, the bidirectional thrust box for the
    ACAI), propeller model with the two channels' lags, and drag (module docs; presets README)."""

    name: str
    source: str
    airframe: Airframe
    actuator: VariablePitchActuator
    drag: Drag

    def __post_init__(self) -> None:
        # Checked once, here: the types, the core's rules (finite coefficients and bounds, lags,
        # drag >= 0: building the simulator runs them) and what the trim divides by.
        for field, value, kind in (
            ("name", self.name, str), ("source", self.source, str), ("airframe", self.airframe, Airframe),
            ("actuator", self.actuator, VariablePitchActuator), ("drag", self.drag, Drag),
        ):
            if not isinstance(value, kind):
                raise TypeError(f"{field}: expected {kind.__name__}, got {type(value).__name__}")
        if self.airframe.rotor_count != 4:
            raise ValueError(f"airframe: a VPP quadcopter has 4 propellers, {self.airframe.name} has {self.airframe.rotor_count}")
        self.simulator()
        k1, k2, k3, _ = self.coefficients
        if not k1 > 0:
            raise ValueError(f"actuator.k: k1 (thrust per speed^2 per pitch) must be > 0, got {k1}")
        if not (k2 >= 0 and k3 >= 0):
            raise ValueError(f"actuator.k: k2 and k3 (drag torque coefficients) must be >= 0, got {k2}, {k3}")
        if not self.actuator.speed_bounds[1] > 0:
            raise ValueError(f"actuator.speed_bounds: the upper bound must be > 0, got {self.actuator.speed_bounds[1]}")
        if not self.actuator.pitch_bounds[1] > 0:
            raise ValueError(f"actuator.pitch_bounds: the upper bound must be > 0 (lift), got {self.actuator.pitch_bounds[1]}")

    @property
    def coefficients(self) -> tuple[float, float, float, float]:
        k = self.actuator.k
        return (float(k[0]), float(k[1]), float(k[2]), float(k[3]))

    def simulator(
        self,
        *,
        failed: Sequence[int] = (),
        wind: npt.ArrayLike = (0.0, 0.0, 0.0),
        wind_profile: Sequence[tuple[float, npt.ArrayLike]] | None = None,
    ) -> Simulator:
        """A :class:`~rotorfault.Simulator` of this vehicle with the 1-based ``failed`` propellers
        producing nothing (efficiency 0)."""
        rotors = _failed_set(self.airframe.rotor_count, failed)
        efficiency = np.ones(self.airframe.rotor_count)
        efficiency[[i - 1 for i in rotors]] = 0.0
        return Simulator(
            self.airframe.with_efficiency(efficiency), actuator=self.actuator, drag=self.drag,
            wind=wind, wind_profile=wind_profile,
        )


def preset(name: str = "wang") -> VppVehicle:
    """A shipped VPP vehicle preset by name (``wang``: Wang et al.'s vehicle)."""
    if not isinstance(name, str):
        raise TypeError(f"preset: expected a preset name (str), got {type(name).__name__}")
    if name not in presets():
        raise ValueError(f"preset: unknown VPP preset {name!r}; available: {', '.join(presets())}")
    raw = _rfcore.VariablePitchPreset.from_toml_str(_vpp_dir().joinpath(f"{name}.toml").read_text(encoding="utf-8"), name)
    # The actuator comes out of the core's parser as it is (issue 26: no field-by-field copy).
    return VppVehicle(raw.name, raw.source, Airframe.preset(raw.airframe), raw.actuator, Drag(linear_n_s_m=raw.linear_drag_n_s_m))


def _failed_set(count: int, failed: Sequence[int]) -> tuple[int, ...]:
    if isinstance(failed, (str, bytes)) or not isinstance(failed, Sequence):
        raise TypeError(f"failed: expected a sequence of 1-based propeller numbers, got {type(failed).__name__}")
    rotors = []
    for i in failed:
        if isinstance(i, bool) or not isinstance(i, (int, np.integer)):
            raise TypeError(f"failed: expected integers, got {type(i).__name__}")
        if not 1 <= int(i) <= count:
            raise ValueError(f"failed: propeller {i} does not exist (1..{count})")
        rotors.append(int(i))
    if len(set(rotors)) != len(rotors):
        raise ValueError(f"failed: propellers listed twice in {list(rotors)}")
    return tuple(sorted(rotors))


# -- trim ----------------------------------------------------------------------------------------


@dataclass(frozen=True)
class VppTrim:
    """A hover equilibrium of a VPP quadcopter.

    ``state``: 12 states (position and yaw as asked, the rest 0); ``command``: interleaved
    ``[omega_1, alpha_1, ...]`` (failed propellers at 0, 0); ``thrust_n``: each propeller's thrust;
    ``fixed_rotors``/``free_rotors``: the yaw groups (module docs); ``residual``: the norm of
    ``Simulator.state_derivative`` at the trim (the evidence)."""

    state: FloatArray
    command: FloatArray
    thrust_n: FloatArray
    failed: tuple[int, ...]
    fixed_rotors: tuple[int, ...]
    free_rotors: tuple[int, ...]
    residual: float

    @property
    def balanced(self) -> bool:
        """The evidence holds: ``residual`` at most :data:`TRIM_RESIDUAL_TOL` (:func:`trim`
        raises otherwise; :func:`fixed_pitch_trim` may return an unbalanced frame, and says so here)."""
        return bool(self.residual <= TRIM_RESIDUAL_TOL)

    def speed(self, rotor: int) -> float:
        return float(self.command[2 * (rotor - 1)])

    def pitch(self, rotor: int) -> float:
        return float(self.command[2 * (rotor - 1) + 1])


@dataclass(frozen=True)
class FeasibleSpeeds:
    """Where a trim exists (Wang eq. (14)-(16) generalised): the fixed group's common speed range,
    the free group's, and the common reaction torque range ``[lo, hi]`` (N m) of each group at the
    balance (Wang's ``r(omega_2)`` lies in ``free_torque_range_nm`` over the free group's own
    bounds, before the balance: ``[0.7714, 2]`` for his vehicle)."""

    fixed_rotors: tuple[int, ...]
    fixed_speed_range: tuple[float, float]
    free_rotors: tuple[int, ...]
    free_speed_range: tuple[float, float]
    free_torque_range_nm: tuple[float, float]
    torque_range_nm: tuple[float, float]


class _Problem:
    """The trim's ingredients for one vehicle and failed set (module docs)."""

    def __init__(self, vehicle: VppVehicle, failed: Sequence[int]) -> None:
        if not isinstance(vehicle, VppVehicle):
            raise TypeError(f"vehicle: expected a rotorfault.vpp.VppVehicle, got {type(vehicle).__name__}")
        airframe = vehicle.airframe
        m = airframe.rotor_count
        self.failed = _failed_set(m, failed)
        self.k1, self.k2, self.k3, self.k4 = vehicle.coefficients
        self.speed_lo, self.speed_hi = (float(v) for v in vehicle.actuator.speed_bounds)
        self.pitch_lo, self.pitch_hi = (float(v) for v in vehicle.actuator.pitch_bounds)
        healthy = np.array([i for i in range(m) if i + 1 not in self.failed], dtype=np.intp)
        if healthy.size == 0:
            raise ValueError("failed: every propeller failed; there is no trim")
        weight = airframe.mass_kg * airframe.gravity_m_s2
        rows = airframe.with_efficiency(np.ones(m)).effectiveness_matrix()[:3, healthy]
        target = np.array([weight, 0.0, 0.0])
        f, *_ = np.linalg.lstsq(rows, target, rcond=None)
        if scaled_norm(rows @ f - target) > 1e-9 * weight:
            raise ValueError(
                f"failed: with propeller(s) {list(self.failed)} failed no thrusts of propellers "
                f"{[int(i) + 1 for i in healthy]} give {weight:.6g} N with zero roll and pitch torque: no trim"
            )
        f[np.abs(f) < 1e-12 * weight] = 0.0
        self.thrust = np.zeros(m)
        self.thrust[healthy] = f
        self.healthy = tuple(int(i) + 1 for i in healthy)
        self.yaw_sign = airframe.spin_sign
        self.m = m

    def min_speed(self, rotor: int) -> float:
        """The lowest speed at which ``rotor`` makes its thrust within the pitch bounds."""
        f = self.thrust[rotor - 1]
        pitch = self.pitch_hi if f > 0 else self.pitch_lo
        if f == 0.0:
            return self.speed_lo
        if pitch == 0.0 or np.sign(pitch) != np.sign(f):
            raise ValueError(f"pitch_bounds: propeller {rotor} needs thrust {f:.6g} N, which no pitch within the bounds gives")
        return max(self.speed_lo, math.sqrt(f / (self.k1 * pitch)))

    def torque(self, rotor: int, speed: float) -> float:
        """Reaction torque magnitude of ``rotor`` at ``speed`` with its trim thrust (N m)."""
        f = float(self.thrust[rotor - 1])
        if f == 0.0:
            return self.k2 * speed * speed
        return self.k2 * speed * speed + self.k3 * f * f / (self.k1**2 * speed * speed) + self.k4 * f / (self.k1 * speed)

    def group_torque(self, rotors: Sequence[int], speed: float) -> float:
        return sum(self.torque(i, speed) for i in rotors)

    def groups(self, fixed: Sequence[int] | None) -> tuple[tuple[int, ...], tuple[int, ...]]:
        """(fixed, free) rotor groups: the fixed group given, or the healthy rotors spinning like
        the first failed propeller (clockwise with none failed)."""
        signs = {i: float(self.yaw_sign[i - 1]) for i in self.healthy}
        if fixed is None:
            reference = float(self.yaw_sign[self.failed[0] - 1]) if self.failed else -1.0
            fixed = tuple(i for i in self.healthy if signs[i] == reference)
        free = tuple(i for i in self.healthy if i not in fixed)
        if not fixed or not free:
            raise ValueError(
                f"speeds: the healthy propellers {list(self.healthy)} spin one way only, so nothing "
                "cancels their reaction torque: no trim"
            )
        if len({signs[i] for i in free}) != 1 or len({signs[i] for i in fixed}) != 1:
            raise ValueError(
                f"speeds: give the speed of every healthy propeller of one spin direction (fixed {list(fixed)}, "
                f"free {list(free)}): the free ones must share a spin direction and one speed"
            )
        return tuple(fixed), free

    def interval(self, rotors: Sequence[int]) -> tuple[float, float]:
        lo = max(self.min_speed(i) for i in rotors)
        if lo > self.speed_hi:
            raise ValueError(
                f"speed_bounds: propellers {list(rotors)} need speed {lo:.6g} at the pitch bound "
                f"{self.pitch_hi}, above the speed bound {self.speed_hi}"
            )
        return lo, self.speed_hi

    def require_increasing(self, rotors: Sequence[int], lo: float, hi: float) -> None:
        grid = np.linspace(max(lo, 1e-9 * hi), hi, 257)
        values = np.array([self.group_torque(rotors, s) for s in grid])
        if np.any(np.diff(values) <= 0):
            raise ValueError(
                f"speeds: the reaction torque of propellers {list(rotors)} is not increasing in speed on "
                f"[{lo:.6g}, {hi:.6g}]; the bisection trim does not apply to these coefficients"
            )

    def solve(self, rotors: Sequence[int], torque: float, lo: float, hi: float) -> float:
        """The speed in [lo, hi] at which ``rotors`` give ``torque`` (increasing; bisection)."""
        a, b = lo, hi
        for _ in range(200):
            if b - a <= SPEED_TOLERANCE * max(1.0, hi):
                break
            mid = 0.5 * (a + b)
            if self.group_torque(rotors, mid) < torque:
                a = mid
            else:
                b = mid
        return 0.5 * (a + b)


def feasible_speeds(vehicle: VppVehicle, *, failed: Sequence[int] = (1,), fixed_rotors: Sequence[int] | None = None) -> FeasibleSpeeds:
    """The speeds at which a hover trim exists (Wang eq. (14)-(16) for any failed set): each
    group's common speed range, the torque ranges (:class:`FeasibleSpeeds`). Raises
    ``ValueError`` naming the bound when there is none."""
    problem = _Problem(vehicle, failed)
    chosen = None
    if fixed_rotors is not None:
        chosen = rotor_numbers("fixed_rotors", fixed_rotors, problem.m)
        bad = [i for i in chosen if i not in problem.healthy]
        if bad:
            raise ValueError(f"fixed_rotors: propeller {bad[0]} is failed; give healthy propellers of one spin direction ({list(problem.healthy)})")
        if not chosen or len(set(chosen)) != len(chosen):
            raise ValueError(f"fixed_rotors: give each healthy propeller at most once and at least one, got {list(chosen)}")
    fixed, free = problem.groups(chosen)
    fixed_lo, fixed_hi = problem.interval(fixed)
    free_lo, free_hi = problem.interval(free)
    problem.require_increasing(fixed, fixed_lo, fixed_hi)
    problem.require_increasing(free, free_lo, free_hi)
    free_torque = (problem.group_torque(free, free_lo), problem.group_torque(free, free_hi))
    fixed_torque = (problem.group_torque(fixed, fixed_lo), problem.group_torque(fixed, fixed_hi))
    lo, hi = max(free_torque[0], fixed_torque[0]), min(free_torque[1], fixed_torque[1])
    if lo > hi:
        raise ValueError(
            f"speed_bounds: propellers {list(free)} make at least {free_torque[0]:.6g} N m of reaction torque "
            f"(pitch bound {problem.pitch_hi}) and propellers {list(fixed)} at most {fixed_torque[1]:.6g} N m "
            f"(speed bound {problem.speed_hi}): yaw cannot balance, no trim"
            if free_torque[0] > fixed_torque[1] else
            f"speed_bounds: propellers {list(fixed)} make at least {fixed_torque[0]:.6g} N m and propellers "
            f"{list(free)} at most {free_torque[1]:.6g} N m (speed bound {problem.speed_hi}): no trim"
        )
    return FeasibleSpeeds(
        fixed, (problem.solve(fixed, lo, fixed_lo, fixed_hi), problem.solve(fixed, hi, fixed_lo, fixed_hi)),
        free, (problem.solve(free, lo, free_lo, free_hi), problem.solve(free, hi, free_lo, free_hi)),
        free_torque, (lo, hi),
    )


def trim(
    vehicle: VppVehicle,
    *,
    failed: Sequence[int] = (1,),
    speeds: Mapping[int, float] | None = None,
    position: npt.ArrayLike = (0.0, 0.0, 0.0),
    yaw: float = 0.0,
) -> VppTrim:
    """The hover inputs of ``vehicle`` with the 1-based ``failed`` propellers (module docs).

    ``position`` (NED, m) and ``yaw`` (rad): where it hovers.
    ``speeds``: ``{propeller: speed}`` (rpm, the preset's speed unit) for every healthy propeller of one spin direction (the fixed
    group; Wang: ``{3: 9000}``); default: the failed propeller's spin direction at the middle of its
    feasible range (:func:`feasible_speeds`). The other group shares the balancing speed. Raises
    ``ValueError`` naming the field and bound when no trim exists."""
    problem = _Problem(vehicle, failed)
    pos = float_array("position", position, 1)
    if pos.shape != (3,) or not np.all(np.isfinite(pos)):
        raise ValueError(f"position: expected 3 finite entries, got {pos.tolist()}")
    heading = real("yaw", yaw)
    if not math.isfinite(heading):
        raise ValueError(f"yaw: must be finite, got {heading}")
    if speeds is None:
        fixed, free = problem.groups(None)
        window = feasible_speeds(vehicle, failed=problem.failed, fixed_rotors=fixed)
        fixed_speed = {i: 0.5 * sum(window.fixed_speed_range) for i in fixed}
    else:
        if not isinstance(speeds, Mapping):
            raise TypeError(f"speeds: expected a mapping {{propeller: speed}}, got {type(speeds).__name__}")
        fixed_speed = {}
        for key, value in speeds.items():
            if isinstance(key, bool) or not isinstance(key, (int, np.integer)):
                raise TypeError(f"speeds: keys are 1-based propeller numbers, got {key!r}")
            if int(key) not in problem.healthy:
                raise ValueError(f"speeds[{key}]: propeller {key} is {'failed' if int(key) in problem.failed else 'not on this vehicle'}")
            v = real(f"speeds[{key}]", value)
            if not (math.isfinite(v) and problem.speed_lo <= v <= problem.speed_hi):
                raise ValueError(f"speeds[{key}]: {v} lies outside speed_bounds [{problem.speed_lo}, {problem.speed_hi}]")
            if v < problem.min_speed(int(key)):
                raise ValueError(
                    f"speeds[{key}]: {v} is below {problem.min_speed(int(key)):.6g}, the speed at which propeller "
                    f"{key} makes its {problem.thrust[int(key) - 1]:.6g} N within pitch_bounds"
                )
            fixed_speed[int(key)] = v
        fixed, free = problem.groups(tuple(sorted(fixed_speed)))
    free_lo, free_hi = problem.interval(free)
    problem.require_increasing(free, free_lo, free_hi)
    needed = sum(problem.torque(i, s) for i, s in fixed_speed.items())
    low, high = problem.group_torque(free, free_lo), problem.group_torque(free, free_hi)
    if not low <= needed <= high:
        bound = (
            f"at their lowest speed {free_lo:.6g} (pitch bound {problem.pitch_hi}) they already make {low:.6g} N m"
            if needed < low else f"at the speed bound {free_hi:.6g} they make only {high:.6g} N m"
        )
        raise ValueError(
            f"speeds: propellers {list(fixed)} at {[fixed_speed[i] for i in fixed]} make {needed:.6g} N m of reaction "
            f"torque; propellers {list(free)} must cancel it, but {bound}: no trim (see feasible_speeds)"
        )
    common = problem.solve(free, needed, free_lo, free_hi)
    command = np.zeros(2 * problem.m)
    for i, s in [*fixed_speed.items(), *((i, common) for i in free)]:
        command[2 * (i - 1)] = s
        command[2 * (i - 1) + 1] = problem.thrust[i - 1] / (problem.k1 * s * s) if s > 0 else 0.0
    state = np.zeros(STATE_DIM)
    state[0:3] = pos
    state[8] = heading
    residual = scaled_norm(vehicle.simulator(failed=problem.failed).state_derivative(state, command))
    if not residual <= TRIM_RESIDUAL_TOL:
        raise ValueError(
            f"trim residual: the trim leaves ||f(x, u)|| = {residual:.3g} (at most {TRIM_RESIDUAL_TOL:g}): "
            "the speeds found do not balance the model"
        )
    return VppTrim(
        frozen_array("state", state, 1), frozen_array("command", command, 1), frozen_array("thrust_n", problem.thrust, 1),
        problem.failed, fixed, free, residual,
    )


def fixed_pitch_trim(vehicle: VppVehicle, *, failed: Sequence[int] = (1,), pitch_rad: float = 0.26) -> VppTrim:
    """Wang Sec. 3.4's conventional quadcopter: every pitch fixed at ``pitch_rad`` (thrust
    ``k1 alpha omega^2``), speeds from the thrusts alone (``omega_3 = 0`` with propeller 1 failed).
    Yaw balances only on a frame whose opposite motors spin opposite ways (the
    ``wang-fixed-pitch`` airframe); ``residual`` says whether it does."""
    problem = _Problem(vehicle, failed)
    alpha = real("pitch_rad", pitch_rad)
    if not (math.isfinite(alpha) and problem.pitch_lo <= alpha <= problem.pitch_hi and alpha > 0):
        raise ValueError(f"pitch_rad: must lie in (0, {problem.pitch_hi}], got {alpha}")
    if np.any(problem.thrust < 0):
        raise ValueError("failed: the fixed-pitch trim needs a negative thrust, which fixed pitch cannot give")
    speeds = np.sqrt(problem.thrust / (problem.k1 * alpha))
    if np.any(speeds > problem.speed_hi):
        raise ValueError(f"speed_bounds: the fixed-pitch trim needs speeds {speeds.tolist()} above {problem.speed_hi}")
    command = np.zeros(2 * problem.m)
    command[0::2] = speeds
    command[1::2] = alpha
    command[[2 * (i - 1) for i in problem.failed]] = 0.0
    state = np.zeros(STATE_DIM)
    residual = scaled_norm(vehicle.simulator(failed=problem.failed).state_derivative(state, command))
    return VppTrim(
        frozen_array("state", state, 1), frozen_array("command", command, 1), frozen_array("thrust_n", problem.thrust, 1),
        problem.failed, (), problem.healthy, residual,
    )


def fixed_pitch(vehicle: VppVehicle, airframe: str = "wang-fixed-pitch") -> VppVehicle:
    """``vehicle`` on a fixed-pitch comparison airframe preset, named after it: Sec. 3.4's spin
    layout ``wang-fixed-pitch`` (default) or the standard layout ``wang-standard-fixed-pitch``
    (both [0, 13] N; fly them with ``pitch_fixed=True`` models and :func:`fixed_pitch_trim`)."""
    import dataclasses

    if not isinstance(airframe, str):
        raise TypeError(f"airframe: expected an airframe preset name, got {type(airframe).__name__}")
    frame = Airframe.preset(airframe)
    return dataclasses.replace(vehicle, name=frame.name, airframe=frame)


# -- linear model and controllability ------------------------------------------------------------


def _snap(matrix: FloatArray) -> FloatArray:
    out = np.array(matrix, dtype=np.float64)
    scale = np.max(np.abs(out), axis=0, keepdims=True)
    out[np.abs(out) <= ROUNDOFF_RTOL * scale] = 0.0
    return out


@dataclass(frozen=True)
class VppLinearization:
    """Deprecated (one release): what :func:`linearize` returned before it returned a
    python-control system (:class:`~rotorfault.control.systems.LinearModel`, whose ``A``, ``B``,
    ``input_labels`` and ``command_columns`` these are). :func:`controllability` still takes it,
    warning."""

    a: FloatArray
    b: FloatArray
    inputs: tuple[str, ...]
    columns: tuple[int, ...]


def linearize(
    vehicle: VppVehicle, at: VppTrim, *, pitch_fixed: bool = False, inputs: VppInputs = "every-channel", step: float = 1e-6,
) -> LinearModel:
    """The Jacobians of the simulator's own dynamics at ``at``
    (:func:`rotorfault.control.lqr.linearize`: central differences, one-sided at a bound) restricted
    to the design's inputs, as a python-control ``StateSpace``
    (:class:`~rotorfault.control.systems.LinearModel`: states ``x ... r``, the operating point
    ``x_trim``, ``u_trim``, and ``input_map``, how an input moves the simulator's command vector,
    ``u = u_trim + input_map (v - v_trim)``). ``inputs="every-channel"``: every healthy speed and
    pitch (inputs ``omega_<i>``, ``alpha_<i>``); ``inputs="wang"``: Wang's design (Sec. 3.1-3.2:
    the trim's fixed group of speeds, Wang's ``omega_3``, held at the trim, "omega_3 remains
    constant all the time"; the free group's speeds one shared input ``omega_2=omega_4`` of
    eq. (11); every healthy pitch an input: Wang's ``z = [omega_2, alpha_2, alpha_3, alpha_4]``).
    ``pitch_fixed`` keeps the speeds only (Wang Sec. 3.4: the fixed-pitch quadcopter)."""
    if not isinstance(at, VppTrim):
        raise TypeError(f"at: expected a VppTrim, got {type(at).__name__}")
    if inputs not in get_args(VppInputs):
        raise ValueError(f"inputs: must be one of {', '.join(get_args(VppInputs))}, got {inputs!r}")
    simulator = vehicle.simulator(failed=at.failed)
    full = _linearize(simulator, at, step=step)
    # Central differences leave round-off (about eps |f| / step, 1e-18 here) where the model has
    # an exact zero; a scale-free rank would equilibrate such a row up to unit size and read noise
    # as authority. Entries below ROUNDOFF_RTOL of their column's largest are that noise.
    a = _snap(full.A)
    b = _snap(full.B)
    channels = 2 * vehicle.airframe.rotor_count
    moves: list[tuple[str, tuple[int, ...]]] = []
    shared = inputs == "wang" and len(at.free_rotors) > 0
    if shared:
        free = tuple(i for i in at.free_rotors if i not in at.failed)
        moves.append(("=".join(f"omega_{i}" for i in free), tuple(2 * (i - 1) for i in free)))
    for i in range(1, vehicle.airframe.rotor_count + 1):
        if i in at.failed:
            continue
        if not shared:
            moves.append((f"omega_{i}", (2 * (i - 1),)))
        if not pitch_fixed:
            moves.append((f"alpha_{i}", (2 * (i - 1) + 1,)))
    input_map = np.zeros((channels, len(moves)))
    for j, (_, moved) in enumerate(moves):
        input_map[list(moved), j] = 1.0
    from .systems import LinearModel  # python-control: imported when a model is built

    return LinearModel(
        a, b @ input_map, inputs=[name for name, _ in moves], x_trim=at.state, u_trim=at.command,
        command_columns=[moved[0] for _, moved in moves], input_map=input_map, name=f"{vehicle.airframe.name} linearisation",
    )


def _model_matrices(model: LinearModel | VppLinearization) -> tuple[FloatArray, FloatArray, tuple[str, ...]]:
    """``(A, B, input names)`` of a model from :func:`linearize` (or, warning, the old
    :class:`VppLinearization`)."""
    if isinstance(model, VppLinearization):
        warn("rotorfault.vpp.VppLinearization", "the python-control system rotorfault.vpp.linearize returns", stacklevel=4)
        return model.a, model.b, model.inputs
    if not (hasattr(model, "A") and hasattr(model, "B") and hasattr(model, "input_labels")):
        raise TypeError(f"model: expected the python-control system of rotorfault.vpp.linearize, got {type(model).__name__}")
    return np.asarray(model.A, dtype=np.float64), np.asarray(model.B, dtype=np.float64), tuple(model.input_labels)


@dataclass(frozen=True)
class ControllabilityResult:
    """``rank``: the scale-free rank of ``[B AB ... A^11 B]`` (core rule); ``plain_rank``: numpy's
    default SVD rank of the unscaled matrix (for contrast: round-off decides it);
    ``uncontrollable_directions``: a basis of the combinations of states no input moves (the left
    null space of the controllability matrix, the uncontrollable part of the Kalman
    decomposition), each in state names (``"yaw rate r together with p and q: 0.132 p + 0.132 q -
    r"``; a single state when the direction is one state); ``uncontrollable_states``: the states
    that take part in them; ``basis``: orthonormal basis of the controllable subspace (scaled
    states)."""

    rank: int
    plain_rank: int
    uncontrollable_directions: tuple[Direction, ...]
    uncontrollable_states: tuple[str, ...]
    basis: FloatArray


def controllability(model: LinearModel | VppLinearization, *, input_scale: npt.ArrayLike | None = None) -> ControllabilityResult:
    """Rank and Kalman decomposition of ``model`` (the python-control system of
    :func:`linearize`). States are scaled by :data:`STATE_SCALE`,
    inputs by ``input_scale`` (default: 1000 per speed, 0.1 rad per pitch) so one SVD sees
    comparable columns; the rank is also the core's scale-free rank, and the uncontrollable
    directions are the left null space of the same equilibrated matrix (one rank rule)."""
    model_a, model_b, inputs = _model_matrices(model)
    n = STATE_DIM
    if input_scale is None:
        su = np.array([1000.0 if name.startswith("omega") else 0.1 for name in inputs])
    else:
        su = float_array("input_scale", input_scale, 1)
        if su.shape != (len(inputs),) or not np.all(np.isfinite(su) & (su > 0)):
            raise ValueError(f"input_scale: expected {len(inputs)} finite entries > 0")
    a = model_a / STATE_SCALE[:, None] * STATE_SCALE[None, :]
    b = model_b / STATE_SCALE[:, None] * su[None, :]
    blocks = [b]
    for _ in range(n - 1):
        blocks.append(a @ blocks[-1])
    q = np.hstack(blocks)
    raw = [model_b]
    for _ in range(n - 1):
        raw.append(model_a @ raw[-1])
    rank = int(_rfcore.scale_free_rank(q))
    plain = int(np.linalg.matrix_rank(np.hstack(raw)))
    own_rank, null = left_null_space(q)
    if own_rank != rank:
        raise ValueError(
            f"model: the core's scale-free rank ({rank}) and numpy's on the same equilibrated matrix "
            f"({own_rank}) disagree: the controllability matrix is at the edge of rank deficiency"
        )
    u, s, _ = np.linalg.svd(q)
    basis = u[:, :rank]
    # Scaled state x_s = x / STATE_SCALE, so a functional w_s^T x_s is (w_s / STATE_SCALE)^T x.
    directions = describe_directions(null.T, 1.0 / STATE_SCALE, STATE_NAMES, STATE_LABELS)
    involved = np.zeros(n, dtype=bool)
    for d in directions:
        involved |= d.coefficients != 0.0
    names = tuple(STATE_NAMES[j] for j in range(n) if involved[j])
    return ControllabilityResult(rank, plain, directions, names, frozen_array("basis", basis, 2))


# -- LQR -----------------------------------------------------------------------------------------

#: The control period an LQR is checked at when none is given: the simulator's default (the
#: core's ``SimulationConfig``).
DEFAULT_DT_S: float = _rfcore.SimulationConfig().dt_s


def lqr(
    vehicle: VppVehicle,
    at: VppTrim,
    *,
    q: npt.ArrayLike | None = None,
    r: npt.ArrayLike | None = None,
    pitch_fixed: bool = False,
    inputs: VppInputs = "every-channel",
    dt_s: float = DEFAULT_DT_S,
) -> LinearFeedback:
    """An LQR on the design's inputs about ``at`` (:func:`linearize`: ``inputs="wang"`` is Wang's
    design, the fixed group's speeds held at the trim and the free group's sharing one input;
    ``"every-channel"`` every healthy speed and pitch), as a full-width
    :class:`~rotorfault.control.LinearFeedback` (failed channels held at 0, held channels at the
    trim). Defaults (Bryson): 1 m, 1 m/s, 0.1 rad, 1 rad/s state errors against 1000 speed units
    and 0.05 rad per input. ``pitch_fixed``: speeds only (the fixed-pitch quadcopter; pitches held
    at the trim's).
    ``dt_s``: the control period of the simulator that flies it (the sampled loop is checked
    there). Raises ``ValueError`` naming the check that fails (:func:`lqr_design`): e.g. the
    fixed-pitch model, which no input can stabilise (the modes named). The returned feedback's
    ``design`` is the checked :class:`~rotorfault.control.riccati.LqrDesign` (its gain has one row
    per healthy channel)."""
    if not isinstance(pitch_fixed, bool):
        raise TypeError(f"pitch_fixed: expected a bool, got {type(pitch_fixed).__name__}")
    model = linearize(vehicle, at, pitch_fixed=pitch_fixed, inputs=inputs)
    q_state = np.diag(1.0 / STATE_SCALE**2) if q is None else q
    r_in = np.diag([1.0 / (1000.0**2 if name.startswith("omega") else 0.05**2) for name in model.input_labels]) if r is None else r
    kind = "fixed-pitch" if pitch_fixed else "VPP"
    failed = f"propeller(s) {', '.join(map(str, at.failed))} failed" if at.failed else "no propeller failed"
    design = design_lqr(
        model, q_state, r_in, dt_s=dt_s, state_names=STATE_NAMES, state_labels=STATE_LABELS,
        model=f"the {kind} hover model of {vehicle.name} ({failed}; inputs {', '.join(model.input_labels)})",
    )
    full = model.input_map @ design.gain
    return LinearFeedback(full, at.state, at.command, design=design)


__all__ = [
    "STATE_NAMES",
    "DEFAULT_DT_S",
    "ControllabilityResult",
    "FeasibleSpeeds",
    "VppLinearization",
    "VppTrim",
    "VppVehicle",
    "controllability",
    "feasible_speeds",
    "fixed_pitch",
    "fixed_pitch_trim",
    "linearize",
    "lqr",
    "preset",
    "presets",
    "trim",
]

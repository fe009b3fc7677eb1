"""The allocator: one validated allocation problem (:class:`Allocator`), solved for one virtual
control or a batch by the active set (exact, the closed loops' path), Clarabel (the reference;
prioritised allocation) or the weighted pseudo-inverse, each answer with its KKT certificate
(:class:`Allocation`). The problem and the methods are described in :mod:`rotorfault.allocation`."""

from __future__ import annotations

import numbers
from collections.abc import Sequence
from typing import Any, cast, get_args

import numpy as np
import numpy.typing as npt

from .. import _rfcore
from .._typing import AllocationMethod, AllocationStatus, ControlAxes, SolvedBy
from .._util.convert import FloatArray, control_axes, count, flag, float_array, frozen_array, real
from .._util.core_result import CoreResult
from .._util.deprecation import dataclass_compat
from .._util.tables import Column, Tabular
from ..analysis.airframe import Airframe

METHODS: tuple[AllocationMethod, ...] = get_args(AllocationMethod)
#: How ``CoreResult._from_core`` makes a result without ``__init__`` (which refuses users).
_new_result = object.__new__
_DEFAULTS = _rfcore.AllocationSettings()
#: The certificate tolerance by default (the core's ``ActiveSetSettings::default()``).
DEFAULT_TOLERANCE: float = _DEFAULTS.tolerance
#: Clarabel's default tolerance here (the core's ``ClarabelSettings::default()``).
CLARABEL_TOLERANCE: float = _DEFAULTS.clarabel_tolerance
#: The KKT residuals of an allocation and the tolerance they are held to: ``stationarity``,
#: ``complementarity``, ``bound_violation``, ``tolerance``, ``holds``, ``worst``.
Certificate = _rfcore.Certificate


class Allocation(CoreResult, Tabular):
    """The result of :func:`allocate`. For one virtual control ``commands`` is (m,), ``achieved``
    (n,) and ``status`` a string; for N of them (N, m), (N, n) and a tuple of N strings.

    ``status``: ``"optimal"`` (the certificate holds), ``"almost-optimal"`` (clarabel at
    reduced accuracy), ``"iteration-limit"`` (neither the active set nor its fallback could
    certify: commands feasible, not proven optimal), ``"unconstrained"`` (pinv) or ``"failed"``
    (clarabel found no solution). ``certificate`` (one per row for a batch): the KKT residuals
    of the commands (:class:`Certificate`). ``solved_by``: ``"active-set"``, ``"clarabel"`` or
    ``"pinv"``. ``fallbacks``: how many answers the active set's Clarabel fallback produced.

    It holds the core's result (``_rfcore.SingleAllocation`` for one active-set answer,
    ``_rfcore.AllocationBatch`` otherwise) and reads every field through it: no copied fields,
    and an array is made when first read (a caller who reads only the commands pays for no
    other array).

    ``to_arrow()`` / ``to_pandas()``: one row per virtual control (``virtual_control_<k>``,
    ``achieved_<k>``, ``rotor_<i>_command``, the status, the solver and the certificate's
    residuals), in the problem's units (N and N m for an airframe).

    Examples:

        >>> import rotorfault as rf
        >>> a = rf.allocate(rf.Airframe.preset("ke-quadcopter"), [[7.0, 0, 0, 0], [7.0, 0.1, 0, 0]])
        >>> a.commands.shape, a.status
        ((2, 4), ('optimal', 'optimal'))
    """

    __slots__ = ()
    FIELDS = ("commands", "achieved", "virtual_control", "status", "iterations", "certificate", "solved_by", "fallbacks")
    _core: _rfcore.SingleAllocation | _rfcore.AllocationBatch

    def __init__(self) -> None:
        raise TypeError("Allocation: made by allocate() or Allocator.allocate(), not constructed")

    @property
    def commands(self) -> FloatArray:
        """Rotor commands, (m,) or (N, m), in the problem's units (N for an airframe)."""
        return self._core.commands

    @property
    def achieved(self) -> FloatArray:
        """What the commands produce, ``M T``: (n,) or (N, n)."""
        return self._core.achieved

    @property
    def virtual_control(self) -> FloatArray:
        """The virtual control(s) allocated, (n,) or (N, n)."""
        return self._core.virtual_control

    @property
    def status(self) -> AllocationStatus | tuple[AllocationStatus, ...]:
        """The solver's status (a tuple of one per row for a batch)."""
        return cast("AllocationStatus | tuple[AllocationStatus, ...]", self._core.status)

    @property
    def iterations(self) -> int | tuple[int, ...]:
        """Iterations of the solver (a tuple of one per row for a batch)."""
        return self._core.iterations

    @property
    def certificate(self) -> _rfcore.Certificate | tuple[_rfcore.Certificate, ...]:
        """The KKT residuals of the commands (a tuple of one per row for a batch)."""
        return self._core.certificate

    @property
    def solved_by(self) -> SolvedBy | tuple[SolvedBy, ...]:
        """Which solver gave the commands (a tuple of one per row for a batch)."""
        return cast("SolvedBy | tuple[SolvedBy, ...]", self._core.solved_by)

    @property
    def fallbacks(self) -> int:
        """How many answers the active set's Clarabel fallback produced."""
        return self._core.fallbacks

    @property
    def attained(self) -> bool | np.ndarray[Any, np.dtype[np.bool_]]:
        """Whether the rotors produce the virtual control exactly (to 1e-9 of its size)."""
        scale = np.maximum(np.max(np.abs(self.virtual_control), axis=-1), 1e-300)
        ok = np.max(np.abs(self.achieved - self.virtual_control), axis=-1) <= 1e-9 * scale
        return bool(ok) if np.ndim(ok) == 0 else ok

    @property
    def residual(self) -> FloatArray:
        """``u_c - M T``: what the rotors could not give."""
        out: FloatArray = self.virtual_control - self.achieved
        return out

    def _table_columns(self) -> list[Column]:
        def rows(value: Any) -> list[Any]:
            return list(value) if isinstance(value, tuple) else [value]

        virtual, achieved, commands = (np.atleast_2d(a) for a in (self.virtual_control, self.achieved, self.commands))
        certificates = rows(self.certificate)
        attained = np.atleast_1d(self.attained)
        columns: list[Column] = [(f"virtual_control_{k + 1}", "float64", virtual[:, k]) for k in range(virtual.shape[1])]
        columns += [(f"achieved_{k + 1}", "float64", achieved[:, k]) for k in range(achieved.shape[1])]
        columns += [(f"rotor_{i + 1}_command", "float64", commands[:, i]) for i in range(commands.shape[1])]
        return columns + [
            ("attained", "bool", attained),
            ("status", "string", rows(self.status)),
            ("solved_by", "string", rows(self.solved_by)),
            ("iterations", "int64", rows(self.iterations)),
            ("certificate_holds", "bool", [c.holds for c in certificates]),
            ("stationarity", "float64", [c.stationarity for c in certificates]),
            ("complementarity", "float64", [c.complementarity for c in certificates]),
            ("bound_violation", "float64", [c.bound_violation for c in certificates]),
        ]

    def _table_title(self) -> str:
        return f"allocation: {np.atleast_2d(self.commands).shape[0]} virtual control(s), {self.fallbacks} fallback(s)"


class Allocator:
    """A validated allocation problem, reusable across calls and by
    :class:`rotorfault.control.Allocated`.

    ``target``: an :class:`~rotorfault.Airframe` (its effectiveness matrix, efficiencies applied,
    and thrust bounds) or an n x m matrix (then ``bounds`` is required). ``weights``: n entries
    >= 0 (default all 1). ``bounds``: ``(lower, upper)``, each a number or m entries.
    ``give_up_yaw``: with an airframe, drop the yaw row (n = 3). ``tolerance``,
    ``max_iterations``, ``clarabel_tolerance``: the solver settings of the module docs (None:
    the core's defaults); they apply to every allocation of this allocator, also inside
    :class:`rotorfault.control.Allocated`.

    Examples:

        >>> import rotorfault as rf
        >>> allocator = rf.Allocator(rf.Airframe.preset("ke-quadcopter"))
        >>> allocator.allocate([7.0, 0.0, 0.0, 0.1]).commands.round(4).tolist()
        [3.256, 0.244, 3.256, 0.244]
    """

    def __init__(
        self,
        target: Airframe | npt.ArrayLike,
        *,
        weights: npt.ArrayLike | None = None,
        bounds: tuple[npt.ArrayLike, npt.ArrayLike] | None = None,
        regularization: float = 0.0,
        preferred: npt.ArrayLike | None = None,
        give_up_yaw: bool = False,
        axes: ControlAxes | None = None,
        tolerance: float | None = None,
        max_iterations: int | None = None,
        clarabel_tolerance: float | None = None,
    ) -> None:
        drop_yaw = flag("give_up_yaw", give_up_yaw)
        settings = _settings(tolerance, max_iterations, clarabel_tolerance)
        if isinstance(target, Airframe):
            names = control_axes(drop_yaw, axes)
            matrix = target.wrench_matrix() if names == "wrench" else target.effectiveness_matrix()
            if drop_yaw:
                matrix = matrix[:3]
            default_bounds: tuple[FloatArray, FloatArray] | None = (target.min_thrust_n, target.max_thrust_n)
        else:
            if drop_yaw or axes is not None:
                field = "give_up_yaw" if drop_yaw else "axes"
                raise ValueError(f"{field}: only applies to an Airframe (pick the rows of the matrix yourself)")
            matrix = float_array("matrix", target, 2)
            default_bounds = None
        n, m = matrix.shape
        if bounds is None:
            if default_bounds is None:
                raise ValueError("bounds: required with a matrix, as (lower, upper)")
            lower, upper = default_bounds
        else:
            lower, upper = _bounds(bounds, m)
        w = np.ones(n) if weights is None else float_array("weights", weights, 1)
        pref = np.zeros(m) if preferred is None else float_array("preferred", preferred, 1)
        gamma = real("regularization", regularization)
        self._core = _rfcore.AllocationProblem(matrix, w, lower, upper, gamma, pref, settings)
        self._allocate_one = self._core.allocate_one
        self.settings = settings
        self.matrix = frozen_array("matrix", matrix, 2)
        self.weights = frozen_array("weights", w, 1)
        self.lower = frozen_array("bounds.lower", lower, 1)
        self.upper = frozen_array("bounds.upper", upper, 1)
        self.regularization = gamma
        self.preferred = frozen_array("preferred", pref, 1)

    @property
    def actuator_count(self) -> int:
        return int(self.matrix.shape[1])

    @property
    def virtual_dimension(self) -> int:
        return int(self.matrix.shape[0])

    def _pinv_commands(self, virtual_controls: np.ndarray) -> np.ndarray:
        """The pseudo-inverse's commands (N, m) for rows of virtual controls (N, n), whatever this
        allocator's solver settings (the pseudo-inverse reads none of them): the linear map a
        design on the virtual control needs (:func:`rotorfault.lqr_hover_allocated`), not a
        user's request for ``method="pinv"``, so the unused-settings rule does not apply."""
        rows = np.ascontiguousarray(virtual_controls, dtype=np.float64)
        return np.asarray(_rfcore.allocate(self._core, rows, "pinv", None).commands)

    def allocate(
        self,
        virtual_control: npt.ArrayLike,
        *,
        method: AllocationMethod = "active-set",
        priorities: Sequence[Sequence[int]] | None = None,
    ) -> Allocation:
        """Allocates one virtual control (n,) or a batch (N, n), in parallel without the GIL,
        with this allocator's settings."""
        if method == "active-set" and priorities is None:
            # The fast path: n floats as given (a float64 vector, a list or tuple of floats),
            # one core call that validates them (the bound method kept at construction); anything
            # else takes the general path below. The result is made as `_from_core` makes it,
            # inline, without the classmethod's call (issue 32: ~80 ns of this wrapper's ~490).
            one = self._allocate_one(virtual_control)
            if one is not None:
                out: Allocation = _new_result(Allocation)
                out._core = one
                return out
        if not isinstance(method, str):
            raise TypeError(f"method: expected a string, got {type(method).__name__}")
        if method not in METHODS:
            raise ValueError(f"method: expected one of {', '.join(map(repr, METHODS))}, got {method!r}")
        _require_used_settings(self.settings, method)
        if isinstance(virtual_control, (str, bytes)):
            raise TypeError(f"virtual_control: expected an array of numbers, got {type(virtual_control).__name__}")
        try:
            ndim = np.ndim(virtual_control)
        except ValueError as exc:
            raise TypeError(f"virtual_control: expected an array of numbers ({exc})") from None
        if ndim not in (1, 2):
            raise ValueError(f"virtual_control: expected shape (n,) or (N, n), got {ndim} dimensions")
        given = float_array("virtual_control", virtual_control, ndim)
        if given.size == 0:
            raise ValueError(f"virtual_control: expected {self.virtual_dimension} entries per row, got an empty array")
        rows = given.reshape(-1, given.shape[-1])
        if rows.shape[1] != self.virtual_dimension:
            raise ValueError(
                f"virtual_control: expected {self.virtual_dimension} entries per row "
                f"(rows of the allocation matrix), got {rows.shape[1]}"
            )
        groups = None if priorities is None else _priorities(priorities)
        batch = _rfcore.allocate(self._core, np.ascontiguousarray(rows), method, groups, ndim == 1)
        result: Allocation = Allocation._from_core(batch)
        return result

    def rate_limited(self, previous: npt.ArrayLike, max_change: float | npt.ArrayLike) -> Allocator:
        """A copy whose bounds also keep each command within ``max_change`` (a number or one per
        actuator, e.g. rate x control period) of ``previous``: Lanzon's rate limit (11) folded into
        the box. A previous command outside the bounds is pulled to the nearest bound, so the
        result is always a valid box."""
        prev = float_array("previous", previous, 1)
        delta = (
            np.full(self.actuator_count, real("max_change", max_change))
            if isinstance(max_change, numbers.Real) and not isinstance(max_change, bool)
            else float_array("max_change", max_change, 1)
        )
        lower, upper = self._core.rate_limited_bounds(prev, delta)
        return Allocator(
            self.matrix, weights=self.weights, bounds=(lower, upper), regularization=self.regularization,
            preferred=self.preferred, tolerance=self.settings.tolerance, max_iterations=self.settings.max_iterations,
            clarabel_tolerance=self.settings.clarabel_tolerance,
        )

    def objective(self, virtual_control: npt.ArrayLike, commands: npt.ArrayLike) -> tuple[float, float]:
        """``(objective, kkt_residual)`` of any commands: the residual (command units) is zero
        exactly at an optimum, whichever solver produced it."""
        u = float_array("virtual_control", virtual_control, 1)
        t = float_array("commands", commands, 1)
        value, kkt = self._core.objective(u, t)
        return float(value), float(kkt)


def allocate(
    target: Airframe | npt.ArrayLike,
    virtual_control: npt.ArrayLike,
    *,
    weights: npt.ArrayLike | None = None,
    bounds: tuple[npt.ArrayLike, npt.ArrayLike] | None = None,
    method: AllocationMethod = "active-set",
    regularization: float = 0.0,
    preferred: npt.ArrayLike | None = None,
    priorities: Sequence[Sequence[int]] | None = None,
    give_up_yaw: bool = False,
    axes: ControlAxes | None = None,
    tolerance: float | None = None,
    max_iterations: int | None = None,
    clarabel_tolerance: float | None = None,
) -> Allocation:
    """Rotor commands for ``virtual_control`` (n,) or a batch (N, n). See :class:`Allocator` for
    the arguments and the module docs for the methods and settings. With an airframe and no
    ``bounds``, ``regularization`` or ``preferred``, the prepared problem is kept on the
    (immutable) airframe, keyed by the weights and settings, so repeated calls are cheap.

    Examples:

        >>> import rotorfault as rf
        >>> ke = rf.Airframe.preset("ke-quadcopter")
        >>> a = rf.allocate(ke, [7.0, 0.0, 0.0, 0.0])
        >>> a.commands.round(4).tolist(), a.status
        ([1.75, 1.75, 1.75, 1.75], 'optimal')
    """
    key = _cache_key(target, weights, bounds, regularization, preferred, give_up_yaw, axes, tolerance, max_iterations, clarabel_tolerance)
    if key is not None:
        cache: dict[Any, Allocator] | None = getattr(target, "_allocators", None)
        if cache is None:
            cache = {}
            target._allocators = cache  # type: ignore[union-attr]
        allocator = cache.get(key)
        if allocator is None:
            allocator = Allocator(target, weights=weights, give_up_yaw=give_up_yaw, axes=axes, tolerance=tolerance,
                                  max_iterations=max_iterations, clarabel_tolerance=clarabel_tolerance)
            if len(cache) >= _CACHE_SIZE:
                cache.clear()
            cache[key] = allocator
    else:
        allocator = Allocator(
            target, weights=weights, bounds=bounds, regularization=regularization, preferred=preferred,
            give_up_yaw=give_up_yaw, axes=axes, tolerance=tolerance, max_iterations=max_iterations,
            clarabel_tolerance=clarabel_tolerance,
        )
    return allocator.allocate(virtual_control, method=method, priorities=priorities)


def _require_used_settings(settings: _rfcore.AllocationSettings, method: str) -> None:
    """A setting the method does not read is refused, not dropped: ``"pinv"`` has no iterations
    and no Clarabel, and ``"pinv"`` and ``"clarabel"`` hold their certificates to
    :data:`DEFAULT_TOLERANCE` (``tolerance=1e-3`` gave a certificate held to 1e-9)."""
    unused = []
    if method != "active-set" and settings.tolerance != DEFAULT_TOLERANCE:
        unused.append(f"tolerance: method={method!r} holds its certificate to DEFAULT_TOLERANCE = {DEFAULT_TOLERANCE:g} "
                      f"(only \"active-set\" takes another), got {settings.tolerance:g}")
    if method == "pinv" and settings.max_iterations is not None:
        unused.append(f"max_iterations: method=\"pinv\" does not iterate, got {settings.max_iterations}")
    if method == "pinv" and settings.clarabel_tolerance != CLARABEL_TOLERANCE:
        unused.append(f"clarabel_tolerance: method=\"pinv\" does not call Clarabel, got {settings.clarabel_tolerance:g}")
    if unused:
        raise ValueError(unused[0])


_CACHE_SIZE = 32
_KEY_TYPES = (float, int)


def _cache_key(
    target: Any, weights: Any, bounds: Any, regularization: Any, preferred: Any, give_up_yaw: Any, *settings: Any
) -> tuple[Any, ...] | None:
    """The key of :func:`allocate`'s cache on an airframe, or None when the call is not
    cacheable (anything but an airframe with default bounds, regularisation and preferred
    commands, weights a list/tuple of plain numbers or None, plain-number settings). Exact types
    only, so every value a key holds is validated once, when its allocator is built."""
    if type(target) is not Airframe or bounds is not None or preferred is not None or type(give_up_yaw) is not bool:
        return None
    if type(regularization) not in _KEY_TYPES or regularization != 0:
        return None
    if not all(v is None or type(v) in _KEY_TYPES for v in settings):
        return None
    if weights is None:
        w: tuple[Any, ...] | None = None
    elif type(weights) in (list, tuple) and all(type(x) in _KEY_TYPES for x in weights):
        w = tuple(weights)
    else:
        return None
    return (w, give_up_yaw, *settings)


dataclass_compat(Allocation)


def _settings(tolerance: Any, max_iterations: Any, clarabel_tolerance: Any) -> _rfcore.AllocationSettings:
    """Types checked here, values by the core (``ActiveSetSettings::check``, Clarabel's)."""
    return _rfcore.AllocationSettings(
        tolerance=None if tolerance is None else real("tolerance", tolerance),
        max_iterations=None if max_iterations is None else count("max_iterations", max_iterations),
        clarabel_tolerance=None if clarabel_tolerance is None else real("clarabel_tolerance", clarabel_tolerance),
    )


def _bounds(bounds: Any, m: int) -> tuple[FloatArray, FloatArray]:
    if not isinstance(bounds, (tuple, list)) or len(bounds) != 2:
        raise TypeError("bounds: expected a pair (lower, upper), each a number or one value per actuator")
    out = []
    for name, value in zip(("lower", "upper"), bounds):
        if isinstance(value, numbers.Real) and not isinstance(value, bool):
            out.append(np.full(m, float(value)))
        else:
            out.append(float_array(f"bounds.{name}", value, 1))
    return out[0], out[1]


def _priorities(priorities: Any) -> list[list[int]]:
    if isinstance(priorities, (str, bytes)) or not hasattr(priorities, "__iter__"):
        raise TypeError("priorities: expected a list of groups of row indices, e.g. [[0, 1, 2], [3]]")
    groups = []
    for k, group in enumerate(priorities):
        if isinstance(group, (str, bytes)) or not hasattr(group, "__iter__"):
            raise TypeError(f"priorities[{k}]: expected a list of row indices, got {type(group).__name__}")
        rows = []
        for r in group:
            if isinstance(r, bool) or not isinstance(r, numbers.Integral):
                raise TypeError(f"priorities[{k}]: expected integer row indices, got {r!r}")
            index = int(r)
            if not 0 <= index < 2**32:
                raise ValueError(f"priorities[{k}]: row indices must be in 0..n-1, got {index}")
            rows.append(index)
        groups.append(rows)
    return groups


def _positive_int(field: str, value: Any) -> int:
    number = count(field, value)
    if not 1 <= number <= 2**32 - 1:
        raise ValueError(f"{field}: must be between 1 and {2**32 - 1}, got {number}")
    return number


__all__ = [
    "CLARABEL_TOLERANCE",
    "DEFAULT_TOLERANCE",
    "METHODS",
    "Allocation",
    "Allocator",
    "Certificate",
    "allocate",
]

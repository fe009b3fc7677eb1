"""The Available Control Authority Index (Du, Quan, Yang, Cai, JGCD 2015, Theorem 3).

The ACAI is the radius of the largest ball centred at the hover wrench G = [m g, 0, 0, 0] inside
the attainable set of thrust and torques (Du eq. (9)). Units: it mixes N (thrust axis) and N m
(torque axes), exactly as in the paper.

Two formulas, named everywhere the number is printed (tables, CLI, reports, scan columns):

- ``"eq13"`` (the default, Du's eq. (13)): the paper's number. Where G lies outside the
  attainable set it is not the distance of its own definition (9): Du Table III prints 0 for the
  PPNNPN hexacopter with rotor 5 failed, where hover is infeasible. Such a value carries
  ``hover == "outside"`` and prints with a star (``0.0000*``).
- ``"facet-margin"``: minus the largest violation of a facet inequality, a lower bound on the
  distance that is continuous and non-decreasing in every efficiency (negative outside).

Both agree whenever G is inside or on the boundary, and verdicts never depend on the choice
(details: ``crates/rfcore/src/analysis/acai.rs``). ``give_up_yaw=True`` asks the same question
for thrust, roll and pitch only (n = 3).
"""

from __future__ import annotations

import math
from typing import Any, Literal, cast, get_args, overload

import numpy as np
import numpy.typing as npt

from .. import _rfcore
from .._util.core_result import CoreResult
from .._util.deprecation import dataclass_compat
from .._util.convert import FloatArray, control_axes, flag, float_array, real
from .._util.tables import Column, Tabular
from .._typing import AcaiFormula, ControlAxes, HoverPoint
from .airframe import Airframe, require_airframe


#: Tolerances of the core (see ``crates/rfcore/src/analysis/acai.rs``): rank decisions are relative to
#: column norms, and an ACAI within ZERO_RTOL x (problem size) of zero is returned as exactly 0.0.
RANK_RTOL: float = _rfcore.RANK_RTOL
ZERO_RTOL: float = _rfcore.ZERO_RTOL
#: The two ACAI formulas, by name (module docs).
ACAI_FORMULAS: tuple[AcaiFormula, ...] = get_args(AcaiFormula)
#: What each formula is, in words (help texts, notes).
FORMULA_DESCRIPTIONS: dict[AcaiFormula, str] = {
    "eq13": "Du's eq. (13), the paper's number (0 where hover is infeasible but the formula reads 0)",
    "facet-margin": "the facet margin, minus the largest violation of a facet inequality (negative where hover is infeasible)",
}
#: The one name of asking the question for thrust, roll and pitch only (``give_up_yaw=True``,
#: ``--give-up-yaw``, the ``_give_up_yaw`` columns and fields): table headers use it as written.
GIVE_UP_YAW = "give-up-yaw"


def acai_label(formula: str) -> str:
    """How a printed ACAI names its formula: ``"ACAI eq13"``, ``"ACAI facet-margin"`` (table
    headers, CLI rows, report captions: one name per formula, the option's own).

    Examples:

        >>> from rotorfault.analysis import acai_label
        >>> acai_label("eq13"), acai_label("facet-margin")
        ('ACAI eq13', 'ACAI facet-margin')
    """
    if formula not in ACAI_FORMULAS:
        raise ValueError(f"formula: must be one of {', '.join(ACAI_FORMULAS)}, got {formula!r}")
    return _rfcore.acai_label(formula)


def _formula(value: Any) -> str:
    if not isinstance(value, str):
        raise TypeError(f"formula: expected 'eq13' or 'facet-margin', got {type(value).__name__}")
    return value


#: ``HoverPoint`` of each code in :attr:`AcaiBatch.hover_code` (the core's compact column).
HOVER_CODES: dict[int, HoverPoint] = {1: "inside", 0: "boundary", -1: "outside", -2: "rank-deficient"}


class AcaiValue(float):
    """An ACAI: a float (N / N m, as in the paper) that also says where the hover wrench lies.

    ``hover`` is ``"inside"``, ``"boundary"``, ``"outside"`` or ``"rank-deficient"``. With
    ``formula="eq13"`` a value of ``0.0`` can come with ``hover == "outside"`` (Du Table III's
    PPNNPN with rotor 5 failed): hover is infeasible although the number reads like a boundary.
    Such a value prints with a star (``0.0*``). The float holds the core's result as it is
    (``_rfcore.AcaiResult``, validated by the core) and reads ``hover`` through it: no copied
    fields.

    Examples:

        >>> import rotorfault as rf
        >>> value = rf.acai(rf.Airframe.preset("quad-x"), [0, 1, 1, 1])
        >>> value.hover, float(value) < 0
        ('rank-deficient', True)
    """

    __slots__ = ("_core", "__weakref__")  # weak references kept working (the float had them before the slot)
    _core: _rfcore.AcaiResult

    def __new__(cls, value: float, hover: HoverPoint) -> AcaiValue:
        if not isinstance(hover, str):
            raise TypeError(f"hover: expected a str, got {type(hover).__name__}")
        obj = super().__new__(cls, value)
        obj._core = _rfcore.AcaiResult(float(obj), hover)
        return obj

    @property
    def hover(self) -> HoverPoint:
        """Where the hover wrench lies: ``"inside"``, ``"boundary"``, ``"outside"`` or
        ``"rank-deficient"``."""
        return cast(HoverPoint, self._core.hover)

    @property
    def hover_feasible(self) -> bool:
        """The hover wrench is attainable (inside or on the boundary)."""
        return self._core.hover_feasible

    def __repr__(self) -> str:
        text = float.__repr__(self)
        return text + "*" if self._core.hover == "outside" and self >= 0.0 else text

    __str__ = __repr__

    def __reduce__(self) -> tuple[type[AcaiValue], tuple[float, HoverPoint]]:
        # The two fields, as every release has pickled them (old pickles load, new ones load in old releases).
        return (AcaiValue, (float(self), self.hover))

    @classmethod
    def _from_core(cls, core: _rfcore.AcaiResult) -> AcaiValue:
        obj = super().__new__(cls, core.acai)
        obj._core = core
        return obj


class AcaiBatch(CoreResult, Tabular):
    """:func:`acai_batch` with ``with_hover=True``: the ACAIs and where the hover wrench lies for
    each row, as codes (:data:`HOVER_CODES`: 1 inside, 0 boundary, -1 outside, -2 rank deficient).
    ``to_arrow()`` / ``to_pandas()``: one row per efficiency vector (``acai_<formula>``,
    ``hover_code``), in the order given.

    It holds the core's batch (``_rfcore.AcaiBatch``) and reads every field through it (no
    copied fields); ``AcaiBatch(acai, hover_code, formula)`` makes one from its fields, checked
    by the core (one code per value, each a code of :data:`HOVER_CODES`, a known formula).

    Examples:

        >>> import rotorfault as rf
        >>> hexa = rf.Airframe.preset("hexa-ppnnpn")
        >>> batch = rf.acai_batch(hexa, [[1, 1, 1, 1, 1, 1], [0, 0, 1, 1, 1, 1]], with_hover=True)
        >>> batch.acai.round(4).tolist(), batch.hover_code.tolist()
        ([1.1295, -0.2779], [1, -1])
    """

    __slots__ = ()
    FIELDS = ("acai", "hover_code", "formula")
    _core: _rfcore.AcaiBatch

    def __init__(self, acai: npt.ArrayLike, hover_code: npt.ArrayLike, formula: AcaiFormula = "eq13") -> None:
        self._core = _rfcore.AcaiBatch(float_array("acai", acai, 1), _hover_codes(hover_code), _formula(formula))

    @property
    def acai(self) -> FloatArray:
        """The ACAI of each row, in :attr:`formula` (N / N m)."""
        return self._core.acai

    @property
    def hover_code(self) -> npt.NDArray[np.int8]:
        """Where the hover wrench lies for each row (:data:`HOVER_CODES`)."""
        return self._core.hover_code

    @property
    def formula(self) -> AcaiFormula:
        """The formula of every value: ``"eq13"`` or ``"facet-margin"``."""
        return cast(AcaiFormula, self._core.formula)

    def _table_columns(self) -> list[Column]:
        return [(f"acai_{self.formula.replace('-', '_')}", "float64", self.acai), ("hover_code", "int8", self.hover_code)]

    @property
    def hover_feasible(self) -> npt.NDArray[np.bool_]:
        return self.hover_code >= 0

    def __reduce__(self) -> tuple[type[AcaiBatch], tuple[FloatArray, npt.NDArray[np.int8], str]]:
        return (AcaiBatch, (self.acai, self.hover_code, self.formula))

    def __setstate__(self, state: dict[str, Any]) -> None:
        # A pickle of the dataclass this class was (its fields as a dict) loads into the core's batch.
        self._core = _rfcore.AcaiBatch(state["acai"], state["hover_code"], state.get("formula", "eq13"))


dataclass_compat(AcaiBatch)


def _hover_codes(value: Any) -> Any:
    """Types and shape here (integers, one dimension); the codes' values are the core's check."""
    codes = np.asarray(value)
    if codes.ndim != 1 or not (codes.size == 0 or np.issubdtype(codes.dtype, np.integer)):
        raise TypeError(f"hover_code: expected a 1-D array of integer codes, got dtype {codes.dtype} with {codes.ndim} dimensions")
    return codes if codes.dtype == np.int8 else codes.astype(np.int64).tolist()


def _efficiency(airframe: Airframe, efficiency: npt.ArrayLike | None) -> FloatArray:
    return airframe.efficiency if efficiency is None else float_array("efficiency", efficiency, 1)


def acai(
    airframe: Airframe,
    efficiency: npt.ArrayLike | None = None,
    *,
    give_up_yaw: bool = False,
    formula: AcaiFormula = "eq13",
    axes: ControlAxes | None = None,
) -> AcaiValue:
    """ACAI of ``airframe`` with rotor ``efficiency`` (Du's eta_i; default: the airframe's own), in
    N / N m like the paper, as an :class:`AcaiValue` (a float with ``.hover``).

    Positive: the distance from G to the boundary of the attainable set. ``0.0``: G on the
    boundary (within ``ZERO_RTOL``) or, with ``formula="eq13"``, a degenerate outside case
    (``.hover == "outside"``, printed ``0.0*``). Negative: G outside. ``-inf``: rank B_f < n, the
    index is undefined.

    Examples:

        >>> import rotorfault as rf
        >>> hexa = rf.Airframe.preset("hexa-ppnnpn")
        >>> round(rf.acai(hexa), 4), rf.acai(hexa).hover
        (1.1295, 'inside')
        >>> round(rf.acai(hexa, [0, 1, 1, 1, 1, 1]), 4)
        0.7221
    """
    airframe = require_airframe(airframe)
    eff = _efficiency(airframe, efficiency)
    names = control_axes(give_up_yaw, axes)
    return AcaiValue._from_core(_rfcore.acai(airframe._core, eff, names, _formula(formula)))


@overload
def acai_batch(
    airframe: Airframe,
    efficiencies: npt.ArrayLike,
    *,
    give_up_yaw: bool = ...,
    formula: AcaiFormula = ...,
    axes: ControlAxes | None = ...,
    with_hover: Literal[False] = ...,
) -> FloatArray: ...
@overload
def acai_batch(
    airframe: Airframe,
    efficiencies: npt.ArrayLike,
    *,
    give_up_yaw: bool = ...,
    formula: AcaiFormula = ...,
    axes: ControlAxes | None = ...,
    with_hover: Literal[True],
) -> AcaiBatch: ...
def acai_batch(
    airframe: Airframe,
    efficiencies: npt.ArrayLike,
    *,
    give_up_yaw: bool = False,
    formula: AcaiFormula = "eq13",
    with_hover: bool = False,
    axes: ControlAxes | None = None,
) -> FloatArray | AcaiBatch:
    """ACAI for every row of ``efficiencies`` (N x m), computed in parallel without the GIL: the
    bare values, or with ``with_hover=True`` an :class:`AcaiBatch` that also says where the hover
    wrench lies for each row (needed to tell eq. (13)'s outside zeros from boundaries).

    A float64 C-contiguous ``efficiencies`` is read in place (no copy) while other Python threads run:
    do not modify it from another thread during the call.

    Examples:

        >>> import rotorfault as rf
        >>> hexa = rf.Airframe.preset("hexa-ppnnpn")
        >>> rf.acai_batch(hexa, [[1, 1, 1, 1, 1, 1], [0, 1, 1, 1, 1, 1]]).round(4).tolist()
        [1.1295, 0.7221]
    """
    airframe = require_airframe(airframe)
    rows = float_array("efficiencies", efficiencies, 2)
    names = control_axes(give_up_yaw, axes)
    if flag("with_hover", with_hover):
        core = _rfcore.acai_batch_with_hover(airframe._core, rows, names, _formula(formula))
        out: AcaiBatch = AcaiBatch._from_core(core)
        return out
    return _rfcore.acai_batch(airframe._core, rows, names, _formula(formula))


def acai_from_matrix(
    effectiveness_matrix: npt.ArrayLike,
    f_min: npt.ArrayLike,
    f_max: npt.ArrayLike,
    g_vec: npt.ArrayLike,
    *,
    formula: AcaiFormula = "eq13",
) -> AcaiValue:
    """ACAI of any effectiveness matrix B (n x m, efficiencies applied), actuator box
    ``[f_min, f_max]`` (length m) and required wrench ``g_vec`` (length n), for any n >= 1, with
    where ``g_vec`` lies (``.hover``). Facets and rank are decided free of the rows' units.

    Examples:

        >>> import rotorfault as rf
        >>> quad = rf.Airframe.preset("quad-x")
        >>> value = rf.acai_from_matrix(quad.effectiveness_matrix(), quad.min_thrust_n, quad.max_thrust_n,
        ...                             [quad.mass_kg * quad.gravity_m_s2, 0, 0, 0])
        >>> round(value, 4) == round(rf.acai(quad), 4)
        True
    """
    core = _rfcore.acai_from_matrix(
        float_array("effectiveness_matrix", effectiveness_matrix, 2),
        float_array("f_min", f_min, 1),
        float_array("f_max", f_max, 1),
        float_array("g_vec", g_vec, 1),
        _formula(formula),
    )
    return AcaiValue._from_core(core)


#: How each position of the hover wrench reads in a table (failure tables, certificates, the
#: report): "boundary" (an ACAI of exactly 0: only a zero-margin static hover, or a spinning one)
#: apart from "outside" (hover infeasible, with its distance when known).
HOVER_WORDS: dict[str, str] = {"inside": "inside", "boundary": "boundary", "outside": "outside",
                               "rank-deficient": "rank-deficient"}
#: The footnote of every table with a hover wrench column.
HOVER_WRENCH_NOTE = (
    "hover wrench: inside; boundary (ACAI exactly 0: a static hover without any margin, or spinning); "
    "outside d (no static hover: d is its distance to the attainable set, N / N m); rank-deficient (rank B_f < n)"
)


def hover_wrench_text(hover: HoverPoint, distance: float | None = None) -> str:
    """Where the hover wrench lies, for a table cell (:data:`HOVER_WRENCH_NOTE`): ``"inside"``,
    ``"boundary"``, ``"outside 0.2133"`` (``distance``: from the hover wrench to the attainable
    set, in the ACAI's units, :func:`rotorfault.allocation.hover_wrench_distance`; a rank-deficient
    case whose wrench is not attained reads the same), ``"rank-deficient"``.

    Examples:

        >>> from rotorfault.analysis import hover_wrench_text
        >>> hover_wrench_text("inside"), hover_wrench_text("outside", 0.8123)
        ('inside', 'outside 0.8123')
    """
    if not isinstance(hover, str) or hover not in HOVER_WORDS:
        raise ValueError(f"hover: must be one of {', '.join(HOVER_WORDS)}, got {hover!r}")
    if distance is not None:
        distance = real("distance", distance)
        if not (math.isfinite(distance) and distance >= 0.0):
            raise ValueError(f"distance: must be finite and >= 0 (N / N m), got {distance}")
    if hover in ("outside", "rank-deficient") and distance is not None and distance > 0.0:
        return f"outside {distance:.4f}"
    return HOVER_WORDS[hover]


#: Footnote for an eq. (13) value of 0 whose hover wrench is in fact outside.
EQ13_ZERO_NOTE = "* eq. (13) prints 0 here although hover is infeasible (--formula facet-margin shows the gap)"


def format_acai(value: float, hover: HoverPoint = "inside") -> str:
    """4 decimals like the paper; "undefined" for -inf; a star where the number reads as
    non-negative (eq. (13)'s 0) but the hover wrench lies outside the attainable set.

    Examples:

        >>> from rotorfault.analysis import format_acai
        >>> format_acai(1.129472), format_acai(0.0, "boundary")
        ('1.1295', '0.0000')
    """
    value = real("value", value)
    if not isinstance(hover, str):
        raise TypeError(f"hover: expected a str, got {type(hover).__name__}")
    # The core's formatting: the one every printed ACAI uses (tables, the report, str(report)).
    return _rfcore.format_acai(value, hover)


__all__ = [
    "ACAI_FORMULAS",
    "EQ13_ZERO_NOTE",
    "FORMULA_DESCRIPTIONS",
    "GIVE_UP_YAW",
    "HOVER_CODES",
    "HOVER_WORDS",
    "HOVER_WRENCH_NOTE",
    "RANK_RTOL",
    "ZERO_RTOL",
    "AcaiBatch",
    "AcaiValue",
    "acai",
    "hover_wrench_text",
    "acai_batch",
    "acai_from_matrix",
    "acai_label",
    "format_acai",
]

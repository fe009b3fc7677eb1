"""Controllability under rotor degradation and failure (Du, Quan, Yang, Cai, JGCD 2015): the
9-step test of Section IV.B (:func:`controllability`) and every combination of failed rotors
(:func:`failure_table`).

The vehicle is controllable about hover iff rank C(A, B) is full and the ACAI
(:mod:`~rotorfault.analysis.acai`) is positive (Theorem 2). ``give_up_yaw=True`` asks the same
question for thrust, roll and pitch only (n = 3): can the vehicle hover if it gives up yaw and
spins, as the controllers of Lanzon et al. and Ke et al. do?
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping, Sequence
from typing import Any, cast, overload

import numpy as np
import numpy.typing as npt

from .. import _rfcore
from .._typing import AcaiFormula, ControlAxes, HoverPoint
from .._util.convert import control_axes, count
from .._util.core_result import CoreResult
from .._util.deprecation import dataclass_compat, renamed_attribute
from .._util.tables import Column, Tabular
from .acai import EQ13_ZERO_NOTE, GIVE_UP_YAW, HOVER_WRENCH_NOTE, _efficiency, _formula, acai_label, format_acai, hover_wrench_text
from .airframe import Airframe, require_airframe, rotor_labels


#: Outcome of Du's 9-step test for one airframe and efficiency vector: the core's report, used
#: directly (issue 26: no field-by-field copy). It carries the question asked (``airframe``,
#: ``efficiency``, ``axes``, ``give_up_yaw``) and the core's answer (ranks, ``acai``,
#: ``formula``, ``verdict``, ``controllable``, ``hover``); it prints with the ACAI formatting every
#: table and command uses (:func:`format_acai`, :func:`acai_label`, one implementation in the
#: core). Frozen, comparable, hashable, picklable.
ControllabilityReport = _rfcore.ControllabilityReport


def controllability(
    airframe: Airframe,
    efficiency: npt.ArrayLike | None = None,
    *,
    give_up_yaw: bool = False,
    formula: AcaiFormula = "eq13",
    axes: ControlAxes | None = None,
) -> ControllabilityReport:
    """Runs Du's Section IV.B procedure for ``airframe`` with rotor ``efficiency`` (default: the
    airframe's own).

    Examples:

        >>> import rotorfault as rf
        >>> report = rf.controllability(rf.Airframe.preset("hexa-ppnnpn"), [0, 1, 1, 1, 1, 1])
        >>> report.controllable, report.verdict, round(report.acai, 4)
        (True, 'controllable', 0.7221)
    """
    airframe = require_airframe(airframe)
    eff = _efficiency(airframe, efficiency)
    names = control_axes(give_up_yaw, axes)
    return _rfcore.controllability(airframe._core, eff, names, _formula(formula))


class FailureCase(CoreResult):
    """One row of a failure table: rotors (numbered from 1) at efficiency 0 and the verdicts
    with all four axes and giving up yaw (``..._give_up_yaw``: thrust, roll and pitch only).

    It holds the core's row (``_rfcore.FailureCase``: the failed rotors and the core's
    :class:`ControllabilityReport` for all axes, giving up yaw and, for fully actuated airframes,
    the full wrench) and reads every field through it (issue 26: no copied fields). Frozen,
    comparable, hashable, picklable; made by :func:`failure_table`.

    Examples:

        >>> import rotorfault as rf
        >>> case = rf.failure_table(rf.Airframe.preset("hexa-pnpnpn"), max_failed=1)[1]
        >>> case.failed, case.controllable, case.controllable_give_up_yaw, round(case.acai_give_up_yaw, 4)
        ((1,), False, True, 1.2882)
    """

    __slots__ = ()
    FIELDS = (
        "failed", "controllability_rank", "effectiveness_rank", "acai", "controllable", "verdict",
        "effectiveness_rank_give_up_yaw", "acai_give_up_yaw", "controllable_give_up_yaw", "verdict_give_up_yaw",
        "hover", "hover_give_up_yaw", "acai_wrench", "controllable_wrench", "hover_wrench",
    )
    _core: _rfcore.FailureCase

    def __init__(self) -> None:
        raise TypeError("FailureCase: made by failure_table(), not constructed")

    @property
    def failed(self) -> tuple[int, ...]:
        """The failed rotors (efficiency 0), numbered from 1."""
        return self._core.failed

    @property
    def controllability_rank(self) -> int:
        """rank C(A, B) with all four axes (of 8)."""
        return self._core.all_axes.controllability_rank

    @property
    def effectiveness_rank(self) -> int:
        """rank B_f with all four axes (of 4)."""
        return self._core.all_axes.effectiveness_rank

    @property
    def acai(self) -> float:
        """The ACAI with all four axes (N / N m; the table's formula)."""
        return self._core.all_axes.acai

    @property
    def controllable(self) -> bool:
        """Controllable with all four axes."""
        return self._core.all_axes.controllable

    @property
    def verdict(self) -> str:
        """``"controllable"`` or ``"uncontrollable: <reason>"`` with all four axes."""
        return self._core.all_axes.verdict

    @property
    def effectiveness_rank_give_up_yaw(self) -> int:
        """rank B_f giving up yaw (of 3)."""
        return self._core.give_up_yaw.effectiveness_rank

    @property
    def acai_give_up_yaw(self) -> float:
        """The ACAI giving up yaw (N / N m; the table's formula)."""
        return self._core.give_up_yaw.acai

    @property
    def controllable_give_up_yaw(self) -> bool:
        """Controllable giving up yaw (thrust, roll and pitch only)."""
        return self._core.give_up_yaw.controllable

    @property
    def verdict_give_up_yaw(self) -> str:
        """The verdict giving up yaw."""
        return self._core.give_up_yaw.verdict

    @property
    def hover(self) -> HoverPoint:
        """Where the hover wrench lies with all four axes (see :class:`AcaiValue`)."""
        return self._core.all_axes.hover

    @property
    def hover_give_up_yaw(self) -> HoverPoint:
        """Where the hover wrench lies giving up yaw."""
        return self._core.give_up_yaw.hover

    @property
    def acai_wrench(self) -> float | None:
        """The full-wrench (n = 6) ACAI, for fully actuated airframes only (else None)."""
        wrench = self._core.wrench
        return None if wrench is None else wrench.acai

    @property
    def controllable_wrench(self) -> bool | None:
        """Controllable in the full wrench (n = 6), for fully actuated airframes only (else None)."""
        wrench = self._core.wrench
        return None if wrench is None else wrench.controllable

    @property
    def hover_wrench(self) -> HoverPoint | None:
        """Where the hover wrench lies in the full wrench (n = 6), fully actuated airframes only (else None)."""
        wrench = self._core.wrench
        return None if wrench is None else wrench.hover

    def __reduce__(self) -> tuple[Any, tuple[_rfcore.FailureCase]]:
        return (FailureCase._from_core, (self._core,))

    def __setstate__(self, state: Any) -> None:
        # A row pickled as the dataclass it was (before issue 26) lacks what its reports hold
        # (the airframe, the efficiencies): refused rather than rebuilt with guesses.
        raise TypeError("FailureCase: a row pickled before rotorfault made rows from the core's reports "
                        "cannot be read; make it again with failure_table()")

    # The names before issue 26 (one name per concept: "give up yaw"), for one release.
    effectiveness_rank_without_yaw = renamed_attribute("effectiveness_rank_without_yaw", "effectiveness_rank_give_up_yaw")
    acai_without_yaw = renamed_attribute("acai_without_yaw", "acai_give_up_yaw")
    controllable_without_yaw = renamed_attribute("controllable_without_yaw", "controllable_give_up_yaw")
    verdict_without_yaw = renamed_attribute("verdict_without_yaw", "verdict_give_up_yaw")
    hover_without_yaw = renamed_attribute("hover_without_yaw", "hover_give_up_yaw")


dataclass_compat(FailureCase)


_COLUMNS = (
    "controllability_rank",
    "effectiveness_rank",
    "acai",
    "controllable",
    "effectiveness_rank_give_up_yaw",
    "acai_give_up_yaw",
    "controllable_give_up_yaw",
    "hover",
    "hover_give_up_yaw",
)


class FailureTable(Sequence[FailureCase], Tabular):
    """Every combination of up to ``max_failed`` failed rotors with rank, ACAI (``formula``) and
    verdict, with all axes and giving up yaw. Prints as a table; converts with :meth:`to_arrow`
    and :meth:`to_pandas` (one row per failure combination), :meth:`to_dicts` and
    :meth:`to_arrays`.

    Examples:

        >>> import rotorfault as rf
        >>> table = rf.failure_table(rf.Airframe.preset("hexa-pnpnpn"), max_failed=2)
        >>> len(table), table.to_arrow().column_names[:3]
        (22, ['failed_rotors', 'failed_count', 'controllability_rank'])
    """

    def __init__(self, airframe: Airframe, max_failed: int, cases: Sequence[FailureCase], *, formula: AcaiFormula = "eq13") -> None:
        self.formula: AcaiFormula = formula
        self.airframe_name = airframe.name
        self.rotor_count = airframe.rotor_count
        self.max_failed = max_failed
        self._cases = tuple(cases)

    @overload
    def __getitem__(self, index: int) -> FailureCase: ...
    @overload
    def __getitem__(self, index: slice) -> Sequence[FailureCase]: ...
    def __getitem__(self, index: int | slice) -> FailureCase | Sequence[FailureCase]:
        return self._cases[index]

    def __len__(self) -> int:
        return len(self._cases)

    def __iter__(self) -> Iterator[FailureCase]:
        return iter(self._cases)

    def case(self, *failed: int) -> FailureCase:
        """The row for exactly these failed rotors (1-based, any order)."""
        key = tuple(sorted(failed))
        for row in self._cases:
            if row.failed == key:
                return row
        raise KeyError(f"no row for failed rotors {key} (max_failed={self.max_failed})")

    def to_dicts(self) -> list[dict[str, Any]]:
        """One dict per row: every field of :class:`FailureCase`, in its order."""
        return [row._as_dict() for row in self._cases]

    def to_arrays(self) -> dict[str, npt.NDArray[Any]]:
        """Columns as numpy arrays; ``failed_mask`` is N x m (True where a rotor failed)."""
        mask = np.zeros((len(self), self.rotor_count), dtype=bool)
        for i, row in enumerate(self._cases):
            mask[i, [r - 1 for r in row.failed]] = True
        arrays: dict[str, npt.NDArray[Any]] = {"failed_mask": mask, "n_failed": mask.sum(axis=1)}
        for column in _COLUMNS:
            arrays[column] = np.array([getattr(row, column) for row in self._cases])
        return arrays

    def _table_columns(self) -> list[Column]:
        # The ACAI columns are named as a scan's (acai_eq13, acai_facet_margin_give_up_yaw, ...).
        acai_ = f"acai_{self.formula.replace('-', '_')}"
        rows = self._cases
        columns: list[Column] = [
            ("failed_rotors", "list<int64>", [list(r.failed) for r in rows]),
            ("failed_count", "int64", [len(r.failed) for r in rows]),
            ("controllability_rank", "int64", [r.controllability_rank for r in rows]),
            ("effectiveness_rank", "int64", [r.effectiveness_rank for r in rows]),
            (acai_, "float64", [r.acai for r in rows]),
            ("hover", "string", [r.hover for r in rows]),
            ("controllable", "bool", [r.controllable for r in rows]),
            ("verdict", "string", [r.verdict for r in rows]),
            ("effectiveness_rank_give_up_yaw", "int64", [r.effectiveness_rank_give_up_yaw for r in rows]),
            (f"{acai_}_give_up_yaw", "float64", [r.acai_give_up_yaw for r in rows]),
            ("hover_give_up_yaw", "string", [r.hover_give_up_yaw for r in rows]),
            ("controllable_give_up_yaw", "bool", [r.controllable_give_up_yaw for r in rows]),
            ("verdict_give_up_yaw", "string", [r.verdict_give_up_yaw for r in rows]),
        ]
        if rows and rows[0].acai_wrench is not None:
            columns += [
                (f"{acai_}_wrench", "float64", [r.acai_wrench for r in rows]),
                ("hover_wrench", "string", [r.hover_wrench for r in rows]),
                ("controllable_wrench", "bool", [r.controllable_wrench for r in rows]),
            ]
        return columns

    def _table_title(self) -> str:
        return f"{self.airframe_name}: up to {self.max_failed} failed rotor(s), {acai_label(self.formula)}"

    def _table_metadata(self) -> dict[str, Any]:
        return {"kind": "failure-table", "airframe": self.airframe_name, "max_failed": self.max_failed, "formula": self.formula}

    def rows_for_display(
        self, distances: Mapping[tuple[int, ...], tuple[float, float]] | None = None,
    ) -> tuple[list[str], list[list[str]]]:
        """Headers and formatted cells; the ACAI columns name their formula, the "give-up-yaw"
        columns keep only thrust, roll and pitch; the "hover wrench" columns say where it lies
        (inside, on the boundary, outside, rank deficient: :func:`~rotorfault.analysis.acai.hover_wrench_text`),
        with the distance of an outside one when ``distances`` gives it (failed rotors -> (all
        axes, giving up yaw), :func:`rotorfault.allocation.hover_distances`)."""
        acai_ = acai_label(self.formula)
        headers = ["failed", "rank C", "rank B_f", acai_, "hover wrench", "ok", f"{acai_} {GIVE_UP_YAW}",
                   f"hover wrench {GIVE_UP_YAW}", f"ok {GIVE_UP_YAW}"]
        given = {} if distances is None else dict(distances)
        rows = [
            [
                rotor_labels(row.failed),
                str(row.controllability_rank),
                str(row.effectiveness_rank),
                format_acai(row.acai, row.hover),
                hover_wrench_text(row.hover, given.get(row.failed, (None, None))[0]),
                "yes" if row.controllable else "no",
                format_acai(row.acai_give_up_yaw, row.hover_give_up_yaw),
                hover_wrench_text(row.hover_give_up_yaw, given.get(row.failed, (None, None))[1]),
                "yes" if row.controllable_give_up_yaw else "no",
            ]
            for row in self._cases
        ]
        if self._cases and self._cases[0].acai_wrench is not None:
            headers += [f"{acai_} 6-D", "ok 6-D"]
            for cells, row in zip(rows, self._cases):
                cells += [
                    format_acai(float(row.acai_wrench or 0.0), row.hover_wrench or "inside"),
                    "yes" if row.controllable_wrench else "no",
                ]
        return headers, rows

    def __str__(self) -> str:
        headers, rows = self.rows_for_display()
        widths = [max(len(h), *(len(r[i]) for r in rows)) for i, h in enumerate(headers)]
        lines = [
            f"{self.airframe_name}: up to {self.max_failed} failed rotor(s)",
            "  ".join(h.ljust(w) for h, w in zip(headers, widths)),
            "  ".join("-" * w for w in widths),
        ]
        lines += ["  ".join(c.ljust(w) for c, w in zip(row, widths)) for row in rows]
        if any(cell.endswith("*") for row in rows for cell in row):
            lines.append(EQ13_ZERO_NOTE)
        lines.append(HOVER_WRENCH_NOTE)
        return "\n".join(lines)

    def __repr__(self) -> str:
        return f"<FailureTable {self.airframe_name}: {len(self)} cases, max_failed={self.max_failed}>"


def failure_table(
    airframe: Airframe, *, max_failed: int = 1, formula: AcaiFormula = "eq13"
) -> FailureTable:
    """Every combination of up to ``max_failed`` fully failed rotors (the other rotors keep the
    airframe's efficiencies), ordered by number failed, then lexicographically.

    Examples:

        >>> import rotorfault as rf
        >>> table = rf.failure_table(rf.Airframe.preset("quad-x"), max_failed=1)
        >>> [(case.failed, case.controllable, case.controllable_give_up_yaw) for case in table]
        [((), True, True), ((1,), False, False), ((2,), False, False), ((3,), False, False), ((4,), False, False)]
    """
    airframe = require_airframe(airframe)
    max_failed = count("max_failed", max_failed)
    formula_name = _formula(formula)
    cases = [FailureCase._from_core(case) for case in _rfcore.failure_table(airframe._core, max_failed, formula_name)]
    return FailureTable(airframe, max_failed, cases, formula=cast(AcaiFormula, formula_name))



__all__ = [
    "ControllabilityReport",
    "FailureCase",
    "FailureTable",
    "controllability",
    "failure_table",
]

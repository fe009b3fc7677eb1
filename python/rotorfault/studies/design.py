"""Design search: which spin-direction assignment of an m-rotor frame tolerates rotor failures best?

Every assignment of spin directions to the frame's rotors is evaluated (on a regular frame, one per
class under rotation, mirror and reversing every spin, which leave every failure set's ACAI
unchanged), by the ACAI after every single and double failure, with yaw and giving up yaw
(Du et al., JGCD 2015, Section V: PNPNPN has ACAI 0 after any single failure, PPNNPN stays
controllable after the failure of rotor 1, 2, 3 or 4).

Spins are written as a string, rotor 1 first: ``P`` turns like rotor 1 of Du's presets (clockwise
seen from above, ``w = -1``), ``N`` the other way.

Ranking (decided here, see the README's decisions table): the worst case over failures alone ties
most hexacopters at 0 (eq. (13)) and ranks a design that survives four of six failures below one
that survives none (the facet margin), so designs are ranked by, in order: the number of single
failures that stay controllable with yaw, the worst-case single-failure ACAI with yaw, the same
two for double failures, then the same four giving up yaw, then the no-failure ACAI. All numbers
are reported, so any other order can be read off the table.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from .._typing import AcaiFormula
from .._util.convert import float_array
from .._util.tables import Column, Tabular
from ..analysis.acai import acai
from ..analysis.airframe import Airframe, require_airframe
from ..analysis.controllability import failure_table
from .scan import _axis_name, _variant


def _orbit(spins: str) -> set[str]:
    flip = str.maketrans("PN", "NP")
    m = len(spins)
    out = set()
    for s in (spins, spins.translate(flip)):
        for t in (s, s[0] + s[:0:-1]):  # mirror about rotor 1's arm
            for k in range(m):
                out.add(t[k:] + t[:k])
    return out


def spin_assignments(rotor_count: int, *, symmetric: bool = True) -> list[str]:
    """Every spin assignment of ``rotor_count`` rotors (``"P"``/``"N"`` strings, rotor 1 first),
    one per symmetry class when ``symmetric`` (a regular frame), sorted."""
    if isinstance(rotor_count, bool) or not isinstance(rotor_count, int):
        raise TypeError(f"rotor_count: expected an integer, got {type(rotor_count).__name__}")
    if not 3 <= rotor_count <= 12:
        raise ValueError(f"rotor_count: must lie in 3..12, got {rotor_count}")
    every = ["".join("N" if (bits >> (rotor_count - 1 - i)) & 1 else "P" for i in range(rotor_count)) for bits in range(2**rotor_count)]
    if not symmetric:
        return every
    seen: set[str] = set()
    classes = []
    for s in every:
        if s in seen:
            continue
        orbit = _orbit(s)
        seen |= orbit
        classes.append(max(orbit))  # P first: Du writes PNPNPN
    return sorted(classes, reverse=True)


def is_regular(airframe: Airframe) -> bool:
    """Rotors upright, equally spaced round the centre at one height, with equal arms, thrust
    bounds and k_mu (the symmetries the search uses hold)."""
    m = airframe.rotor_count
    angles = np.sort(np.mod(airframe.arm_angle_rad - airframe.arm_angle_rad[0], 2 * np.pi))
    spaced = np.allclose(angles, np.arange(m) * 2 * np.pi / m, rtol=0.0, atol=1e-9)
    same = all(
        np.ptp(v) <= 1e-12 * max(1.0, float(np.max(np.abs(v))))
        for v in (airframe.arm_length_m, airframe.max_thrust_n, airframe.min_thrust_n, airframe.efficiency,
                  airframe.rotor_drag_torque_ratio_m, airframe.position_m[:, 2])
    )
    # Tilted rotors break the mirror symmetry the classes rely on: every assignment is then ranked.
    upright = bool(np.all(airframe.thrust_axis == np.array([0.0, 0.0, -1.0])))
    ordered = bool(np.all(np.diff(np.mod(airframe.arm_angle_rad - airframe.arm_angle_rad[0], 2 * np.pi)) > 0))
    return bool(spaced and same and ordered and upright)


def with_spins(airframe: Airframe, spins: str) -> Airframe:
    """``airframe`` with spin directions ``spins`` (``P``: clockwise from above, ``N``: anticlockwise)."""
    if not isinstance(spins, str):
        raise TypeError(f"spins: expected a string of P and N, got {type(spins).__name__}")
    if len(spins) != airframe.rotor_count or set(spins) - {"P", "N"}:
        raise ValueError(f"spins: expected {airframe.rotor_count} letters P or N, got {spins!r}")
    signs = np.array([-1.0 if c == "P" else 1.0 for c in spins])
    # Only the spins change: 3-D positions, tilted axes, each rotor's k_mu and the bounds are kept.
    return airframe.with_parameters(spin=signs, name=f"{airframe.name} {spins}")


@dataclass(frozen=True)
class Design:
    """One spin assignment and its ACAIs after failures (``formula``).

    Examples:

        >>> import rotorfault as rf
        >>> best = rf.design_search(rf.Airframe.preset("hexa-ppnnpn")).best()
        >>> best.spins, best.controllable_single, round(best.worst_single, 4)
        ('PPNPNN', 4, -0.2133)
    """

    spins: str
    #: The parameter axis value (None without one).
    parameter_value: float | None
    nominal: float
    #: ACAI after the failure of rotor 1, 2, ... (with yaw / giving up yaw).
    single: tuple[float, ...]
    single_give_up_yaw: tuple[float, ...]
    controllable_single: int
    worst_single: float
    controllable_double: int
    worst_double: float
    controllable_single_give_up_yaw: int
    worst_single_give_up_yaw: float
    controllable_double_give_up_yaw: int
    worst_double_give_up_yaw: float

    @property
    def survivable_single(self) -> tuple[int, ...]:
        """Rotors (1-based) whose failure leaves the vehicle controllable with yaw."""
        return tuple(i + 1 for i, ok in enumerate(self._single_ok) if ok)

    _single_ok: tuple[bool, ...] = ()

    def rank_key(self) -> tuple[float, ...]:
        return (
            self.controllable_single, self.worst_single, self.controllable_double, self.worst_double,
            self.controllable_single_give_up_yaw, self.worst_single_give_up_yaw,
            self.controllable_double_give_up_yaw, self.worst_double_give_up_yaw, self.nominal,
        )


@dataclass(frozen=True)
class DesignSearch(Tabular):
    """Designs ranked best first (per parameter value when a parameter axis was given);
    ``to_arrow()`` / ``to_pandas()``: one row per design (its ``rank`` from 1 within its parameter
    value, the parameter's own column when there is one).

    Examples:

        >>> import rotorfault as rf
        >>> search = rf.design_search(rf.Airframe.preset("hexa-ppnnpn"))
        >>> search.to_arrow().num_rows == len(search.designs), search.formula
        (True, 'facet-margin')
    """

    airframe: str
    formula: AcaiFormula
    parameter: str | None
    designs: tuple[Design, ...]

    def best(self, parameter_value: float | None = None) -> Design:
        pool = [d for d in self.designs if parameter_value is None or d.parameter_value == parameter_value]
        if not pool:
            raise KeyError(f"no design for parameter value {parameter_value}")
        return pool[0]

    def design(self, spins: str, parameter_value: float | None = None) -> Design:
        """The entry of ``spins`` (any member of its symmetry class)."""
        for d in self.designs:
            if (parameter_value is None or d.parameter_value == parameter_value) and (d.spins == spins or spins in _orbit(d.spins)):
                return d
        raise KeyError(f"no design {spins!r}")

    def _table_columns(self) -> list[Column]:
        acai_ = f"acai_{self.formula.replace('-', '_')}"
        designs = self.designs
        ranks: list[int] = []
        seen: dict[float | None, int] = {}
        for d in designs:
            seen[d.parameter_value] = seen.get(d.parameter_value, 0) + 1
            ranks.append(seen[d.parameter_value])
        single = [len(d.single) for d in designs]
        columns: list[Column] = [(self.parameter, "float64", [d.parameter_value for d in designs])] if self.parameter else []
        columns += [
            ("rank", "int64", ranks),
            ("spins", "string", [d.spins for d in designs]),
            (acai_, "float64", [d.nominal for d in designs]),
            ("single_failures", "int64", single),
            ("controllable_single", "int64", [d.controllable_single for d in designs]),
            ("survivable_single_rotors", "list<int64>", [list(d.survivable_single) for d in designs]),
            (f"worst_single_{acai_}", "float64", [d.worst_single for d in designs]),
            ("double_failures", "int64", [m * (m - 1) // 2 for m in single]),
            ("controllable_double", "int64", [d.controllable_double for d in designs]),
            (f"worst_double_{acai_}", "float64", [d.worst_double for d in designs]),
            ("controllable_single_give_up_yaw", "int64", [d.controllable_single_give_up_yaw for d in designs]),
            (f"worst_single_{acai_}_give_up_yaw", "float64", [d.worst_single_give_up_yaw for d in designs]),
            ("controllable_double_give_up_yaw", "int64", [d.controllable_double_give_up_yaw for d in designs]),
            (f"worst_double_{acai_}_give_up_yaw", "float64", [d.worst_double_give_up_yaw for d in designs]),
        ]
        return columns

    def _table_title(self) -> str:
        return f"{self.airframe} frame: spin assignments, best first (ACAI {self.formula})"

    def _table_metadata(self) -> dict[str, Any]:
        return {"kind": "design-search", "airframe": self.airframe, "formula": self.formula, "parameter": self.parameter}

    def rows_for_display(self) -> tuple[list[str], list[list[str]]]:
        headers = (["value"] if self.parameter else []) + [
            "spins", "ACAI", "ok1", "worst1", "ok2", "worst2", "ok1*", "worst1*", "ok2*", "worst2*",
        ]
        rows = []
        for d in self.designs:
            single_total = len(d.single)
            double_total = single_total * (single_total - 1) // 2
            rows.append(
                ([f"{d.parameter_value:g}"] if self.parameter else [])
                + [
                    d.spins, f"{d.nominal:.4f}",
                    f"{d.controllable_single}/{single_total}", _fmt(d.worst_single),
                    f"{d.controllable_double}/{double_total}", _fmt(d.worst_double),
                    f"{d.controllable_single_give_up_yaw}/{single_total}", _fmt(d.worst_single_give_up_yaw),
                    f"{d.controllable_double_give_up_yaw}/{double_total}", _fmt(d.worst_double_give_up_yaw),
                ]
            )
        return headers, rows

    def __str__(self) -> str:
        return self.format()

    def format(self, top: int = 0) -> str:
        """The ranking as text (80 columns for up to 8 rotors); ``top``: only the best N per
        parameter value (0: all)."""
        headers, rows = self.rows_for_display()
        if top > 0:
            seen: dict[float | None, int] = {}
            kept = []
            for d, row in zip(self.designs, rows):
                seen[d.parameter_value] = seen.get(d.parameter_value, 0) + 1
                if seen[d.parameter_value] <= top:
                    kept.append(row)
            rows = kept
        widths = [max(len(h), *(len(r[i]) for r in rows)) for i, h in enumerate(headers)]
        lines = [
            f"{self.airframe} frame: spin assignments, best first (ACAI {self.formula})",
            "P: clockwise seen from above; okK: controllable cases of K failed rotors;",
            "worstK: their lowest ACAI; *: giving up yaw (thrust, roll and pitch only)",
            " ".join(h.ljust(w) for h, w in zip(headers, widths)).rstrip(),
            " ".join("-" * w for w in widths),
        ]
        lines += [" ".join(c.ljust(w) for c, w in zip(r, widths)).rstrip() for r in rows]
        return "\n".join(lines)


def _fmt(value: float) -> str:
    return "undef" if math.isinf(value) else f"{value:.4f}"


def _evaluate(frame: Airframe, spins: str, formula: AcaiFormula, value: float | None) -> Design:
    candidate = with_spins(frame, spins)
    table = failure_table(candidate, max_failed=2, formula=formula)
    singles = [c for c in table if len(c.failed) == 1]
    doubles = [c for c in table if len(c.failed) == 2]

    def worst(cases: Sequence[Any], attr: str) -> float:
        return min(getattr(c, attr) for c in cases) if cases else math.nan

    return Design(
        spins=spins,
        parameter_value=value,
        nominal=float(acai(candidate, formula=formula)),
        single=tuple(c.acai for c in singles),
        single_give_up_yaw=tuple(c.acai_give_up_yaw for c in singles),
        controllable_single=sum(c.controllable for c in singles),
        worst_single=worst(singles, "acai"),
        controllable_double=sum(c.controllable for c in doubles),
        worst_double=worst(doubles, "acai"),
        controllable_single_give_up_yaw=sum(c.controllable_give_up_yaw for c in singles),
        worst_single_give_up_yaw=worst(singles, "acai_give_up_yaw"),
        controllable_double_give_up_yaw=sum(c.controllable_give_up_yaw for c in doubles),
        worst_double_give_up_yaw=worst(doubles, "acai_give_up_yaw"),
        _single_ok=tuple(c.controllable for c in singles),
    )


def design_search(
    airframe: Airframe,
    *,
    parameter: str | None = None,
    values: Sequence[float] | None = None,
    formula: AcaiFormula = "facet-margin",
) -> DesignSearch:
    """Ranks every spin assignment of ``airframe``'s frame (its geometry, thrust bounds and mass;
    its own spins are ignored) by failure tolerance (module docstring), optionally for each value
    of one airframe parameter (``parameter``: an axis name of :func:`rotorfault.acai_scan`, e.g.
    ``arm_length_m`` or ``max_thrust_n``). ``formula="facet-margin"`` (default) makes the worst
    case of an infeasible hover negative (how far outside) instead of eq. (13)'s 0.

    Examples:

        >>> import rotorfault as rf
        >>> search = rf.design_search(rf.Airframe.preset("hexa-ppnnpn"))
        >>> len(search.designs), search.best().spins
        (8, 'PPNPNN')
    """
    airframe = require_airframe(airframe)
    if formula not in ("eq13", "facet-margin"):
        raise ValueError(f"formula: must be 'eq13' or 'facet-margin', got {formula!r}")
    if (parameter is None) != (values is None):
        raise ValueError("parameter, values: give both or neither")
    frames: list[tuple[float | None, Airframe]] = [(None, airframe)]
    if parameter is not None:
        param, rotor = _axis_name(parameter, airframe.rotor_count)
        if param == "efficiency" or rotor is not None:
            raise ValueError(f"parameter: must be an airframe parameter of every rotor ({', '.join(('max_thrust_n', 'min_thrust_n', 'arm_length_m', 'mass_kg', 'drag_torque_ratio_m'))}), got {parameter!r}")
        levels = float_array("values", values, 1)
        if levels.size == 0:
            raise ValueError("values: give at least one value")
        frames = []
        for v in levels:
            try:
                frames.append((float(v), _variant(airframe, {parameter: float(v)})))
            except ValueError as exc:
                raise ValueError(f"values: {parameter} = {v:g}: {exc}") from None
    spins = spin_assignments(airframe.rotor_count, symmetric=is_regular(airframe))
    designs: list[Design] = []
    for value, frame in frames:
        group = [_evaluate(frame, s, formula, value) for s in spins]
        group.sort(key=lambda d: tuple(-x for x in d.rank_key()))
        designs += group
    return DesignSearch(airframe.name, formula, parameter, tuple(designs))


__all__ = ["Design", "DesignSearch", "design_search", "is_regular", "spin_assignments", "with_spins"]

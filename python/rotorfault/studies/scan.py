"""Efficiency-grid scans: the controllable region of Du et al. Fig. 4.

Some rotors' efficiencies sweep a regular grid over [0, 1] while the others keep the airframe's
values; the ACAI is evaluated at every grid point by the parallel Rust batch.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from os import PathLike
from pathlib import Path
from typing import TYPE_CHECKING, Any, cast

import numpy as np
import numpy.typing as npt

from .._typing import AcaiFormula, ScanBackend as Backend
from .._util.convert import FloatArray, count, flag, float_array, real, rotor_numbers
from .._util.progress import chunks
from .._util.tables import Column, Tabular
from ..analysis.acai import acai_batch
from ..analysis.airframe import Airframe, require_airframe
from .storage import pyarrow_module

if TYPE_CHECKING:
    from matplotlib.figure import Figure

#: Points evaluated per batch call; bounds memory and drives the progress bar.
CHUNK_POINTS = 1 << 20
#: Scans held in memory are sized by their bytes, not their points: at most
#: :data:`rotorfault.studies.engine.MAX_IN_MEMORY_BYTES` (1 GiB) of results, each row's bytes
#: counted from what it holds (:func:`efficiency_scan`: 8 per swept rotor, 8 for the ACAI, 1 for the
#: hover code; :func:`acai_scan`: its schema, 43 bytes for three efficiency axes and both formulas,
#: so at most 24,970,740 points). Larger scans stream to Parquet (``out=``, ``rotorfault scan --out``).
#: Largest scan streamed to Parquet: row numbers stay far inside int64 and the chunk files
#: (``chunk-<9 digits>``) stay countable; planning it takes constant memory (chunks are made
#: one at a time), running it takes as long as it takes.
MAX_STREAM_POINTS = 10**15


@dataclass(frozen=True)
class EfficiencyScan(Tabular):
    """Result of :func:`efficiency_scan`; ``to_arrow()`` / ``to_pandas()``: one row per grid point
    with the columns of :func:`acai_scan` (``efficiency_<rotor>``, ``acai_<formula>``,
    ``hover_code``, ``controllable``; ``..._give_up_yaw`` when yaw was given up).

    Examples:

        >>> import rotorfault as rf
        >>> scan = rf.efficiency_scan(rf.Airframe.preset("hexa-ppnnpn"), rotors=(1,), step=0.25)
        >>> scan.to_arrow().column_names, scan.acai.round(4).tolist()
        (['efficiency_1', 'acai_eq13', 'hover_code', 'controllable'], [0.7221, 0.9559, 1.1295, 1.1295, 1.1295])
    """

    airframe: str
    #: Swept rotors, 1-based.
    rotors: tuple[int, ...]
    #: Grid values shared by every swept rotor.
    levels: FloatArray
    #: N x len(rotors) efficiencies of the swept rotors at each point (last rotor fastest).
    points: FloatArray
    #: ACAI at each point (``formula``: how a point with the hover wrench outside reads).
    acai: FloatArray
    give_up_yaw: bool
    #: Where the hover wrench lies at each point (:data:`rotorfault.analysis.HOVER_CODES`:
    #: 1 inside, 0 boundary, -1 outside, -2 rank deficient): eq. (13) prints 0 for some outside
    #: points, this column tells them from boundaries.
    hover_code: npt.NDArray[np.int8] = field(default_factory=lambda: np.zeros(0, dtype=np.int8))
    formula: AcaiFormula = "eq13"

    @property
    def controllable(self) -> np.ndarray[Any, np.dtype[np.bool_]]:
        return self.acai > 0.0

    @property
    def hover_feasible(self) -> np.ndarray[Any, np.dtype[np.bool_]]:
        """The hover wrench is attainable (inside or on the boundary) at each point."""
        return self.hover_code >= 0

    @property
    def controllable_fraction(self) -> float:
        return float(self.controllable.mean())

    def plot(self, path: str | None = None) -> Figure:
        """Du Fig. 4 style: the controllable points in 3-D and their projections."""
        return plot_efficiency_scan(self, path)

    def _table_columns(self) -> list[Column]:
        suffix = _column_suffix(self.give_up_yaw)
        columns: list[Column] = [(f"efficiency_{r}", "float64", self.points[:, k]) for k, r in enumerate(self.rotors)]
        return columns + [
            (acai_column(self.formula, self.give_up_yaw), "float64", self.acai),
            (f"hover_code{suffix}", "int8", self.hover_code),
            (f"controllable{suffix}", "bool", self.controllable),
        ]

    def _table_title(self) -> str:
        return f"{self.airframe}: efficiency scan of rotors {', '.join(map(str, self.rotors))}"

    def _table_metadata(self) -> dict[str, Any]:
        return {"kind": "efficiency-scan", "airframe": self.airframe, "formula": self.formula, "give_up_yaw": self.give_up_yaw}


def efficiency_scan(
    airframe: Airframe,
    rotors: Sequence[int] = (1, 2, 5),
    step: float = 0.04,
    *,
    give_up_yaw: bool = False,
    formula: AcaiFormula = "eq13",
    progress: bool | None = None,
) -> EfficiencyScan:
    """Sweeps the efficiencies of ``rotors`` (1-based) over ``0, step, ..., 1`` (Du Fig. 4 uses
    rotors 1, 2, 5 of the PNPNPN hexacopter with step 0.04: 26^3 = 17,576 points).

    ``progress`` shows a progress bar (default: only for scans over 10 million points).

    Examples:

        >>> import rotorfault as rf
        >>> scan = rf.efficiency_scan(rf.Airframe.preset("hexa-ppnnpn"), rotors=(1, 2), step=0.5)
        >>> scan.points.shape, round(scan.controllable_fraction, 4)
        ((9, 2), 0.6667)
    """
    airframe = require_airframe(airframe)
    step = real("step", step)
    give_up_yaw = flag("give_up_yaw", give_up_yaw)
    # 1e-9: the divisibility tolerance below (and 1 / step stays finite: 1e-310 overflowed).
    if not 1e-9 <= step <= 1.0:
        raise ValueError(f"step: must lie in [1e-9, 1], got {step}")
    swept = rotor_numbers("rotors", rotors, airframe.rotor_count)
    if not swept:
        raise ValueError("rotors: give at least one rotor to sweep")
    if len(set(swept)) != len(swept):
        raise ValueError(f"rotors: each rotor may be swept once, got {swept}")
    count = int(round(1.0 / step))
    if not np.isclose(count * step, 1.0, rtol=0.0, atol=1e-9):
        raise ValueError(f"step: must divide 1 evenly (0.04, 0.05, 0.1, ...), got {step}")
    # The size is checked on integers before anything is allocated: per point the swept
    # efficiencies, the ACAI (float64 each) and the hover code (int8).
    from .engine import check_in_memory

    total = (count + 1) ** len(swept)
    check_in_memory(
        "step, rotors", total, 8 * len(swept) + 8 + 1,
        remedy=f"({count + 1}^{len(swept)} grid points) use a coarser step or fewer rotors, or stream the grid to Parquet "
        "with acai_scan(..., out=DIR) (CLI: rotorfault scan --out DIR)",
    )
    levels = np.linspace(0.0, 1.0, count + 1)
    points = np.empty((total, len(swept)))
    # Each column broadcast into place (the last rotor fastest): no grid-sized temporaries.
    grid = points.reshape((count + 1,) * len(swept) + (len(swept),))
    for column in range(len(swept)):
        shape = [1] * len(swept)
        shape[column] = count + 1
        grid[..., column] = levels.reshape(shape)
    base = airframe.efficiency
    columns = [r - 1 for r in swept]
    result = np.empty(total)
    hover = np.empty(total, dtype=np.int8)
    pieces = chunks(total, CHUNK_POINTS, description=f"ACAI over {total:,} points", show=progress, default_show=total > 10_000_000)
    for start, stop in pieces:
        efficiencies = np.tile(base, (stop - start, 1))
        efficiencies[:, columns] = points[start:stop]
        batch = acai_batch(airframe, efficiencies, give_up_yaw=give_up_yaw, formula=formula, with_hover=True)
        result[start:stop] = batch.acai
        hover[start:stop] = batch.hover_code
    return EfficiencyScan(airframe.name, swept, levels, points, result, give_up_yaw, hover, formula)


def plot_efficiency_scan(scan: EfficiencyScan | Scan | str | PathLike[str], path: str | None = None) -> Figure:
    """Du Fig. 4 style. Left: the surface of the controllable region (grid points that are
    controllable but have an uncontrollable neighbour), shaded by the third rotor's efficiency.
    Other panels: for each pair of swept rotors, the lowest efficiency of the third rotor that
    keeps the vehicle controllable, on a colour scale spanning the values that occur; hatched
    grey where no efficiency of the third rotor does ("uncontrollable"), which the scale never
    confuses with a small value. A scan giving up yaw says so in every title. Needs exactly three
    swept rotors. Returns the figure (not registered with pyplot), saved to ``path`` (``.png``,
    ``.pdf`` or ``.svg``, written atomically) if given.

    ``scan`` may also be a :class:`Scan` or the Parquet directory of one (``rotorfault scan
    --out``): only its verdict column is read, chunk by chunk.

    Examples:

        >>> import matplotlib
        >>> matplotlib.use("Agg")
        >>> import rotorfault as rf
        >>> scan = rf.efficiency_scan(rf.Airframe.preset("hexa-ppnnpn"), rotors=(1, 2, 5), step=0.5)
        >>> len(rf.plot_efficiency_scan(scan).axes) >= 1
        True
    """
    from ..plotting.regions import plot_region

    if isinstance(scan, (str, PathLike)):
        scan = read_scan(scan)
    if isinstance(scan, Scan):
        return scan.plot(path)
    if not isinstance(scan, EfficiencyScan):
        raise TypeError(f"scan: expected an EfficiencyScan, a Scan or the path of a scan's output, got {type(scan).__name__}")
    if len(scan.rotors) != 3:
        raise ValueError(f"scan: the Fig. 4 plot needs three swept rotors, got {len(scan.rotors)}")
    n = len(scan.levels)
    return plot_region(scan.controllable.reshape(n, n, n), scan.levels, scan.rotors, scan.airframe, scan.give_up_yaw, path)


# -- scans at scale: N-D grids or sample sets, in memory or streamed to Parquet -------------------

#: Airframe parameters a scan can sweep (every rotor, or one rotor with a ``_<i>`` suffix for the
#: per-rotor ones), besides ``efficiency_<i>``.
PARAMETER_AXES = ("max_thrust_n", "min_thrust_n", "arm_length_m", "mass_kg", "drag_torque_ratio_m")
_PER_ROTOR = ("efficiency", "max_thrust_n", "min_thrust_n", "arm_length_m")
#: Kind recorded in a scan output's manifest.
SCAN_KIND = "rotorfault-scan"


def _axis_name(name: Any, rotor_count: int) -> tuple[str, int | None]:
    """``(parameter, rotor index 0-based or None)`` of an axis name."""
    if not isinstance(name, str):
        raise TypeError(f"axes: axis names must be strings, got {type(name).__name__}")
    for base in _PER_ROTOR:
        prefix = base + "_"
        if name.startswith(prefix) and name[len(prefix):].isdigit():
            rotor = int(name[len(prefix):])
            if not 1 <= rotor <= rotor_count:
                raise ValueError(f"axes: {name!r}: rotor numbers run from 1 to {rotor_count}")
            return base, rotor - 1
    if name in PARAMETER_AXES:
        return name, None
    raise ValueError(
        f"axes: unknown axis {name!r}; use efficiency_<rotor>, max_thrust_n[_<rotor>], min_thrust_n[_<rotor>], "
        "arm_length_m[_<rotor>], mass_kg or drag_torque_ratio_m"
    )


def _variant(base: Airframe, params: Mapping[str, float]) -> Airframe:
    """``base`` with the parameter axes' values and nothing else changed (its 3-D positions, thrust
    axes, reversible bounds, each rotor's k_mu and efficiencies kept: :meth:`Airframe.with_parameters`);
    the core checks the values, naming the field."""
    if not params:
        return base
    changes: dict[str, Any] = {}
    for name, value in params.items():
        param, rotor = _axis_name(name, base.rotor_count)
        if param in ("mass_kg", "drag_torque_ratio_m"):
            changes[param] = float(value)
            continue
        values = changes.setdefault(param, np.array(getattr(base, param), dtype=np.float64))
        if rotor is None:
            values[:] = value
        else:
            values[rotor] = value
    return base.with_parameters(**changes)


def _check_overlaps(names: Sequence[str], rotor_count: int) -> None:
    """Two axes on one parameter (``max_thrust_n`` and ``max_thrust_n_2``, or the same rotor
    written twice) would both set it: refused, naming them."""
    seen: dict[tuple[str, int | None], str] = {}
    for name in names:
        param, rotor = _axis_name(name, rotor_count)
        clashes = [other for (p, r), other in seen.items() if p == param and (r == rotor or r is None or rotor is None)]
        if clashes:
            raise ValueError(f"axes: {clashes[0]!r} and {name!r} both set {param}{'' if rotor is None else f' of rotor {rotor + 1}'}; give one axis per parameter")
        seen[(param, rotor)] = name


def _column_suffix(give_up_yaw: bool) -> str:
    return "_give_up_yaw" if give_up_yaw else ""


def acai_column(formula: str, give_up_yaw: bool = False) -> str:
    """Name of a scan's ACAI column: ``acai_eq13``, ``acai_facet_margin``, ``..._give_up_yaw``."""
    return f"acai_{formula.replace('-', '_')}{_column_suffix(give_up_yaw)}"


def scan_schema(names: Sequence[str], formulas: Sequence[str], give_up_yaw: bool) -> Any:
    """The Arrow schema of a scan: the axes (float64), then per yaw choice the ACAI of each
    formula, the hover code (int8), the verdict and rank C(A, B) (int8)."""
    pa = pyarrow_module()

    fields = [pa.field(n, pa.float64()) for n in names]
    for yaw in (False, True) if give_up_yaw else (False,):
        fields += [pa.field(acai_column(f, yaw), pa.float64()) for f in formulas]
        suffix = _column_suffix(yaw)
        fields += [
            pa.field(f"hover_code{suffix}", pa.int8()),
            pa.field(f"controllable{suffix}", pa.bool_()),
            pa.field(f"controllability_rank{suffix}", pa.int8()),
        ]
    return pa.schema(fields)


@dataclass(frozen=True)
class _ScanTask:
    """The work of one chunk of a scan (picklable: the airframe travels as its exact TOML)."""

    airframe_toml: str
    names: tuple[str, ...]
    #: Grid: the levels of each axis (last axis fastest); None for a sample set.
    levels: tuple[tuple[float, ...], ...] | None
    #: Sample set: one column per axis; None for a grid.
    samples: tuple[FloatArray, ...] | None
    give_up_yaw: bool
    formulas: tuple[str, ...]

    @property
    def total(self) -> int:
        """Rows, exactly (Python integers: a grid's size never wraps)."""
        if self.levels is not None:
            return math.prod(len(v) for v in self.levels)
        assert self.samples is not None
        return len(self.samples[0])

    def coordinates(self, start: int, stop: int) -> list[FloatArray]:
        if self.samples is not None:
            return [np.ascontiguousarray(column[start:stop], dtype=np.float64) for column in self.samples]
        assert self.levels is not None
        index = np.arange(start, stop, dtype=np.int64)
        shape = tuple(len(v) for v in self.levels)
        return [np.asarray(levels, dtype=np.float64)[k] for levels, k in zip(self.levels, np.unravel_index(index, shape))]

    def __call__(self, spec: Any) -> Any:
        pa = pyarrow_module()

        from ..analysis.controllability import controllability

        base = Airframe.from_toml_str(self.airframe_toml, "scan airframe")
        m = base.rotor_count
        coords = self.coordinates(spec.start, spec.stop)
        rows = spec.stop - spec.start
        parsed = [_axis_name(n, m) for n in self.names]
        eff_axes = [(k, rotor) for k, (param, rotor) in enumerate(parsed) if param == "efficiency"]
        param_axes = [k for k, (param, _) in enumerate(parsed) if param != "efficiency"]
        efficiencies = np.empty((rows, m))
        efficiencies[:] = base.efficiency
        for k, rotor in eff_axes:
            efficiencies[:, rotor] = coords[k]
        yaws = (False, True) if self.give_up_yaw else (False,)
        out: dict[str, Any] = {n: coords[k] for k, n in enumerate(self.names)}
        for yaw in yaws:
            for f in self.formulas:
                out[acai_column(f, yaw)] = np.empty(rows)
            suffix = _column_suffix(yaw)
            out[f"hover_code{suffix}"] = np.empty(rows, dtype=np.int8)
            out[f"controllable{suffix}"] = np.empty(rows, dtype=bool)
            out[f"controllability_rank{suffix}"] = np.empty(rows, dtype=np.int8)
        if param_axes:
            keys = np.stack([coords[k] for k in param_axes], axis=1)
            combos, inverse = np.unique(keys, axis=0, return_inverse=True)
            groups: list[tuple[FloatArray, npt.NDArray[np.intp] | None]] = [
                (combo, np.flatnonzero(inverse.ravel() == g)) for g, combo in enumerate(combos)
            ]
        else:
            groups = [(np.zeros(0), None)]
        for combo, where in groups:
            frame = _variant(base, {self.names[k]: float(v) for k, v in zip(param_axes, combo)})
            etas = efficiencies if where is None else np.ascontiguousarray(efficiencies[where])
            for yaw in yaws:
                suffix = _column_suffix(yaw)
                rank = controllability(frame, give_up_yaw=yaw).controllability_rank
                full = rank == (6 if yaw else 8)
                hover = None
                for f in self.formulas:
                    batch = acai_batch(frame, etas, give_up_yaw=yaw, formula=cast(AcaiFormula, f), with_hover=True)
                    target = out[acai_column(f, yaw)]
                    if where is None:
                        target[:] = batch.acai
                    else:
                        target[where] = batch.acai
                    hover = batch.hover_code
                assert hover is not None
                # Du's Theorem 2 (the core's verdict rule): rank C full and the facet margin > 0.
                ok = (hover == 1) & full
                sel = slice(None) if where is None else where
                out[f"hover_code{suffix}"][sel] = hover
                out[f"controllable{suffix}"][sel] = ok
                out[f"controllability_rank{suffix}"][sel] = rank
        schema = scan_schema(self.names, self.formulas, self.give_up_yaw)
        return pa.Table.from_arrays([pa.array(out[field.name], type=field.type) for field in schema], schema=schema)


@dataclass(frozen=True)
class Scan(Tabular):
    """Result of :func:`acai_scan`: the rows in memory (``table``) or the Parquet output directory
    (``out``), with what the scan was (``manifest``: axes, airframe TOML, version...).
    ``to_arrow()`` / ``to_pandas()``: every row, in memory or read whole from Parquet (the same
    schema either way, :func:`scan_schema`; :meth:`iter_tables` reads a large output chunk by
    chunk).

    Examples:

        >>> import rotorfault as rf
        >>> scan = rf.acai_scan(rf.Airframe.preset("quad-x"), {"efficiency_1": [0.5, 1.0]}, formulas=["eq13"])
        >>> scan.table.column_names, scan.column("acai_eq13").round(4).tolist()
        (['efficiency_1', 'acai_eq13', 'hover_code', 'controllable', 'controllability_rank'], [-0.2251, 0.7623])
    """

    airframe: str
    names: tuple[str, ...]
    levels: tuple[FloatArray, ...] | None
    give_up_yaw: bool
    formulas: tuple[str, ...]
    total: int
    table: Any = None
    out: Path | None = None
    seconds: float = 0.0
    computed_chunks: int = 0
    skipped_chunks: int = 0

    def iter_tables(self, columns: Sequence[str] | None = None) -> Iterator[Any]:
        """The rows chunk by chunk (pyarrow Tables, in row order); from Parquet without loading
        the whole output."""
        cols = None if columns is None else list(columns)
        if self.table is not None:
            yield self.table if cols is None else self.table.select(cols)
            return
        from .storage import iter_tables

        assert self.out is not None
        yield from iter_tables(self.out, cols)

    def to_arrow(self) -> Any:
        """Every row as one ``pyarrow.Table`` with the scan's schema (:func:`scan_schema`)."""
        pa = pyarrow_module()
        schema = scan_schema(self.names, self.formulas, self.give_up_yaw)
        tables = [t.replace_schema_metadata(None) for t in self.iter_tables()]
        return pa.concat_tables(tables) if tables else schema.empty_table()

    def _table_title(self) -> str:
        where = "in memory" if self.out is None else str(self.out)
        return f"{self.airframe}: scan over {', '.join(self.names)} ({where})"

    def column(self, name: str) -> npt.NDArray[Any]:
        """One whole column as a numpy array (reads only that column from Parquet)."""
        parts = [t.column(0).to_numpy() for t in self.iter_tables([name])]
        return np.concatenate(parts) if parts else np.zeros(0)

    def controllable_count(self, *, give_up_yaw: bool = False) -> int:
        name = f"controllable{_column_suffix(give_up_yaw)}"
        return sum(int(np.count_nonzero(t.column(0).to_numpy(zero_copy_only=False))) for t in self.iter_tables([name]))

    def plot(self, path: str | None = None, *, give_up_yaw: bool = False) -> Figure:
        """Du Fig. 4 from a grid over exactly three efficiency axes with equal levels, reading
        only the verdict column chunk by chunk (memory: one byte per grid point)."""
        if self.levels is None or len(self.names) != 3 or not all(n.startswith("efficiency_") for n in self.names):
            raise ValueError(f"scan: the Fig. 4 plot needs a grid over three efficiency axes, got {', '.join(self.names)}")
        if not all(np.array_equal(self.levels[0], lv) for lv in self.levels):
            raise ValueError("scan: the Fig. 4 plot needs the same levels on the three axes")
        n = len(self.levels[0])
        ok = np.empty(self.total, dtype=bool)
        name = f"controllable{_column_suffix(give_up_yaw)}"
        at = 0
        for t in self.iter_tables([name]):
            part = t.column(0).to_numpy(zero_copy_only=False)
            ok[at : at + len(part)] = part
            at += len(part)
        rotors = tuple(int(x.split("_")[1]) for x in self.names)
        from ..plotting.regions import plot_region

        return plot_region(ok.reshape(n, n, n), np.asarray(self.levels[0]), rotors, self.airframe, give_up_yaw, path)


def _axis_values(name: str, values: Any) -> FloatArray:
    array = float_array(f"axes[{name!r}]", values, 1)
    if array.size == 0:
        raise ValueError(f"axes[{name!r}]: give at least one value")
    return array


def _check_axis_values(base: Airframe, names: Sequence[str], columns: Sequence[FloatArray]) -> None:
    """Each axis value through the core's own checks (before anything is computed)."""
    for name, values in zip(names, columns):
        param, rotor = _axis_name(name, base.rotor_count)
        for value in np.unique(values):
            if param == "efficiency":
                eff = base.efficiency.copy()
                assert rotor is not None
                eff[rotor] = value
                try:
                    base.with_efficiency(eff)
                except ValueError as exc:
                    raise ValueError(f"axes[{name!r}]: {exc}") from None
            else:
                try:
                    _variant(base, {name: float(value)})
                except ValueError as exc:
                    raise ValueError(f"axes[{name!r}] = {value:g}: {exc}") from None


def acai_scan(
    airframe: Airframe,
    axes: Mapping[str, npt.ArrayLike] | None = None,
    *,
    samples: Mapping[str, npt.ArrayLike] | None = None,
    give_up_yaw: bool = False,
    formulas: Sequence[AcaiFormula] = ("eq13", "facet-margin"),
    out: str | PathLike[str] | None = None,
    resume: bool = False,
    force: bool = False,
    backend: Backend = "local",
    dask: Any = None,
    chunk_points: int = CHUNK_POINTS,
    progress: bool | None = None,
) -> Scan:
    """ACAI and controllability over an N-D grid (``axes``: name -> levels, the last axis
    fastest) or a sample set (``samples``: name -> one value per point), in memory or streamed to
    the Parquet directory ``out`` (resumable; see :mod:`rotorfault.studies.storage`).

    Axis names: ``efficiency_<rotor>`` (1-based), and airframe parameters ``max_thrust_n``,
    ``min_thrust_n``, ``arm_length_m`` (every rotor, or one with ``_<rotor>``), ``mass_kg`` and
    ``drag_torque_ratio_m`` (k_mu). Put parameter axes first (slowest): each chunk builds one
    airframe per parameter combination it holds.

    Columns: the axes, ``acai_eq13`` / ``acai_facet_margin`` (``formulas``), ``hover_code``
    (1 inside, 0 boundary, -1 outside, -2 rank B_f deficient), ``controllable`` (rank C(A, B)
    full and the hover wrench strictly inside: Du's Theorem 2, the core's verdict) and
    ``controllability_rank`` (rank C(A, B), of 8); with ``give_up_yaw=True`` the same again for
    thrust, roll and pitch only (suffix ``_give_up_yaw``, rank of 6).

    ``backend="dask"`` runs the chunks on a ``dask.distributed`` cluster (``dask``: a Client, an
    address or ``"local:N"``); the rows are identical to the local backend's.

    Examples:

        >>> import rotorfault as rf
        >>> scan = rf.acai_scan(rf.Airframe.preset("quad-x"), {"efficiency_1": [0.0, 0.5, 1.0]})
        >>> scan.total, scan.controllable_count()
        (3, 1)
    """
    from .. import _rfcore
    from .engine import run_chunks

    airframe = require_airframe(airframe)
    give_up_yaw = flag("give_up_yaw", give_up_yaw)
    if (axes is None) == (samples is None):
        raise ValueError("axes, samples: give exactly one (a grid or a sample set)")
    if isinstance(formulas, str) or not isinstance(formulas, Sequence):
        raise TypeError("formulas: expected a sequence of 'eq13' / 'facet-margin'")
    formula_names = tuple(formulas)
    for f in formula_names:
        if f not in ("eq13", "facet-margin"):
            raise ValueError(f"formulas: each must be 'eq13' or 'facet-margin', got {f!r}")
    if not formula_names or len(set(formula_names)) != len(formula_names):
        raise ValueError(f"formulas: give each formula once and at least one, got {formula_names}")
    if isinstance(chunk_points, bool) or not isinstance(chunk_points, int):
        raise TypeError(f"chunk_points: expected an integer, got {type(chunk_points).__name__}")
    if chunk_points < 1:
        raise ValueError(f"chunk_points: must be at least 1, got {chunk_points}")
    spec = axes if axes is not None else samples
    if not isinstance(spec, Mapping):
        raise TypeError(f"{'axes' if axes is not None else 'samples'}: expected a mapping of axis name to values")
    if not spec:
        raise ValueError(f"{'axes' if axes is not None else 'samples'}: give at least one axis")
    names = tuple(spec)
    _check_overlaps(names, airframe.rotor_count)
    columns = [_axis_values(n, spec[n]) for n in names]
    from .engine import check_in_memory, row_bytes

    if axes is not None:
        # The size on Python integers, before anything is built from it.
        total_points = math.prod(len(c) for c in columns)
        shape = " x ".join(str(len(c)) for c in columns)
        streamable = total_points <= MAX_STREAM_POINTS
        if out is None:
            check_in_memory("axes", total_points, row_bytes(scan_schema(names, formula_names, give_up_yaw)),
                            remedy=f"({shape} grid points) stream them to Parquet with out=DIR (CLI: rotorfault scan --out DIR)" if streamable
                            else f"({shape} grid points) more than a streamed scan takes too ({MAX_STREAM_POINTS:,}): use fewer levels")
        if not streamable:
            raise ValueError(f"axes: {shape} = {total_points:,} grid points exceed the limit of a streamed scan of {MAX_STREAM_POINTS:,}")
        if -(-total_points // chunk_points) >= 10**9:
            raise ValueError(f"chunk_points: {total_points:,} points in chunks of {chunk_points:,} make over 10^9 chunk files; use larger chunks")
    if samples is not None and len({len(c) for c in columns}) != 1:
        raise ValueError(f"samples: every axis needs one value per point, got lengths {[len(c) for c in columns]}")
    if samples is not None and out is None:
        check_in_memory("samples", len(columns[0]), row_bytes(scan_schema(names, formula_names, give_up_yaw)))
    _check_axis_values(airframe, names, columns)
    levels = tuple(tuple(float(v) for v in c) for c in columns) if axes is not None else None
    task = _ScanTask(airframe.to_toml(), names, levels, tuple(columns) if samples is not None else None, give_up_yaw, formula_names)
    total = task.total
    if axes is not None:
        axes_arg: dict[str, Any] = {"grid": {n: list(lv) for n, lv in zip(names, levels or ())}}
    else:
        import hashlib

        digest = hashlib.sha256()
        for c in columns:
            digest.update(np.ascontiguousarray(c).tobytes())
        axes_arg = {"samples": list(names), "sample_count": total, "samples_sha256": digest.hexdigest()}
    arguments = {
        "airframe_toml": airframe.to_toml(),
        **axes_arg,
        "give_up_yaw": give_up_yaw,
        "formulas": list(formula_names),
    }
    result = run_chunks(
        task,
        total_rows=total,
        chunk_rows=chunk_points,
        schema=scan_schema(names, formula_names, give_up_yaw),
        arguments=arguments,
        kind=SCAN_KIND,
        out=out,
        metadata={"airframe": airframe.name, "rotorfault_version": _rfcore.__version__, "row_order": "grid: row-major, last axis fastest" if axes is not None else "sample order"},
        resume=resume,
        force=force,
        backend=backend,
        dask=dask,
        progress=progress,
        description=f"{airframe.name}: ACAI over {total:,} points",
        rows_field="axes" if axes is not None else "samples",
    )
    return Scan(
        airframe.name, names, tuple(columns) if axes is not None else None, give_up_yaw, formula_names, total,
        result.table, result.out, result.seconds, result.computed_chunks, result.skipped_chunks,
    )


def read_scan(path: str | PathLike[str]) -> Scan:
    """A scan written to Parquet by :func:`acai_scan` (or ``rotorfault scan --out``), read lazily.

    Examples:

        >>> import tempfile, pathlib
        >>> import rotorfault as rf
        >>> folder = tempfile.TemporaryDirectory()
        >>> out = pathlib.Path(folder.name) / "scan"
        >>> written = rf.acai_scan(rf.Airframe.preset("quad-x"), {"efficiency_1": [0.5, 1.0]}, out=out)
        >>> rf.read_scan(out).total
        2
        >>> folder.cleanup()
    """
    from .storage import read_manifest

    manifest = read_manifest(path)
    if manifest.get("kind") != SCAN_KIND:
        raise ValueError(f"path: {str(path)!r} holds a {manifest.get('kind')!r} output, not a scan")
    if not manifest.get("complete"):
        raise ValueError(f"path: {str(path)!r} is an interrupted scan; finish it with --resume first")
    args = manifest["arguments"]
    if "grid" in args:
        names = tuple(args["grid"])
        levels: tuple[FloatArray, ...] | None = tuple(np.asarray(args["grid"][n], dtype=np.float64) for n in names)
    else:
        names, levels = tuple(args["samples"]), None
    return Scan(
        manifest["metadata"].get("airframe", "airframe"), names, levels, bool(args["give_up_yaw"]), tuple(args["formulas"]),
        int(manifest["total_rows"]), None, Path(path),
    )


def failure_samples(rotor_count: int, max_failed: int) -> dict[str, FloatArray]:
    """No failure and every combination of 1..``max_failed`` failed rotors as a sample set for :func:`acai_scan`
    (``efficiency_<i>`` columns of 0 and 1), in :func:`rotorfault.failure_table` order.

    At most 1 GiB (:data:`rotorfault.studies.engine.MAX_IN_MEMORY_BYTES`) of columns: 8 bytes per
    rotor and row, counted before anything is built.

    Examples:

        >>> import rotorfault as rf
        >>> samples = rf.failure_samples(4, 1)
        >>> {name: column.tolist() for name, column in samples.items()}
        {'efficiency_1': [1.0, 0.0, 1.0, 1.0, 1.0], 'efficiency_2': [1.0, 1.0, 0.0, 1.0, 1.0], 'efficiency_3': [1.0, 1.0, 1.0, 0.0, 1.0], 'efficiency_4': [1.0, 1.0, 1.0, 1.0, 0.0]}
    """
    from .engine import check_in_memory

    rotor_count = count("rotor_count", rotor_count)
    max_failed = count("max_failed", max_failed)
    if not 1 <= rotor_count:
        raise ValueError(f"rotor_count: must be >= 1, got {rotor_count}")
    if max_failed > rotor_count:
        raise ValueError(f"max_failed: must be at most rotor_count ({rotor_count}), got {max_failed}")
    # Counted before anything is built: C(n, k) rows of n values each, summed k by k and stopped
    # as soon as the sum is past the limit (C(1e9, k) for every k up to 1e9 never ends: long
    # hostile run, 2026-11-28).
    from .engine import MAX_IN_MEMORY_BYTES

    total = size = 0
    for k in range(max_failed + 1):
        size = 1 if k == 0 else size * (rotor_count - k + 1) // k
        total += size
        if total * 8 * rotor_count > MAX_IN_MEMORY_BYTES:
            break
    check_in_memory("max_failed", total, 8 * rotor_count, at_least=k < max_failed,
                    remedy=f"({rotor_count} rotors, up to {max_failed} failed) give fewer failed rotors")
    # One row per rotor (each column contiguous), built block by block without listing a
    # combination: in lexicographic order the k-failure rows whose first failed rotor is ``a`` are
    # the last C(n - a - 1, k - 1) rows of the (k - 1)-failure block (their failed rotors all
    # above ``a``) with rotor ``a`` failed too: one slice copy per (k, a), each value written once.
    eff = np.empty((rotor_count, total))
    eff[:, 0] = 1.0
    block_stop = first = 1
    for k in range(1, max_failed + 1):
        for a in range(rotor_count - k + 1):
            width = math.comb(rotor_count - a - 1, k - 1)
            eff[:, first : first + width] = eff[:, block_stop - width : block_stop]
            eff[a, first : first + width] = 0.0
            first += width
        block_stop = first
    return {f"efficiency_{r + 1}": eff[r] for r in range(rotor_count)}

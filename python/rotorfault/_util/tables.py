"""Results as tables: one implementation of ``to_arrow()``, ``to_pandas()`` and the notebook view
(``_repr_html_``) for every tabular result of the package (failure tables, certificates, scans,
campaigns, design searches, trajectories, batches, allocations, the papers' report rows).

A result class mixes in :class:`Tabular` and says what its columns are
(:meth:`Tabular._table_columns`: name, Arrow type, values; one row per case, units in the names,
``altitude_error_m``), or, when it already holds an Arrow table, overrides
:meth:`Tabular.to_arrow`. Rows that are records (a list of dicts) are :class:`Records`.

pyarrow is a dependency of the package, imported here on first use (``import rotorfault`` stays
light); pandas is optional (``rotorfault[pandas]``): :meth:`Tabular.to_pandas` says so, naming the
extra, when it is missing. This module depends only on its siblings in ``_util``.
"""

from __future__ import annotations

import html
import json
import math
from collections.abc import Iterator, Mapping, Sequence
from typing import Any, overload

from .optional import require, require_available

#: Column types, by the names :func:`arrow_type` maps to pyarrow types (strings, so that declaring
#: a schema imports nothing).
COLUMN_TYPES = ("float64", "float32", "int64", "int8", "bool", "string", "list<int64>", "list<string>", "list<float64>", "list<float32>")
#: Rows a notebook shows (half from the start, half from the end; the caption gives the count).
HTML_ROWS = 20


def pyarrow() -> Any:
    """``pyarrow`` (a dependency of the package; the message names the extra if it is missing)."""
    return require("pyarrow", feature="tables (to_arrow)")


def arrow_type(name: str) -> Any:
    """The pyarrow type of a column type name of :data:`COLUMN_TYPES`."""
    pa = pyarrow()
    scalar = {"float64": pa.float64(), "float32": pa.float32(), "int64": pa.int64(), "int8": pa.int8(), "bool": pa.bool_(), "string": pa.string()}
    if name in scalar:
        return scalar[name]
    if name.startswith("list<") and name.endswith(">") and name[5:-1] in scalar:
        # Parquet names a list's items "element": so does the schema here, so that a table written
        # to Parquet reads back with the same schema.
        return pa.list_(pa.field("element", scalar[name[5:-1]]))
    raise ValueError(f"column type: expected one of {', '.join(COLUMN_TYPES)}, got {name!r}")


#: One column: its name (units in it), its type (:data:`COLUMN_TYPES`) and one value per row.
Column = tuple[str, str, Any]


def arrow_table(columns: Sequence[Column], *, metadata: Mapping[str, Any] | None = None) -> Any:
    """A ``pyarrow.Table`` of ``columns``; ``metadata`` (JSON-able) goes into the schema under the
    key ``rotorfault``, so a Parquet file written from it says what it holds."""
    pa = pyarrow()
    fields = [pa.field(name, arrow_type(kind)) for name, kind, _ in columns]
    schema = pa.schema(fields, metadata=schema_metadata(metadata))
    arrays = [_array(pa, values, field.type) for (_, _, values), field in zip(columns, fields)]
    return pa.Table.from_arrays(arrays, schema=schema)


def schema_metadata(metadata: Mapping[str, Any] | None) -> dict[str, str] | None:
    """A schema's metadata for ``metadata`` (JSON under the key ``rotorfault``; None when empty)."""
    return None if not metadata else {"rotorfault": json.dumps(dict(metadata), sort_keys=True)}


def _array(pa: Any, values: Any, kind: Any) -> Any:
    if hasattr(values, "tolist") and not pa.types.is_list(kind):
        return pa.array(values, type=kind)
    return pa.array(list(values), type=kind)


def to_pandas(table: Any) -> Any:
    """``table`` (pyarrow) as a pandas DataFrame; ``ImportError`` naming ``rotorfault[pandas]``
    when pandas is missing (checked before anything is converted)."""
    require_available("to_pandas()", "pandas")
    return table.to_pandas()


def html_table(table: Any, *, title: str) -> str:
    """A notebook's view of ``table``: the caption (``title`` and the size), the column names and
    at most :data:`HTML_ROWS` rows (the first and the last), every cell escaped."""
    rows = table.num_rows
    shown = list(range(rows)) if rows <= HTML_ROWS else [*range(HTML_ROWS // 2), *range(rows - HTML_ROWS // 2, rows)]
    columns = table.column_names
    data = {name: table.column(name).to_pylist() for name in columns} if rows <= HTML_ROWS else {
        name: [table.column(name)[i].as_py() for i in shown] for name in columns
    }
    caption = f"{title}: {rows:,} row{'' if rows == 1 else 's'} x {len(columns)} column{'' if len(columns) == 1 else 's'}"
    out = ['<table class="rotorfault-table">', f"<caption>{html.escape(caption)}</caption>", "<thead><tr>"]
    out += [f"<th>{html.escape(str(name))}</th>" for name in columns]
    out.append("</tr></thead><tbody>")
    for k, _ in enumerate(shown):
        if rows > HTML_ROWS and k == HTML_ROWS // 2:
            out.append(f'<tr><td colspan="{len(columns)}">... {rows - HTML_ROWS:,} more rows ...</td></tr>')
        out.append("<tr>" + "".join(f"<td>{html.escape(_cell(data[name][k]))}</td>" for name in columns) + "</tr>")
    out.append("</tbody></table>")
    return "".join(out)


def _cell(value: Any) -> str:
    if value is None:
        return ""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return repr(value) if not math.isfinite(value) else f"{value:.6g}"
    if isinstance(value, list):
        return ", ".join(_cell(v) for v in value)
    return str(value)


class Tabular:
    """A result with one row per case: ``to_arrow()``, ``to_pandas()`` and the notebook view.

    A subclass gives :meth:`_table_columns` (and may give :meth:`_table_title` and
    :meth:`_table_metadata`), or overrides :meth:`to_arrow` when it holds an Arrow table."""

    __slots__ = ()  # a subclass over a core result keeps only its slot (``_util.core_result``)

    def _table_columns(self) -> Sequence[Column]:
        raise NotImplementedError(f"{type(self).__name__} gives no columns")

    def _table_title(self) -> str:
        return type(self).__name__

    def _table_metadata(self) -> Mapping[str, Any]:
        return {"kind": type(self).__name__}

    def to_arrow(self) -> Any:
        """The rows as a ``pyarrow.Table`` (one row per case; units in the column names)."""
        return arrow_table(self._table_columns(), metadata=self._table_metadata())

    def to_pandas(self) -> Any:
        """The rows as a pandas DataFrame (needs the ``pandas`` extra: ``pip install
        "rotorfault[pandas]"``), converted from :meth:`to_arrow`."""
        require_available("to_pandas()", "pandas")
        return to_pandas(self.to_arrow())

    def _repr_html_(self) -> str:
        return html_table(self.to_arrow(), title=self._table_title())


class Records(Sequence[dict[str, Any]], Tabular):
    """Rows as records (dicts, in order) with a declared schema: ``columns`` is ``(name, type)``
    pairs (:data:`COLUMN_TYPES`), every row has exactly those keys (``None``: no value, a null).
    It is a sequence of the dicts, so code that iterated a list of rows works unchanged."""

    def __init__(self, rows: Sequence[Mapping[str, Any]], columns: Sequence[tuple[str, str]], *, title: str = "rows", kind: str = "records") -> None:
        names = [name for name, _ in columns]
        for kind_name in (k for _, k in columns):
            if kind_name not in COLUMN_TYPES:
                raise ValueError(f"columns: unknown column type {kind_name!r}")
        for k, row in enumerate(rows):
            if list(row) != names:
                missing = sorted(set(names) - set(row))
                extra = sorted(set(row) - set(names))
                raise ValueError(f"rows[{k}]: keys differ from the columns (missing {missing}, extra {extra}, or another order)")
        self._rows = tuple(dict(row) for row in rows)
        self.columns = tuple((str(n), str(t)) for n, t in columns)
        self._title = title
        self._kind = kind

    @overload
    def __getitem__(self, index: int) -> dict[str, Any]: ...
    @overload
    def __getitem__(self, index: slice) -> Sequence[dict[str, Any]]: ...
    def __getitem__(self, index: int | slice) -> dict[str, Any] | Sequence[dict[str, Any]]:
        return self._rows[index]

    def __len__(self) -> int:
        return len(self._rows)

    def __iter__(self) -> Iterator[dict[str, Any]]:
        return iter(self._rows)

    def __eq__(self, other: object) -> bool:
        if isinstance(other, Records):
            return self._rows == other._rows and self.columns == other.columns
        if isinstance(other, list):
            return list(self._rows) == other
        return NotImplemented

    __hash__ = None  # type: ignore[assignment]

    def __repr__(self) -> str:
        return f"<Records {self._title}: {len(self)} rows x {len(self.columns)} columns>"

    def _table_columns(self) -> Sequence[Column]:
        return [(name, kind, [row[name] for row in self._rows]) for name, kind in self.columns]

    def _table_title(self) -> str:
        return self._title

    def _table_metadata(self) -> Mapping[str, Any]:
        return {"kind": self._kind}


__all__ = ["COLUMN_TYPES", "Column", "Records", "Tabular", "arrow_table", "arrow_type", "html_table", "pyarrow", "schema_metadata", "to_pandas"]

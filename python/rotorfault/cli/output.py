"""The one output layer of the command line: every command builds a :class:`CommandOutput` (its
facts as typed fields, its tables as typed rows, and how to draw it for a person) and this module
writes it in the format asked for:

- ``--format table`` (default): for a person. On a terminal, rich tables in colour; when standard
  output is not a terminal (a pipe, a file), the same tables as plain, unwrapped text (no colour,
  no box drawing, one line per row), so ``grep`` and ``awk`` work;
- ``--format json``: one JSON document, ``{"command": ..., "schema_version": 1, <fields>,
  <tables>}``, whose schema per command is documented in ``docs/cli.md`` and checked by
  ``tests/cli/test_formats.py``; numbers that are not finite (an ACAI of ``-inf``: rank
  deficient) are ``null``;
- ``--format csv``: the command's main table (:attr:`CommandOutput.csv_table`), a header of the
  JSON keys and one line per row (lists joined by spaces); a command without rows writes its
  fields as one row.

``--quiet`` writes nothing on standard output (and no progress bar): the exit status is the
answer. Errors always go to standard error as one line. Exit statuses (:data:`EXIT_CODES`): 0 ok,
1 error (bad input, a failed computation, an interrupted run), 2 usage (an unknown option, a
missing argument: click's), 3 a requirement not met (``certify --require``).
"""

from __future__ import annotations

import csv
import functools
import io
import json
import math
import sys
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, Literal, TypeVar, get_args

import click
from rich.console import Console
from rich.table import Table

F = TypeVar("F", bound=Callable[..., Any])

#: ``--format`` values.
Format = Literal["table", "json", "csv"]
FORMATS: tuple[str, ...] = get_args(Format)
#: Version of every command's JSON document (``schema_version``); a change of a documented key
#: that is not an addition raises it.
SCHEMA_VERSION = 1
#: The exit statuses of every command.
EXIT_CODES = {0: "ok", 1: "error (bad input, failed computation, interrupted)", 2: "usage (click)", 3: "requirement not met"}
EXIT_REQUIREMENT = 3


@dataclass
class Rows:
    """A table of a command's output: ``name`` is its JSON key, ``rows`` typed records (the JSON
    and CSV rows; keys with units, as the API's ``to_arrow()`` columns)."""

    name: str
    rows: Sequence[Mapping[str, Any]]
    columns: Sequence[str] | None = None

    def keys(self) -> list[str]:
        if self.columns is not None:
            return list(self.columns)
        return list(self.rows[0]) if self.rows else []


@dataclass
class CommandOutput:
    """What a command says: ``fields`` (JSON scalars and lists), ``tables`` (:class:`Rows`),
    ``csv_table`` (the name of the table ``--format csv`` writes; None: the fields as one row) and
    ``human``, which draws it for a person on an :class:`Output` (tables and lines)."""

    command: str
    fields: dict[str, Any] = field(default_factory=dict)
    tables: list[Rows] = field(default_factory=list)
    csv_table: str | None = None
    human: Callable[[Output], None] | None = None

    def document(self) -> dict[str, Any]:
        """The JSON document (non-finite numbers as null)."""
        out: dict[str, Any] = {"command": self.command, "schema_version": SCHEMA_VERSION, **self.fields}
        for table in self.tables:
            out[table.name] = [dict(row) for row in table.rows]
        finite: dict[str, Any] = _finite(out)
        return finite


def _finite(value: Any) -> Any:
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {str(k): _finite(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_finite(v) for v in value]
    if hasattr(value, "item") and not isinstance(value, (str, bytes)):  # numpy scalars
        return _finite(value.item())
    return value


def _csv_cell(value: Any) -> str:
    value = _finite(value)
    if value is None:
        return ""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, list):
        return " ".join(_csv_cell(v) for v in value)
    if isinstance(value, float):
        return repr(value)
    return str(value)


class Output:
    """Where a command writes: the format, quiet or not, and a console for the table format
    (rich on a terminal; plain and unwrapped otherwise)."""

    def __init__(self, format: Format = "table", *, quiet: bool = False, terminal: bool | None = None) -> None:
        self.format: Format = format
        self.quiet = quiet
        self.terminal = sys.stdout.isatty() if terminal is None else terminal
        if self.terminal:
            self.console = Console(highlight=False)
        else:
            # Not a terminal: no colour, no wrapping at 80 columns, no box drawing (see table()).
            self.console = Console(width=1_000_000, color_system=None, soft_wrap=True, highlight=False, emoji=False)

    @property
    def human(self) -> bool:
        """Whether text for a person is written (the table format, not quiet)."""
        return self.format == "table" and not self.quiet

    @property
    def progress(self) -> bool:
        """Whether progress bars are shown (not quiet)."""
        return not self.quiet

    def table(self, **options: Any) -> Table:
        """A rich table for this output: box drawing on a terminal only."""
        if not self.terminal:
            options["box"] = None
            options.setdefault("pad_edge", False)
        return Table(**options)

    def status(self, text: str) -> None:
        """Narration of long work (``flying 12 runs``): on standard error, like the progress
        bars, so it never mixes with the output; none when quiet."""
        if not self.quiet:
            click.echo(text, err=True)

    def print(self, *objects: Any, **options: Any) -> None:
        """Text for a person (the table format only)."""
        if self.human:
            options.setdefault("highlight", False)
            self.console.print(*objects, **options)

    def emit(self, result: CommandOutput) -> None:
        """Writes ``result`` in this output's format."""
        if self.quiet:
            return
        if self.format == "json":
            click.echo(json.dumps(result.document(), indent=2, allow_nan=False))
        elif self.format == "csv":
            click.echo(_csv(result), nl=False)
        elif result.human is not None:
            result.human(self)


def _csv(result: CommandOutput) -> str:
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    if result.csv_table is None:
        scalars = {k: v for k, v in result.fields.items()}
        writer.writerow(list(scalars))
        writer.writerow([_csv_cell(v) for v in scalars.values()])
        return buffer.getvalue()
    table = next(t for t in result.tables if t.name == result.csv_table)
    keys = table.keys()
    writer.writerow(keys)
    for row in table.rows:
        writer.writerow([_csv_cell(row.get(k)) for k in keys])
    return buffer.getvalue()


def output_options(command: F) -> F:
    """Adds ``--format`` and ``--quiet`` to a command and hands it an :class:`Output` as the
    keyword argument ``output``."""

    @click.option("--format", "output_format", type=click.Choice(FORMATS), default="table", show_default=True,
                  help="table: for a person (plain text when not a terminal); json: one document (docs/cli.md); csv: the main table.")
    @click.option("--quiet", "-q", is_flag=True, help="Write nothing on standard output (errors still go to standard error); the exit status is the answer.")
    @functools.wraps(command)
    def wrapper(*args: Any, output_format: Format, quiet: bool, **kwargs: Any) -> Any:
        return command(*args, output=Output(output_format, quiet=quiet), **kwargs)

    return wrapper  # type: ignore[return-value]


def records(table: Any) -> list[dict[str, Any]]:
    """The rows of a tabular result (anything with ``to_arrow()``) as JSON-ready records."""
    return [_finite(row) for row in table.to_arrow().to_pylist()]


__all__ = ["EXIT_CODES", "EXIT_REQUIREMENT", "FORMATS", "SCHEMA_VERSION", "CommandOutput", "Format", "Output", "Rows", "output_options", "records"]

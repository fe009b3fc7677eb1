"""The one report writer every paper feeds.

A paper contributes to the reproduce-all report (``rotorfault reproduce``) a
:class:`ReportSection` of printed numbers (:class:`~rotorfault.papers._numbers.PaperNumber`),
tables and figures: each paper module provides ``report_section(out, *, quick)``, which writes its
figures into the directory ``out`` and returns the section; the report imports the modules that
exist and shows a "not landed yet" section for those that do not. A paper's own report command
(``ftc-report``, ...) writes its directory through the same functions: :func:`check_report_directory`
before any work, :func:`report_directory` (built beside the final place, with ``manifest.json``,
swapped in when complete), :func:`csv_text` and :func:`markdown_table` for its tables."""

from __future__ import annotations

import contextlib
import csv
import io
import os
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Protocol

from ._numbers import PaperNumber


@dataclass(frozen=True)
class ReportFigure:
    """A figure file (name relative to the report directory) and its caption; ``small``: shown
    as a thumbnail in a grid (a click opens it full size), for series such as time histories."""

    file: str
    caption: str
    small: bool = False


@dataclass(frozen=True)
class ReportTable:
    """A table of text cells (the template escapes every cell)."""

    caption: str
    columns: tuple[str, ...]
    rows: tuple[tuple[str, ...], ...]


@dataclass
class ReportSection:
    """One paper's part of the report. ``landed`` False: the paper's reproduction is not in the
    package yet (``notes`` say what is missing); the section is shown, never hidden."""

    key: str
    title: str
    landed: bool = True
    numbers: list[PaperNumber] = field(default_factory=list)
    tables: list[ReportTable] = field(default_factory=list)
    figures: list[ReportFigure] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    #: Sub-sections (e.g. a paper's flights, which may land later than its equations).
    parts: list[ReportSection] = field(default_factory=list)
    #: The module and command that produce the section (shown in the page).
    source: str = ""
    run_time_s: float = 0.0


class SectionProvider(Protocol):
    def __call__(self, out: Path, *, quick: bool) -> ReportSection: ...


def markdown_table(lines: list[str]) -> tuple[tuple[str, ...], tuple[tuple[str, ...], ...]]:
    """Header and rows of a Markdown table a paper module prints (``| a | b |`` lines, the second
    the separator): one code path for its Markdown report and the report page."""
    cells = [tuple(c.strip() for c in line.strip().strip("|").split(" | ")) for line in lines]
    return cells[0], tuple(cells[2:])


def not_landed(key: str, title: str, module: str, what: str) -> ReportSection:
    """The section of a paper whose reproduction has not landed yet."""
    return ReportSection(
        key, title, landed=False, source=module,
        notes=[f"Not landed yet: {what} ({module} is not in this version of rotorfault)."],
    )


def package_version() -> str:
    """The installed rotorfault's version (``"unknown"`` from a bare source tree)."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("rotorfault")
    except PackageNotFoundError:  # pragma: no cover - running from a source tree
        return "unknown"


def check_report_directory(field_name: str, out_dir: str | os.PathLike[str], *, force: bool) -> Path:
    """Checks, before any work, that ``out_dir`` can take a report (new, empty, or with ``force``
    a previous report; never a directory holding other files)."""
    from .._util.output import check_output_directory

    return check_output_directory(field_name, out_dir, force=force)


@contextlib.contextmanager
def report_directory(out: Path, *, generator: str, command: str | None, default_command: str, **extra: Any) -> Iterator[Path]:
    """Yields a temporary directory to fill; when the block completes it gets ``manifest.json``
    (the files, ``generator``, ``command``, the version, ``extra``) and replaces ``out`` as a whole;
    on an error or interrupt ``out`` is left as it was. Call :func:`check_report_directory` first."""
    from .._util.output import output_directory

    manifest = {"generator": generator, "command": command or default_command, "version": package_version(), **extra}
    with output_directory(out, manifest) as tmp:
        yield tmp


def csv_text(rows: Sequence[dict[str, Any]], cell: Callable[[dict[str, Any], str], str] | None = None) -> str:
    """The rows as CSV text, one column per key of the first row (``cell(row, column)`` formats
    each value; by default ``None`` is empty)."""
    buffer = io.StringIO()
    writer = csv.DictWriter(buffer, fieldnames=list(rows[0]), lineterminator="\n")
    writer.writeheader()
    for row in rows:
        writer.writerow({column: ("" if row[column] is None else row[column]) if cell is None else cell(row, column) for column in row})
    return buffer.getvalue()


__all__ = [
    "ReportFigure",
    "ReportSection",
    "ReportTable",
    "SectionProvider",
    "check_report_directory",
    "csv_text",
    "markdown_table",
    "not_landed",
    "package_version",
    "report_directory",
]

"""The one report writer every paper feeds.

A paper contributes to the reproduce-all report (``rotorfault reproduce``) a
:class:`ReportSection` of printed numbers (:class:`~rotorfault.papers._numbers.PaperNumber`),
tables and figures: each paper module provides ``report_section(out, *, quick)``, which writes its
figures into the directory ``out`` and returns the section; the report imports the modules that
exist and shows a "not landed yet" section for those that do not.

Every report directory (``rotorfault reproduce``, and each paper's own command: ``ftc-report``,
``lanzon-report``, ``vpp-report``) is written by one writer, :func:`write_report_files`: the
directory claimed before any work (its lock held, an interrupted run's leftovers recovered, the
directory checked), the content built in a directory beside it, each text file written atomically,
``manifest.json`` added and the whole swapped in when complete. A paper hands it the content: its
figures drawn into the directory it is given and its text files (:class:`MarkdownText`, its
tables rendered by :func:`markdown_lines`; :class:`CsvTable`, columns named with their units;
:class:`TextFile`)."""

from __future__ import annotations

import contextlib
import csv
import io
import os
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Protocol

from ._numbers import PaperClaim, PaperNumber


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
    #: The paper's claims about its flights, each beside our measurement and verdict.
    claims: list[PaperClaim] = field(default_factory=list)
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


def markdown_lines(columns: Sequence[str], rows: Sequence[Sequence[str]]) -> list[str]:
    """A table of text cells as Markdown lines: the header, the separator, one line per row (the
    inverse of :func:`markdown_table`)."""
    return [_markdown_row(columns), "|" + "---|" * len(columns), *(_markdown_row(row) for row in rows)]


def _markdown_row(cells: Sequence[str]) -> str:
    return "| " + " | ".join(cells) + " |"


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


@dataclass(frozen=True)
class MarkdownText:
    """A Markdown file of a report directory: its ``lines`` (tables from :func:`markdown_lines`),
    written joined by newlines with a final newline."""

    file: str
    lines: tuple[str, ...]

    def text(self) -> str:
        return "\n".join(self.lines) + "\n"


@dataclass(frozen=True)
class CsvTable:
    """A table of a report directory as the CSV file ``file``: ``columns`` named with their units
    (``final_error_m``, ``window_tilt_deg``) and ``rows``, one value per column (``None`` is an
    empty cell; other values as the csv module writes them)."""

    file: str
    columns: tuple[str, ...]
    rows: tuple[tuple[Any, ...], ...]

    def __post_init__(self) -> None:
        for k, row in enumerate(self.rows):
            if len(row) != len(self.columns):
                raise ValueError(f"rows[{k}]: {len(row)} values for {len(self.columns)} columns in {self.file}")

    @classmethod
    def from_records(
        cls, file: str, records: Sequence[Mapping[str, Any]], cell: Callable[[Any, str], Any] | None = None
    ) -> CsvTable:
        """One column per key of the first record, one row per record (``cell(record, column)``
        formats each value; by default the value itself)."""
        columns = tuple(records[0])
        return cls(file, columns, tuple(tuple(r[c] if cell is None else cell(r, c) for c in columns) for r in records))

    def text(self) -> str:
        buffer = io.StringIO()
        writer = csv.writer(buffer, lineterminator="\n")
        writer.writerow(self.columns)
        writer.writerows(self.rows)
        return buffer.getvalue()


@dataclass(frozen=True)
class TextFile:
    """Any other text file of a report directory (the page, ``numbers.json``), as written."""

    file: str
    content: str

    def text(self) -> str:
        return self.content


#: A text file a report directory holds (written by :func:`write_report_files`).
ReportFile = MarkdownText | CsvTable | TextFile


def csv_text(rows: Sequence[dict[str, Any]], cell: Callable[[dict[str, Any], str], str] | None = None) -> str:
    """The rows as CSV text, one column per key of the first row (``cell(row, column)`` formats
    each value; by default ``None`` is empty): :meth:`CsvTable.text` of :meth:`CsvTable.from_records`."""
    return CsvTable.from_records("", rows, cell).text()


def write_report_files(
    out_dir: str | os.PathLike[str],
    content: Callable[[Path], Sequence[ReportFile]],
    *,
    field_name: str,
    force: bool,
    generator: str,
    command: str | None,
    default_command: str,
    **manifest: Any,
) -> Path:
    """The one writer of a report directory. Before any work: ``out_dir`` claimed (its lock held
    to the end, a second writer refused naming the first; an interrupted run's leftovers
    recovered) and checked (new, empty, or with ``force`` a previous report; never a directory
    holding other files; errors name ``field_name``). Then ``content(tmp)`` fills a directory built
    beside it (it draws its figures there) and returns its text files, each written atomically;
    ``manifest.json`` (the files, ``generator``, ``command`` or ``default_command``, the version,
    ``manifest``) is added and the directory swapped in for ``out_dir`` as a whole. On an error or
    interrupt ``out_dir`` is left as it was. Returns the directory's path."""
    from .._util.atomic import write_text
    from .._util.output import claim_output_directory

    with claim_output_directory(field_name, out_dir, force=force) as out:
        with report_directory(out, generator=generator, command=command, default_command=default_command, **manifest) as tmp:
            for item in content(tmp):
                write_text(tmp / item.file, item.text())
    return out


__all__ = [
    "CsvTable",
    "MarkdownText",
    "ReportFile",
    "ReportFigure",
    "ReportSection",
    "ReportTable",
    "SectionProvider",
    "TextFile",
    "check_report_directory",
    "csv_text",
    "markdown_lines",
    "markdown_table",
    "not_landed",
    "package_version",
    "report_directory",
    "write_report_files",
]

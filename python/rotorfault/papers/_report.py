"""What a paper contributes to the reproduce-all report (``rotorfault reproduce``): a
:class:`ReportSection` of printed numbers (:class:`~rotorfault.papers._numbers.PaperNumber`),
tables and figures. Each paper module provides ``report_section(out, *, quick)``, which writes
its figures into the directory ``out`` and returns the section; the report imports the modules
that exist and shows a "not landed yet" section for those that do not."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Protocol

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


__all__ = ["ReportFigure", "ReportSection", "ReportTable", "SectionProvider", "markdown_table", "not_landed"]

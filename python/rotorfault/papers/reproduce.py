"""``rotorfault reproduce``: every result of the four papers in one static report (``index.html``
plus figure files; no server, no network, opens from disk).

Each paper is a section provider, ``report_section(out, *, quick)`` in its module (:data:`PAPERS`):
the same functions the paper's CLI command and its tests call, so the report and the tests cannot
disagree. A paper whose module is not in the package yet gets a section that says so. The
decisions on the papers' gaps come from the README's table (:mod:`~rotorfault.papers.decisions`),
the performance figures from the benches' JSON (``rotorfault/papers/bench_results/*.json``,
package data written by ``python benches/<bench>.py --json PATH``: an installed package shows
them too). The HTML is rendered by Jinja2 with autoescaping: every name
and text from the data is escaped.
"""

from __future__ import annotations

import importlib
import json
import math
import os
import re
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ._numbers import KIND_DESCRIPTIONS, PaperClaim, PaperNumber, score
from ._report import ReportSection, SectionProvider, not_landed
from .decisions import Decision, decisions, source_root


@dataclass(frozen=True)
class Paper:
    """A paper of the report: its key, title, the module holding its ``report_section`` and what
    the section shows (for the "not landed yet" text)."""

    key: str
    title: str
    module: str
    what: str


#: The four papers, in the report's order.
PAPERS = (
    Paper("du", "Du et al.: controllability and the available control authority index (ACAI)", "rotorfault.papers.du",
          "Tables II and III, the failure tables and Fig. 4"),
    Paper("ke", "Ke et al.: uniform passive fault-tolerant control", "rotorfault.papers.ke",
          "Table II, the stability checks, the flights and the unit-sphere plot"),
    Paper("lanzon", "Lanzon et al.: flying a quadrotor on three rotors by letting it spin", "rotorfault.papers.lanzon_checks",
          "eq. (26), the loop shape and the flights"),
    Paper("wang", "Wang et al.: variable-pitch quadcopters", "rotorfault.papers.wang",
          "the trim numbers of Section 3.1, the controllability ranks of Sections 3.3/3.4 and the flights"),
)


#: Studies shown after the papers (same provider protocol); with ``providers`` given (tests), a
#: study absent from it is left out rather than computed.
STUDIES = (
    Paper("campaign", "The campaign that decides: which controller holds which failure", "rotorfault.papers.campaign",
          "the table vehicle x fault class x controller"),
)


def provider(paper: Paper) -> SectionProvider | None:
    """The paper's ``report_section``, or None when its module is not in the package (an import
    error inside an existing module is raised, not hidden)."""
    try:
        module = importlib.import_module(paper.module)
    except ModuleNotFoundError as exc:
        if exc.name is not None and paper.module.startswith(exc.name):
            return None
        raise
    found = getattr(module, "report_section", None)
    return found if callable(found) else None


# -- benchmarks ----------------------------------------------------------------------------------

BENCH_SCHEMA = "rotorfault-bench/1"


@dataclass(frozen=True)
class BenchResult:
    """One bench's JSON (see ``benches/_results.py``)."""

    file: str
    bench: str
    title: str
    command: str
    date: str
    machine: dict[str, Any]
    reduced: str | None
    figures: list[dict[str, Any]]


#: The committed bench results: package data, so an installed package (``pip install .``, the
#: wheel) shows the same Performance section as the source tree (benches/README.md refreshes them).
BENCH_RESULTS = "bench_results"


def default_bench_directory() -> Path | None:
    """The bench results that ship with the package (:data:`BENCH_RESULTS`), None if absent."""
    from importlib import resources

    found = resources.files("rotorfault.papers").joinpath(BENCH_RESULTS)
    path = Path(str(found))
    return path if path.is_dir() else None


def bench_results(directory: str | os.PathLike[str] | None) -> list[BenchResult]:
    """The bench results in ``directory`` (``*.json`` of schema ``rotorfault-bench/1``), sorted
    by file name; an unreadable or foreign file is a ``ValueError`` naming it."""
    if directory is None:
        return []
    d = Path(directory)
    if not d.is_dir():
        raise ValueError(f"benches: {str(d)!r} is not a directory")
    out = []
    for path in sorted(d.glob("*.json")):
        try:
            data = json.loads(path.read_text(encoding="utf-8"))
            out.append(_bench_result(path.name, data))
        except (ValueError, KeyError, TypeError, RecursionError, UnicodeDecodeError) as exc:
            raise ValueError(f"benches: {str(path)!r} is not a bench result ({exc})") from None
    return out


def _field(data: Any, key: str, kinds: tuple[type, ...], *, optional: bool = False, where: str = "") -> Any:
    """``data[key]`` of one of ``kinds`` (None allowed when ``optional``), naming the field."""
    if not isinstance(data, dict):
        raise TypeError(f"{where or 'the file'} must be a JSON object")
    if key not in data:
        if optional:
            return None
        raise KeyError(f"{where}{key} is missing")
    value = data[key]
    if value is None and optional:
        return None
    if isinstance(value, bool) and bool not in kinds or not isinstance(value, kinds):
        raise TypeError(f"{where}{key} must be {' or '.join(k.__name__ for k in kinds)}, got {type(value).__name__}")
    if isinstance(value, float) and not math.isfinite(value):
        raise ValueError(f"{where}{key} must be finite, got {value}")
    return value


def _bench_result(name: str, data: Any) -> BenchResult:
    """Every field the page shows, checked when the file is read (before the report's work), so a
    malformed file is a one-line error naming the field, never a crash after the long work."""
    if _field(data, "schema", (str,)) != BENCH_SCHEMA:
        raise ValueError(f"schema is {data.get('schema')!r}, expected {BENCH_SCHEMA!r}")
    text = {key: _field(data, key, (str,)) for key in ("bench", "title", "command", "date")}
    machine = _field(data, "machine", (dict,))
    for key in ("cpu", "system", "python", "rotorfault"):
        _field(machine, key, (str,), where="machine.")
    _field(machine, "cpus", (int,), where="machine.")
    _field(machine, "load_average_1min", (int, float), optional=True, where="machine.")
    figures = _field(data, "figures", (list,))
    for k, fig in enumerate(figures):
        where = f"figures[{k}]."
        _field(fig, "what", (str,), where=where)
        _field(fig, "unit", (str,), where=where)
        _field(fig, "value", (int, float), where=where)
        for key in ("baseline_value", "ratio"):
            _field(fig, key, (int, float), optional=True, where=where)
        for key in ("baseline", "target"):
            _field(fig, key, (str,), optional=True, where=where)
    return BenchResult(name, text["bench"], text["title"], text["command"], text["date"], dict(machine),
                       _field(data, "reduced", (str,), optional=True), list(figures))


def _number(value: float | None, unit: str = "") -> str:
    if value is None:
        return ""
    if abs(value) >= 1e5:
        text = f"{value:,.0f}" if abs(value) < 1e7 else f"{value / 1e6:,.2f} M"
    elif abs(value) >= 100:
        text = f"{value:,.0f}"
    else:
        text = f"{value:.3g}"
    return f"{text} {unit}".strip()


# -- rendering -----------------------------------------------------------------------------------


def score_text(section: ReportSection) -> str:
    """One line on a section's scoreboard (what ``rotorfault reproduce`` prints per paper): the
    reproduced numbers that pass, the rows shown beside them unscored, the flight claims
    confirmed, the parts not landed."""
    if not section.landed:
        return "not landed yet"
    parts = [section, *section.parts]
    board = score([n for part in parts for n in part.numbers])
    claims = [c for part in parts for c in part.claims]
    beside = board["input"] + board["consistency"] + board["unclassified"]
    text = f"{board['passed']} of {board['reproduced']} reproduced numbers pass" if board["reproduced"] else "no reproduced number scored"
    if beside:
        text += f" ({beside} input, consistency or unclassified rows beside them, not scored)"
    if claims:
        text += f"; {sum(c.status == 'confirmed' for c in claims)} of {len(claims)} flight claims confirmed"
    pending = [part.title for part in section.parts if not part.landed]
    if pending:
        text += f"; not landed yet: {', '.join(pending)}"
    return text


def verdict_legend() -> list[dict[str, str]]:
    """The flight verdicts and their thresholds, as the page states them
    (:data:`rotorfault.flight.outcomes.VERDICT_MEANINGS`)."""
    from ..flight.outcomes import VERDICT_MEANINGS

    return [{"verdict": k, "meaning": v} for k, v in VERDICT_MEANINGS.items()]


def _fmt(value: float) -> str:
    if value != value:  # nan
        return "nan"
    if value == 0:
        return "0"
    if abs(value) >= 1e4 or abs(value) < 1e-3:
        return f"{value:.6g}"
    return f"{value:.6g}"


def number_row(n: PaperNumber) -> dict[str, str]:
    """A row of a paper's numbers table as text. ``status`` is the pass/differs marker of a
    scored (``reproduced``) row; the other kinds show the comparison without a score."""
    return {"where": n.where, "quantity": n.quantity, "printed": _fmt(n.printed), "ours": _fmt(n.ours),
            "difference": f"{n.difference:+.2e}" if n.difference == n.difference else "nan",
            "tolerance": f"{n.tolerance:.1e}", "status": n.status, "note": n.note, "kind": n.kind_label,
            "scored": "scored" if n.scored else "not scored"}


def claim_row(c: PaperClaim) -> dict[str, str]:
    """A row of a paper's flight-claims table as text."""
    return {"where": c.where, "claim": c.claim, "measurement": c.measurement, "verdict": c.verdict,
            "status": c.status, "reason": c.reason}


_CODE = re.compile(r"`([^`]+)`")
_BOLD = re.compile(r"\*\*([^*]+)\*\*")


def inline_markdown(text: str) -> Any:
    """The README's inline Markdown (backticks, bold) as HTML, everything else escaped."""
    from markupsafe import Markup, escape

    html = str(escape(text))
    html = _CODE.sub(lambda m: f"<code>{m.group(1)}</code>", html)
    html = _BOLD.sub(lambda m: f"<strong>{m.group(1)}</strong>", html)
    return Markup(html)


#: Where a decision's code link points (README "Decisions on the paper's gaps", the report's note):
#: the file in the source tree the report was built from; else the installed file (the package's
#: own Python and presets); else, for files the wheel does not install (the Rust core), the file
#: in the repository at the installed version's tag ``v<version>`` when the package's metadata
#: names its repository (``Project-URL: Source``), or the path in that version's source as text.
LINK_RULE = (
    "Links: into the source tree this report was built from; from an installed package, to the installed file; "
    "files the package does not install (the Rust core) at tag v{version} of the repository when the package "
    "names one, else as their path in rotorfault {version}'s source (sdist, or the repository at that tag)."
)


def _repository_url() -> str | None:
    """The repository the package's metadata names (``Project-URL: Source, <url>``), if any."""
    from importlib.metadata import PackageNotFoundError, metadata

    try:
        urls = metadata("rotorfault").get_all("Project-URL") or []
    except PackageNotFoundError:  # pragma: no cover - neither installed nor a source tree
        return None
    for entry in urls:
        name, _, url = entry.partition(",")
        if name.strip().lower() in ("source", "repository") and url.strip():
            return str(url).strip().rstrip("/")
    return None


def _code_links(decision: Decision, out: Path, *, root: Path | None = None, version: str | None = None) -> list[dict[str, str]]:
    """Each code path of ``decision`` with its link (:data:`LINK_RULE`): ``href`` (relative to
    the report in a source tree, a ``file:`` URI of the installed file, a repository URL at the
    version's tag, or empty) and ``where`` (how to read the link)."""
    from ._report import package_version

    root = source_root() if root is None else root
    version = package_version() if version is None else version
    package = Path(__file__).resolve().parents[1]
    links = []
    for path in decision.code:
        if root is not None and (root / path).exists():
            links.append({"path": path, "href": Path(os.path.relpath(root / path, out.resolve())).as_posix(), "where": "source tree"})
            continue
        installed = package / path.removeprefix("python/rotorfault/") if path.startswith("python/rotorfault/") else None
        if installed is not None and installed.exists():
            links.append({"path": path, "href": installed.as_uri(), "where": f"installed rotorfault {version}"})
            continue
        repository = _repository_url()
        if repository is not None:
            links.append({"path": path, "href": f"{repository}/blob/v{version}/{path}", "where": f"repository at v{version}"})
        else:
            links.append({"path": path, "href": "", "where": f"rotorfault {version} source (not installed)"})
    return links


def render(
    sections: list[ReportSection],
    decision_rows: list[Decision],
    benches: list[BenchResult],
    *,
    out: Path,
    quick: bool,
    run_time_s: float,
    command: str,
    version: str,
    bench_directory: str,
) -> str:
    """The page (``index.html``) as text."""
    from jinja2 import Environment, FileSystemLoader, StrictUndefined

    env = Environment(loader=FileSystemLoader(Path(__file__).with_name("templates")), autoescape=True,
                      undefined=StrictUndefined, trim_blocks=True, lstrip_blocks=True)
    env.filters["md"] = inline_markdown
    env.filters["number"] = _number

    def flat(section: ReportSection) -> list[ReportSection]:
        return [section, *(p for part in section.parts for p in flat(part))]

    summary = []
    for s in sections:
        numbers = [n for part in flat(s) for n in part.numbers]
        claims = [c for part in flat(s) for c in part.claims]
        summary.append({"key": s.key, "title": s.title, "landed": s.landed and all(p.landed for p in flat(s)),
                        "partly": s.landed and not all(p.landed for p in flat(s)), **score(numbers),
                        "claims": len(claims), "confirmed": sum(c.status == "confirmed" for c in claims)})
    root = source_root()
    have = {b.bench for b in benches}
    missing_benches = [] if root is None else sorted(
        p.stem for p in (root / "benches").glob("*.py") if not p.name.startswith("_") and p.stem not in have)
    template = env.get_template("reproduce.html.j2")
    return template.render(
        sections=sections, summary=summary, number_row=number_row, claim_row=claim_row, kinds=KIND_DESCRIPTIONS,
        verdicts=verdict_legend(),
        decisions=[{"gap": d.gap, "decision": d.decision, "links": _code_links(d, out)} for d in decision_rows],
        link_rule=LINK_RULE.format(version=version),
        benches=benches, missing_benches=missing_benches, quick=quick, run_time_s=run_time_s, command=command, version=version,
        bench_directory=bench_directory, generated=time.strftime("%Y-%m-%d %H:%M:%S %Z"),
    )


def _shown_path(path: Path | None) -> str:
    """A path as the page shows it: relative to the source tree when inside it, the package's
    own results by their place in the package."""
    if path is None:
        return "none"
    root = source_root()
    if root is not None:
        try:
            return path.resolve().relative_to(root).as_posix()
        except ValueError:
            pass
    default = default_bench_directory()
    if default is not None and path.resolve() == default.resolve():
        return f"rotorfault/papers/{BENCH_RESULTS} (installed with the package: {path})"
    return str(path)


#: Schema of ``numbers.json``, the report's numbers and tables in a form a program compares.
NUMBERS_SCHEMA = "rotorfault-report-numbers/2"


def report_numbers(sections: list[ReportSection]) -> dict[str, Any]:
    """Every number (with its kind), flight claim and table cell of the report, by section (run
    times left out): what
    ``numbers.json`` holds, so that two installs' reports can be compared field by field (CI
    compares the README's main job, run without the test extras, with the test environment's)."""

    def flat(section: ReportSection) -> list[ReportSection]:
        return [section, *(p for part in section.parts for p in flat(part))]

    out: dict[str, Any] = {"schema": NUMBERS_SCHEMA, "sections": {}}
    for s in sections:
        for part in flat(s):
            out["sections"][part.key] = {
                "title": part.title,
                "landed": part.landed,
                "numbers": [{"where": n.where, "quantity": n.quantity, "printed": n.printed, "ours": n.ours,
                             "tolerance": n.tolerance, "status": n.status, "kind": n.kind} for n in part.numbers],
                "claims": [{"where": c.where, "claim": c.claim, "measurement": c.measurement, "verdict": c.verdict,
                            "status": c.status, "reason": c.reason} for c in part.claims],
                "tables": [{"caption": t.caption, "columns": list(t.columns), "rows": [list(r) for r in t.rows]}
                           for t in part.tables],
            }
    return out


@dataclass
class ReproduceResult:
    path: Path
    sections: list[ReportSection] = field(default_factory=list)
    run_time_s: float = 0.0


def write_reproduce(
    out_dir: str | os.PathLike[str],
    *,
    quick: bool = False,
    force: bool = False,
    command: str | None = None,
    bench_directory: str | os.PathLike[str] | None = None,
    providers: dict[str, SectionProvider | None] | None = None,
    progress: Any = None,
) -> ReproduceResult:
    """Writes the report directory ``out_dir`` (``index.html``, the figures, ``manifest.json``),
    built beside it and swapped in when complete; an existing report is replaced only with
    ``force``, a directory that is not a report never. ``bench_directory`` defaults to the source
    results shipped with the package (:func:`default_bench_directory`); ``providers`` overrides the section providers by paper key (None:
    not landed), for tests. ``progress(text)`` is called before each section."""
    from ._report import TextFile, check_report_directory, package_version, write_report_files

    # The directory and the bench files are checked before any work (the writer claims the
    # directory again, holding its lock to the end).
    out = check_report_directory("out", out_dir, force=force)
    if bench_directory is None:  # the source tree's results, when there are any
        default = default_bench_directory()
        benches_dir = default if default is not None and default.is_dir() else None
    else:
        benches_dir = Path(bench_directory)
    benches = bench_results(benches_dir)
    decision_rows = decisions()
    start = time.perf_counter()
    result = ReproduceResult(out / "index.html")
    shown_command = command or "rotorfault.papers.reproduce.write_reproduce"

    def add_section(entry: Paper, chosen: SectionProvider | None, tmp: Path) -> None:
        if progress is not None:
            progress(f"{entry.key}: {'computing' if chosen is not None else 'not landed yet'}")
        if chosen is None:
            result.sections.append(not_landed(entry.key, entry.title, entry.module, entry.what))
        else:
            result.sections.append(chosen(tmp, quick=quick))

    def content(tmp: Path) -> list[TextFile]:
        for paper in PAPERS:
            add_section(paper, providers[paper.key] if providers is not None and paper.key in providers else provider(paper), tmp)
        for study in STUDIES:
            if providers is not None and study.key not in providers:
                continue
            add_section(study, providers[study.key] if providers is not None else provider(study), tmp)
        result.run_time_s = time.perf_counter() - start
        html = render(result.sections, decision_rows, benches, out=out, quick=quick, run_time_s=result.run_time_s,
                      command=shown_command, version=package_version(),
                      bench_directory=_shown_path(benches_dir))
        return [TextFile("index.html", html),
                TextFile("numbers.json", json.dumps(report_numbers(result.sections), indent=1, allow_nan=True) + "\n")]

    write_report_files(out, content, field_name="out", force=force,
                       generator="rotorfault reproduce (rotorfault.papers.reproduce.write_reproduce)", command=command,
                       default_command=shown_command, quick=quick)
    return result


__all__ = ["BENCH_RESULTS", "BENCH_SCHEMA", "LINK_RULE", "NUMBERS_SCHEMA", "PAPERS", "STUDIES", "BenchResult", "Paper", "ReproduceResult", "bench_results",
           "claim_row", "default_bench_directory", "inline_markdown", "number_row", "provider", "render", "report_numbers", "score", "score_text",
           "verdict_legend", "write_reproduce"]

"""``rotorfault reproduce``: the printed numbers it shows (the same functions the paper tests
call), the decisions table read from the README with its code links, the bench results read from
JSON, the "not landed yet" sections, escaping, and the output-directory rules. The page itself is
checked in a browser in ``test_report_browser.py``."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from rotorfault._util.lock import is_lock_file
from rotorfault.papers import du as du_paper
from rotorfault.papers import ke as ke_paper
from rotorfault.papers import reproduce
from rotorfault.papers._numbers import PaperClaim, PaperNumber
from rotorfault.papers._report import ReportFigure, ReportSection, ReportTable
from rotorfault.papers.decisions import DECISION_CODE, decisions, source_root

ROOT = Path(__file__).resolve().parents[2]

# Ke Table II as printed (typed again here, independently of rotorfault.papers.ke).
KE_PRINTED = [
    (1, 0.625, 1), (1, 0.25, 1), (0.1718, 0.644, 0.7592), (0.1, 0.025, 0.1), (1, 0, 0.5), (0.5, 0, 0.25),
    (0.5, 0, 1), (1, 0, 0.5), (1, 0, 0.5), (0.75, 0, 0), (0.75, 0, 0),
]


def test_ke_table_ii_numbers_are_the_printed_ones_and_all_pass() -> None:
    numbers = ke_paper.printed_numbers()
    assert len(numbers) == 33
    assert [n.printed for n in numbers] == [float(v) for row in KE_PRINTED for v in sorted(row)]
    assert all(n.tolerance == 0.5e-4 and n.where == "Table II" for n in numbers)
    assert all(n.status == "pass" for n in numbers), [n for n in numbers if n.status != "pass"]


def test_du_numbers_cover_tables_ii_and_iii() -> None:
    numbers = du_paper.printed_numbers()
    assert len(numbers) == 14
    # Table III's zeros for rotors 5 and 6 pass as printed (eq. (13)) and carry the note why they mislead.
    noted = [n.quantity for n in numbers if n.note]
    assert noted == ["ACAI eq13, hexa-ppnnpn, rotor 5 failed", "ACAI eq13, hexa-ppnnpn, rotor 6 failed"]
    assert all(n.status == "pass" for n in numbers)


def _readme_decision_rows() -> int:
    text = (ROOT / "README.md").read_text(encoding="utf-8").split("## Decisions on the paper's gaps", 1)[1]
    text = text.split("\n## ", 1)[0]
    return sum(1 for line in text.splitlines() if line.startswith("| ")) - 1  # minus the header row


def test_decisions_are_the_readme_table_and_every_row_links_to_existing_code() -> None:
    rows = decisions()
    assert len(rows) == _readme_decision_rows()
    assert rows[0].gap == "Du uses `+-10^6` for infinity"
    # A decision quoting `|x_i|` stays one cell.
    noise = next(d for d in rows if d.gap == 'Wang\'s "15 dB SNR noise"')
    assert "`10^(-SNR/20) |x_i|`" in noise.decision
    missing = [d.gap for d in rows if not d.code]
    assert not missing, f"README decisions without a code link in rotorfault.papers.decisions.DECISION_CODE: {missing}"
    stale = sorted(set(DECISION_CODE) - {d.gap for d in rows})
    assert not stale, f"DECISION_CODE names gaps the README no longer has: {stale}"
    for d in rows:
        for path in d.code:
            assert (ROOT / path).exists(), (d.gap, path)


def test_decisions_from_the_package_metadata_readme_parse_the_same(monkeypatch: pytest.MonkeyPatch) -> None:
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    assert decisions(text) == decisions()
    with pytest.raises(ValueError, match="Decisions on the paper's gaps"):
        decisions("# no such section\n")


def _bench(tmp: Path, name: str, **changes: object) -> None:
    record = {"schema": "rotorfault-bench/1", "bench": name, "title": "t <b>", "command": "python benches/x.py",
              "date": "2026-01-01T00:00:00+00:00", "machine": {"cpu": "cpu", "cpus": 2, "system": "Linux",
              "python": "3.11", "rotorfault": "0", "load_average_1min": 1.0}, "reduced": None,
              "figures": [{"what": "w", "value": 1e6, "unit": "steps/s", "baseline": "b", "baseline_value": 1e3,
                           "ratio": 1000.0, "target": ">= 1"}]}
    record.update(changes)
    (tmp / f"{name}.json").write_text(json.dumps(record), encoding="utf-8")


def test_bench_results_are_read_and_checked(tmp_path: Path) -> None:
    _bench(tmp_path, "b1")
    _bench(tmp_path, "b2", reduced="10 runs")
    got = reproduce.bench_results(tmp_path)
    assert [b.bench for b in got] == ["b1", "b2"] and got[1].reduced == "10 runs"
    _bench(tmp_path, "b3", schema="other")
    with pytest.raises(ValueError, match=r"benches: .*b3\.json.* not a bench result"):
        reproduce.bench_results(tmp_path)
    with pytest.raises(ValueError, match="benches: .* is not a directory"):
        reproduce.bench_results(tmp_path / "nope")


def test_committed_bench_results_are_readable() -> None:
    # The default is the installed package's own copy (editable or not), which ships the committed files.
    installed = reproduce.default_bench_directory()
    assert installed is not None and installed == Path(reproduce.__file__).resolve().parent / "bench_results"
    committed = ROOT / "python" / "rotorfault" / "papers" / "bench_results"
    shipped = {p.name for p in installed.glob("*.json")}
    assert shipped == {p.name for p in committed.glob("*.json")}
    got = reproduce.bench_results(committed)
    assert {b.bench for b in got} >= {"acai_grid", "allocation_clarabel", "ftc_batch", "startup", "deciding_campaign"}
    for b in got:
        assert b.figures and b.machine["cpus"] >= 1 and b.date


def _fake(key: str, title: str) -> reproduce.SectionProvider:
    def provide(out: Path, *, quick: bool) -> ReportSection:
        from rotorfault.plotting.style import new_figure, save_figure

        fig = new_figure(figsize=(2, 1))
        fig.add_subplot().plot([0, 1], [0, 1])
        save_figure(fig, out / f"{key}.png")
        return ReportSection(
            key, title,
            numbers=[PaperNumber("P", "T1", "<img src=x onerror=alert(1)>", 1.0, 1.0, 0.1, kind="reproduced"),
                     PaperNumber("P", "T1", "q2", 1.0, 2.0, 0.1, "a note", kind="reproduced"),
                     PaperNumber("P", "T1", "an input", 3.0, 3.0, 0.1, kind="input"),
                     PaperNumber("P", "T1", "not yet classified", 3.0, 4.0, 0.1)],
            claims=[PaperClaim("P", "Sec. 1", "<b>it flies</b>", "it flew", "holds", "confirmed", "held")],
            tables=[ReportTable("<script>alert(1)</script>", ("a", "b"), (("<i>x</i>", "y"),))],
            figures=[ReportFigure(f"{key}.png", "a figure")],
        )

    return provide


def test_sections_render_landed_and_not_landed_and_escape_names(tmp_path: Path) -> None:
    out = tmp_path / "report"
    fakes = {"du": _fake("du", "Du & <Co>"), "ke": None, "lanzon": None, "wang": _fake("wang", "Wang")}
    result = reproduce.write_reproduce(out, quick=True, providers=fakes)
    html = (out / "index.html").read_text(encoding="utf-8")
    assert [s.landed for s in result.sections] == [True, False, False, True]
    assert html.count("Not landed yet") == 2 and "rotorfault.papers.ke" in html
    assert "Du &amp; &lt;Co&gt;" in html
    assert "<script>alert" not in html and "&lt;script&gt;alert(1)&lt;/script&gt;" in html
    assert "<img src=x" not in html and "<i>x</i>" not in html
    # Only reproduced rows carry the pass/differs marker; the other kinds are shown unscored.
    assert html.count('<td class="pass">pass</td>') == 2 and html.count('<td class="differs">differs</td>') == 2
    assert html.count('<td class="unscored">') == 4
    assert '<td class="kind">input</td>' in html and '<td class="kind">not classified</td>' in html
    summary = html.split('id="summary"')[1].split("</table>")[0]
    assert summary.count('<td class="num">2</td><td class="num">1</td><td class="num">1</td>') == 2  # 2 scored: 1 pass, 1 differs
    assert "&lt;b&gt;it flies&lt;/b&gt;" in html and 'id="du-claims"' in html
    assert 'id="verdicts"' in html and "holds" in html.split('id="verdicts"')[1].split("</ul>")[0]
    numbers = json.loads((out / "numbers.json").read_text(encoding="utf-8"))
    assert [n["kind"] for n in numbers["sections"]["du"]["numbers"]] == ["reproduced", "reproduced", "input", None]
    assert numbers["sections"]["du"]["claims"][0]["status"] == "confirmed"
    manifest = json.loads((out / "manifest.json").read_text(encoding="utf-8"))
    assert set(manifest["outputs"]) == {"index.html", "numbers.json", "du.png", "wang.png"} and manifest["quick"] is True
    # The decisions table: one row per README decision, linked to the files.
    assert len(re.findall(r"<tr><td>", html.split('id="decisions-table"')[1].split("</table>")[0])) == len(decisions())
    if source_root() is not None:  # from a source tree the links point into it, relative to the report
        hrefs = re.findall(r'<a href="([^"]+)" title="source tree"><code>', html.split('id="decisions-table"')[1])
        assert hrefs and all((out / h).resolve().exists() for h in hrefs)


def test_a_report_is_not_overwritten_without_force(tmp_path: Path) -> None:
    out = tmp_path / "report"
    fakes: dict[str, reproduce.SectionProvider | None] = {"du": None, "ke": None, "lanzon": None, "wang": None}
    reproduce.write_reproduce(out, providers=fakes)
    with pytest.raises(ValueError, match="pass --force"):
        reproduce.write_reproduce(out, providers=fakes)
    reproduce.write_reproduce(out, providers=fakes, force=True)
    (tmp_path / "other").mkdir()
    (tmp_path / "other" / "notes.txt").write_text("mine")
    with pytest.raises(ValueError, match="not a rotorfault output"):
        reproduce.write_reproduce(tmp_path / "other", providers=fakes, force=True)


def test_a_failing_section_leaves_the_previous_report(tmp_path: Path) -> None:
    out = tmp_path / "report"
    fakes: dict[str, reproduce.SectionProvider | None] = {"du": None, "ke": None, "lanzon": None, "wang": None}
    reproduce.write_reproduce(out, providers=fakes)
    before = (out / "index.html").read_text(encoding="utf-8")

    def broken(out_: Path, *, quick: bool) -> ReportSection:
        raise RuntimeError("boom")

    with pytest.raises(RuntimeError, match="boom"):
        reproduce.write_reproduce(out, providers={**fakes, "ke": broken}, force=True)
    assert (out / "index.html").read_text(encoding="utf-8") == before
    assert sorted(p.name for p in tmp_path.iterdir() if not is_lock_file(p.name)) == ["report"]


def test_missing_paper_modules_are_not_landed_and_others_provide() -> None:
    papers = {p.key: p for p in reproduce.PAPERS}
    assert reproduce.provider(papers["du"]) is du_paper.report_section
    assert reproduce.provider(reproduce.Paper("x", "X", "rotorfault.papers.no_such_paper", "it")) is None


def test_readme_main_job_is_the_report_and_links_its_screenshot() -> None:
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    first = re.search(r"```bash\n(.*?)\n```", text, re.S)
    assert first is not None and first.group(1) == "pip install . && rotorfault reproduce --quick --out report/"
    assert "(docs/report.png)" in text
    png = ROOT / "docs" / "report.png"
    assert png.is_file() and png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_cli_checks_the_output_directory_before_computing(tmp_path: Path) -> None:
    from click.testing import CliRunner

    from rotorfault.cli import cli

    runner = CliRunner()
    missing = runner.invoke(cli, ["reproduce", "--quick", "--out", str(tmp_path / "no" / "report")])
    assert missing.exit_code == 1 and "out: directory" in missing.output and "does not exist" in missing.output
    out = tmp_path / "report"
    reproduce.write_reproduce(out, providers={"du": None, "ke": None, "lanzon": None, "wang": None})
    again = runner.invoke(cli, ["reproduce", "--quick", "--out", str(out)])
    assert again.exit_code == 1 and "pass --force" in again.output
    bad_benches = runner.invoke(cli, ["reproduce", "--quick", "--out", str(tmp_path / "r2"), "--benches", str(tmp_path / "nope")])
    assert bad_benches.exit_code == 1 and "benches:" in bad_benches.output


def test_decision_links_outside_a_source_tree_point_to_the_installed_file_or_the_version(tmp_path: Path,
                                                                                        monkeypatch: pytest.MonkeyPatch) -> None:
    """Issue 28: from an installed package the links must not point at files it does not have.
    A Python file or preset links to the installed file (it exists); a Rust file, which the wheel
    does not install, shows its path in that version's source, or the repository at tag
    v<version> when the package's metadata names one."""
    decision = next(d for d in decisions() if d.gap == "Wang's design, frames and u4")
    links = reproduce._code_links(decision, tmp_path, root=tmp_path, version="9.9.9")
    by_path = {link["path"]: link for link in links}
    wang = by_path["python/rotorfault/papers/wang.py"]
    assert wang["href"].startswith("file://") and wang["where"] == "installed rotorfault 9.9.9"
    monkeypatch.setattr(reproduce, "_repository_url", lambda: None)
    rust = {link["path"]: link for link in reproduce._code_links(decision, tmp_path, root=tmp_path, version="9.9.9")}[
        "crates/rfcore/src/flight/actuator.rs"]
    assert rust["href"] == "" and rust["where"] == "rotorfault 9.9.9 source (not installed)"
    monkeypatch.setattr(reproduce, "_repository_url", lambda: "https://example.org/rotorfault")
    rust = {link["path"]: link for link in reproduce._code_links(decision, tmp_path, root=tmp_path, version="9.9.9")}[
        "crates/rfcore/src/flight/actuator.rs"]
    assert rust["href"] == "https://example.org/rotorfault/blob/v9.9.9/crates/rfcore/src/flight/actuator.rs"
    assert "9.9.9" in reproduce.LINK_RULE.format(version="9.9.9")


def test_the_bench_results_ship_with_the_package() -> None:
    """The Performance section's results are package data (issue 28: after ``pip install .`` the
    section was empty): the default directory is inside the package, and the wheel test checks
    that the built wheel carries it."""
    import rotorfault

    directory = reproduce.default_bench_directory()
    assert directory is not None and directory.is_relative_to(Path(rotorfault.__file__).parent)
    assert len(reproduce.bench_results(directory)) >= 5


def test_the_score_line_counts_only_reproduced_rows() -> None:
    """What ``rotorfault reproduce`` prints per paper: only reproduced rows are counted as passing
    or not; inputs, consistency checks and unclassified rows are said to be beside them."""
    from rotorfault.papers._numbers import PaperClaim, PaperNumber
    from rotorfault.papers._report import ReportSection

    rows = [PaperNumber("P", "T", "a", 1.0, 1.0, 0.1, kind="reproduced"), PaperNumber("P", "T", "b", 1.0, 2.0, 0.1, kind="reproduced"),
            PaperNumber("P", "T", "c", 1.0, 1.0, 0.1, kind="input"), PaperNumber("P", "T", "d", 1.0, 1.0, 0.1)]
    claim = PaperClaim("P", "w", "c", "m", "drifts", "not confirmed", "r")
    section = ReportSection("p", "P", numbers=rows, claims=[claim], parts=[ReportSection("q", "flights", landed=False)])
    assert reproduce.score_text(section) == (
        "1 of 2 reproduced numbers pass (2 input, consistency or unclassified rows beside them, not scored); "
        "0 of 1 flight claims confirmed; not landed yet: flights")
    assert reproduce.score_text(ReportSection("p", "P", numbers=rows[3:])) == (
        "no reproduced number scored (1 input, consistency or unclassified rows beside them, not scored)")
    assert reproduce.score_text(ReportSection("p", "P", landed=False)) == "not landed yet"

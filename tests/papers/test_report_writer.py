"""The one report writer every paper feeds (issue 26): ``papers/_report.write_report_files`` claims
the directory (its lock, the checks) before the paper's content is computed, writes the files the
paper hands it, and leaves the previous report as it was when the content fails; the tables a
paper hands it render as before (Markdown lines, CSV as the csv module writes dicts)."""

from __future__ import annotations

import csv
import io
import json
import subprocess
import sys
from pathlib import Path

import pytest

from rotorfault._util.lock import OutputInUse, is_lock_file
from rotorfault.papers._report import CsvTable, MarkdownText, TextFile, markdown_lines, markdown_table, write_report_files

HOLDER = """
import sys, time
from rotorfault._util.lock import output_lock
with output_lock("out", sys.argv[1]):
    print("held", flush=True)
    time.sleep(600)
"""


def _files(tmp: Path) -> list[MarkdownText | CsvTable | TextFile]:
    (tmp / "figure.png").write_bytes(b"\x89PNG")
    return [MarkdownText("r.md", ("# title", "", *markdown_lines(("a (m)", "b"), [("1.0", ""), ("x", "y")]))),
            CsvTable("r.csv", ("a_m", "b"), ((1.5, None), (True, "q,r"))), TextFile("r.json", '{"k": 1}\n')]


def _write(out: Path, content: object, *, force: bool = False) -> Path:
    return write_report_files(out, content, field_name="out_dir", force=force, generator="test", command=None,  # type: ignore[arg-type]
                              default_command="test", extra=3)


def test_the_writer_writes_what_the_paper_hands_it(tmp_path: Path) -> None:
    out = _write(tmp_path / "report", _files)
    assert (out / "r.md").read_text(encoding="utf-8") == "# title\n\n| a (m) | b |\n|---|---|\n| 1.0 |  |\n| x | y |\n"
    assert (out / "r.csv").read_text(encoding="utf-8") == 'a_m,b\n1.5,\nTrue,"q,r"\n'
    assert (out / "r.json").read_text(encoding="utf-8") == '{"k": 1}\n'
    manifest = json.loads((out / "manifest.json").read_text(encoding="utf-8"))
    assert manifest["outputs"] == ["figure.png", "r.csv", "r.json", "r.md"]
    assert manifest["generator"] == "test" and manifest["command"] == "test" and manifest["extra"] == 3 and "version" in manifest
    # An existing report is replaced only with force; the refusal comes before the content runs.
    ran = []
    with pytest.raises(ValueError, match="out_dir: .* holds a previous output; pass --force"):
        _write(out, lambda tmp: ran.append(tmp) or [])
    assert ran == []


def test_a_failing_content_leaves_the_previous_report_and_no_temporary_directory(tmp_path: Path) -> None:
    out = _write(tmp_path / "report", _files)
    before = {p.name: p.read_bytes() for p in out.iterdir()}

    def broken(tmp: Path) -> list[TextFile]:
        (tmp / "half.png").write_bytes(b"half")
        raise ValueError("runs: nothing to report")

    with pytest.raises(ValueError, match="runs: nothing to report"):
        _write(out, broken, force=True)
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before
    assert [p.name for p in tmp_path.iterdir() if not is_lock_file(p.name)] == ["report"]


def test_a_held_output_is_refused_before_the_content_runs(tmp_path: Path) -> None:
    out = tmp_path / "report"
    proc = subprocess.Popen([sys.executable, "-c", HOLDER, str(out)], stdout=subprocess.PIPE, text=True)
    try:
        assert proc.stdout is not None and proc.stdout.readline().strip() == "held"
        ran = []
        with pytest.raises(OutputInUse, match=f"out_dir: .*process {proc.pid}"):
            _write(out, lambda tmp: ran.append(tmp) or [])
        assert ran == [] and not out.exists()
    finally:
        proc.kill()
        proc.wait(timeout=30)
        if proc.stdout is not None:
            proc.stdout.close()


def test_tables_render_as_the_papers_wrote_them() -> None:
    # Markdown: the inverse of the report page's parser.
    columns, rows = ("scenario", "final error (m)", "verdict"), (("1", "", "holds"), ("2", "0.125", "lost"))
    assert markdown_table(markdown_lines(columns, rows)) == (columns, rows)
    # CSV: what csv.DictWriter wrote for the same records (None empty, floats and bools as csv writes them).
    records = [{"run": 0, "error_m": 0.1 + 0.2, "lost": False, "note": None}, {"run": 1, "error_m": float("nan"), "lost": True, "note": 'a "b"'}]
    buffer = io.StringIO()
    writer = csv.DictWriter(buffer, fieldnames=list(records[0]), lineterminator="\n")
    writer.writeheader()
    writer.writerows({k: ("" if v is None else v) for k, v in r.items()} for r in records)
    assert CsvTable.from_records("t.csv", records).text() == buffer.getvalue()
    with pytest.raises(ValueError, match=r"rows\[0\]: 1 values for 2 columns in t.csv"):
        CsvTable("t.csv", ("a", "b"), (("x",),))

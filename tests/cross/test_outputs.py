"""The user's files (issue 21, items 5, 7, 8, 11): outputs are checked before the computation,
written under a temporary name and renamed when complete, a report directory swapped in as one
unit with a manifest; existing outputs are replaced only with --force; an interrupted report
(SIGINT, SIGTERM) leaves the previous one intact; bad input gives one-line errors naming the file
and the key; the FTC table fits 80 columns."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from click.testing import CliRunner

from rotorfault._util.lock import is_lock_file
from rotorfault.cli import cli

QUICK = ["--laws", "feedforward", "--scenarios", "fault-free,one-failure"]


def run(*args: str, width: int = 200) -> tuple[int, str, str]:
    result = CliRunner().invoke(cli, list(args), terminal_width=width)
    return result.exit_code, result.stdout, result.stderr


def one_line_error(code: int, out: str, err: str, *fragments: str) -> None:
    assert code == 1, out
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err + out, err
    for fragment in fragments:
        assert fragment in err, err


def snapshot(directory: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(directory.iterdir())}


def test_simulate_refuses_empty_runs_and_faults_outside_the_run(tmp_path: Path) -> None:
    """Item 5."""
    cases = {
        'airframe = "quad-x"\ndt_s = 100\nduration_s = 10\n': "duration_s: must be at least one control period",
        'airframe = "quad-x"\nduration_s = 10\n[[fault]]\nrotor = 1\ntime_s = 20\n': "fault[0].time_s: must lie in [0, duration_s)",
        'airframe = "quad-x"\nduration_s = 10\n[[fault]]\nrotor = 1\ntime_s = -1\n': "fault[0].time_s: must lie in [0, duration_s)",
        'airframe = "quad-x"\nduration_s = 1e12\n': "duration_s, dt_s:",
    }
    for k, (text, message) in enumerate(cases.items()):
        path = tmp_path / f"s{k}.toml"
        path.write_text(text)
        png = tmp_path / f"s{k}.png"
        one_line_error(*run("simulate", str(path), "--plot", str(png)), f"s{k}.toml: ", message)
        assert not png.exists()


def test_bad_files_name_the_file(tmp_path: Path) -> None:
    """Item 8: missing, binary and deeply nested files give one line naming the file."""
    deep = tmp_path / "deep.toml"
    deep.write_text('airframe = "quad-x"\nx = ' + "[" * 600 + "]" * 600 + "\n")
    one_line_error(*run("simulate", str(deep)), "deep.toml: nested too deeply")
    binary = tmp_path / "binary.toml"
    binary.write_bytes(bytes(range(256)) * 4)
    one_line_error(*run("simulate", str(binary)), "binary.toml: not UTF-8 text")
    one_line_error(*run("simulate", str(tmp_path / "missing.toml")), "scenario_file: ", "missing.toml")
    one_line_error(*run("acai", "--airframe", str(binary)), "binary.toml")


def test_plot_paths_are_checked_before_the_computation(tmp_path: Path) -> None:
    """Item 8: no extension, a missing directory and an existing file (without --force) are
    refused at once; with --force the file is replaced."""
    one_line_error(*run("scan", "-a", "hexa-pnpnpn", "--plot", str(tmp_path / "noext")), "plot: the file name must end in .png")
    assert not list(tmp_path.iterdir())
    one_line_error(*run("scan", "-a", "hexa-pnpnpn", "--plot", str(tmp_path / "no" / "fig.png")), "plot: directory")
    png = tmp_path / "fig.png"
    png.write_bytes(b"precious")
    started = time.perf_counter()
    one_line_error(*run("scan", "-a", "hexa-pnpnpn", "--step", "0.5", "--plot", str(png)), "plot: ", "exists; pass --force")
    assert png.read_bytes() == b"precious"
    code, out, err = run("scan", "-a", "hexa-pnpnpn", "--step", "0.5", "--plot", str(png), "--force")
    assert code == 0, err
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["fig.png"]  # no temporary file left
    example = Path(__file__).resolve().parents[2] / "examples" / "quad-x-rotor-failure.toml"
    one_line_error(*run("simulate", str(example), "--plot", str(png)), "exists; pass --force")
    assert time.perf_counter() - started < 30


def test_scan_grid_size_is_checked_before_allocating() -> None:
    """Item 8: --step 1e-9 used to allocate ~8 GB before the limit error; measured < 1 s now
    (bound 5 s on a shared machine)."""
    started = time.perf_counter()
    one_line_error(*run("scan", "-a", "hexa-pnpnpn", "--step", "1e-9"), "exceed the in-memory limit")
    assert time.perf_counter() - started < 5.0


def test_ftc_report_refuses_bad_laws_without_touching_the_report(tmp_path: Path) -> None:
    """Item 7: --laws "" used to truncate the CSV and end in an IndexError."""
    out = tmp_path / "report"
    code, _, err = run("ftc-report", "--out", str(out), *QUICK, "--no-figures")
    assert code == 0, err
    before = snapshot(out)
    assert json.loads(before["manifest.json"])["outputs"] == ["ftc-report.csv", "ftc-report.md"]
    for laws in ("", " , ", "magic"):
        code, o, e = run("ftc-report", "--out", str(out), "--laws", laws, "--force")
        one_line_error(code, o, e, "law")
    one_line_error(*run("ftc-report", "--out", str(out), *QUICK), "holds a previous output; pass --force")
    assert snapshot(out) == before
    # A directory holding anything else is never replaced, not even with --force.
    other = tmp_path / "mine"
    other.mkdir()
    (other / "thesis.tex").write_text("keep")
    one_line_error(*run("ftc-report", "--out", str(other), *QUICK, "--force"), "not a rotorfault output")
    assert (other / "thesis.tex").read_text() == "keep"


def test_no_figures_leaves_no_stale_figures(tmp_path: Path) -> None:
    out = tmp_path / "report"
    code, _, err = run("ftc-report", "--out", str(out), *QUICK)
    assert code == 0, err
    assert (out / "one-failure.png").exists() and (out / "primary-axis.png").exists()
    code, _, err = run("ftc-report", "--out", str(out), *QUICK, "--no-figures", "--force")
    assert code == 0, err
    assert sorted(p.name for p in out.iterdir()) == ["ftc-report.csv", "ftc-report.md", "manifest.json"]
    assert sorted(p.name for p in tmp_path.iterdir() if not is_lock_file(p.name)) == ["report"]  # no temporary directory left


def _report_command(out: Path, *extra: str) -> list[str]:
    return [sys.executable, "-m", "rotorfault", "ftc-report", "--out", str(out), *extra]


# Each signal once and each stage once (the handler is the same for both signals; every case
# flies a whole report, so the full cross product doubled the cost without a new path).
@pytest.mark.parametrize(("signum", "marker"), [(signal.SIGINT, "writing the report"), (signal.SIGTERM, "flying")])
def test_an_interrupted_report_leaves_the_previous_one_intact(tmp_path: Path, signum: int, marker: str) -> None:
    """Item 7: the previous report (table only) is intact after a signal while flying or while
    the figures are written; or, if the signal came too late, the new report is complete."""
    out = tmp_path / "report"
    subprocess.run(_report_command(out, *QUICK, "--no-figures"), check=True, capture_output=True, timeout=300)
    before = snapshot(out)
    env = {**os.environ, "COLUMNS": "200", "PYTHONUNBUFFERED": "1"}
    proc = subprocess.Popen(
        _report_command(out, "--laws", "feedforward,baseline", "--force"),
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env,
    )
    assert proc.stdout is not None
    for line in proc.stdout:
        if marker in line:
            break
    time.sleep(0.3)
    proc.send_signal(signum)
    _, err = proc.communicate(timeout=300)
    after = snapshot(out)
    if proc.returncode == 0:  # finished before the signal: the new report must be complete
        listed = json.loads(after["manifest.json"])["outputs"]
        assert sorted(listed + ["manifest.json"]) == sorted(after)
        assert all(after[name] for name in listed)
    else:
        assert after == before, err
        assert "Traceback" not in err and "no report written, the previous one is unchanged" in err, err
    leftovers = [p.name for p in tmp_path.iterdir() if p.name != "report" and not is_lock_file(p.name)]
    assert leftovers == [], leftovers


def test_ftc_table_fits_80_columns() -> None:
    """Item 11: below 120 columns, one narrow table per law; no line wider than 80, no scenario
    name broken."""
    from rotorfault.cli import _print_ftc_table, console
    from rotorfault.papers import ke as ke_paper

    runs = [ke_paper.run_scenario(n, law=law) for n in ("two-adjacent-front-reversed", "one-failure") for law in ("feedforward", "baseline")]
    with console.capture() as captured:
        old = console.width
        console.width = 80
        try:
            _print_ftc_table(runs, "ke-hil")
        finally:
            console.width = old
    text = captured.get()
    assert max(len(line) for line in text.splitlines()) <= 80
    assert "two-adjacent-front-reversed*" in text and "diverged: tilt" in text and "at 2.37 s" in text and "lost" in text
    assert "…" not in text  # no number or word cut

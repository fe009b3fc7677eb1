"""One writer per output (issue 27): a second writer, ``--resume`` or ``--force`` is refused while a
run holds the output, naming it; a killed run's lock goes with it and ``--resume`` then completes
the rows exactly; every state an interrupted ``--force`` can leave is accepted by ``--force`` and
``--resume``. Writers are real processes (``subprocess``): the lock is the operating system's."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from click.testing import CliRunner
from signal_after_chunks import run_signalled

import rotorfault as rf
from rotorfault._util.lock import OutputInUse, lock_file, output_lock
from rotorfault.cli import cli
from rotorfault.studies import Campaign, run_campaign
from rotorfault.studies.scan import acai_scan

pytest.importorskip("pyarrow")

#: A holder that takes the lock of argv[1] like a writer does, says so, and waits to be killed.
HOLDER = """
import sys, time
from rotorfault._util.lock import output_lock
with output_lock("out", sys.argv[1]):
    print("held", flush=True)
    time.sleep(600)
"""


def _hold(out: Path) -> subprocess.Popen[str]:
    proc = subprocess.Popen([sys.executable, "-c", HOLDER, str(out)], stdout=subprocess.PIPE, text=True)
    assert proc.stdout is not None
    assert proc.stdout.readline().strip() == "held"
    return proc


def _kill(proc: subprocess.Popen[Any]) -> None:
    proc.kill()
    proc.wait(timeout=30)
    if proc.stdout is not None:
        proc.stdout.close()


SCAN_ARGS = ["scan", "-a", "quad-x", "--rotors", "1,2", "--step", "0.1", "--chunk-points", "10"]


def test_a_second_writer_resume_and_force_are_refused_naming_the_holder(tmp_path: Path) -> None:
    out = tmp_path / "scan"
    holder = _hold(out)
    try:
        for extra in ([], ["--resume"], ["--force"]):
            result = CliRunner().invoke(cli, [*SCAN_ARGS, "--out", str(out), *extra])
            assert result.exit_code == 1, result.output
            message = result.output.strip()
            assert "\n" not in message, message  # one line
            assert f"process {holder.pid} on " in message and " since " in message and "-c" in message, message
        assert not out.exists()  # nothing was written by the refused runs
        with pytest.raises(OutputInUse, match=f"process {holder.pid}"):
            run_campaign(Campaign(runs=2, chunk_size=1, duration_s=1.0, fault_time_s=0.5, gap_s=0.1), out=out)
    finally:
        _kill(holder)
    # The lock went with the killed holder: its record is found stale and taken over.
    assert lock_file(out).with_name(lock_file(out).name + ".json").exists()
    with output_lock("out", out) as held:
        assert held.previous is not None and held.previous["pid"] == holder.pid
    assert not lock_file(out).with_name(lock_file(out).name + ".json").exists()


def test_report_commands_are_refused_before_any_work(tmp_path: Path) -> None:
    out = tmp_path / "report"
    holder = _hold(out)
    try:
        for command in (["reproduce", "--quick"], ["vpp-report", "--quick"], ["ftc-report"], ["lanzon-report", "--quick"]):
            result = CliRunner().invoke(cli, [*command, "--out", str(out)])
            assert result.exit_code == 1 and f"process {holder.pid}" in result.output, result.output
            assert not out.exists()
    finally:
        _kill(holder)


def _chunks(out: Path) -> list[Path]:
    return sorted(out.glob("chunk-*.parquet")) if out.is_dir() else []


def _kill_after_chunks(args: list[str], out: Path, chunks: int) -> None:
    """Runs the CLI in a process that is SIGKILLed right after its ``chunks``-th chunk file is written."""
    proc = run_signalled(args, after_chunks=chunks, signum=signal.SIGKILL)
    assert proc.returncode == -signal.SIGKILL, f"the writer was not killed (exit {proc.returncode}): {proc.stderr}"
    assert len(_chunks(out)) == chunks


def _rows(out: Path) -> dict[str, np.ndarray[Any, Any]]:
    import pyarrow as pa
    import pyarrow.parquet as pq

    table = pa.concat_tables([pq.read_table(p) for p in _chunks(out)])
    return {name: table.column(name).to_numpy(zero_copy_only=False) for name in table.column_names}


def test_scan_killed_mid_run_resumes_to_the_uninterrupted_rows(tmp_path: Path) -> None:
    out = tmp_path / "scan"
    args = ["scan", "-a", "hexa-pnpnpn", "--rotors", "1,2,3", "--step", "0.05", "--chunk-points", "100", "--give-up-yaw", "--out", str(out)]
    _kill_after_chunks(args, out, 3)
    manifest = json.loads((out / "_rotorfault.json").read_text())
    assert not manifest["complete"] and len(_chunks(out)) < manifest["chunks"]
    result = CliRunner().invoke(cli, [*args, "--resume"])
    assert result.exit_code == 0, result.output
    assert json.loads((out / "_rotorfault.json").read_text())["complete"]
    levels = np.linspace(0.0, 1.0, 21)
    reference = acai_scan(rf.Airframe.preset("hexa-pnpnpn"), {f"efficiency_{r}": levels for r in (1, 2, 3)}, give_up_yaw=True)
    rows = _rows(out)
    for name in reference.table.column_names:
        np.testing.assert_array_equal(rows[name], reference.table.column(name).to_numpy(zero_copy_only=False), err_msg=name)


def test_campaign_killed_mid_run_resumes_to_the_uninterrupted_rows(tmp_path: Path) -> None:
    campaign = Campaign(runs=24, chunk_size=2, duration_s=3.0, fault_time_s=(0.5, 1.0), gap_s=0.5, seed=7)
    file = tmp_path / "c.toml"
    file.write_text(campaign.to_toml())
    out = tmp_path / "campaign"
    args = ["campaign", str(file), "--out", str(out), "--no-progress"]
    _kill_after_chunks(args, out, 2)
    assert not json.loads((out / "_rotorfault.json").read_text())["complete"]
    result = CliRunner().invoke(cli, [*args, "--resume"])
    assert result.exit_code == 0, result.output
    reference = run_campaign(campaign)
    rows = _rows(out)
    assert rows.keys() == reference.columns.keys()
    for name, column in reference.columns.items():
        np.testing.assert_array_equal(rows[name], column, err_msg=name)


@pytest.mark.parametrize("stop_after", [0, 1, 3, 5])
def test_every_state_an_interrupted_force_leaves_is_accepted(tmp_path: Path, monkeypatch: pytest.MonkeyPatch, stop_after: int) -> None:
    """--force interrupted after ``stop_after`` deletions (0: right after marking the manifest
    incomplete): both --force and --resume accept what is left, and --resume completes it."""
    frame = rf.Airframe.preset("quad-x")
    axes = {"efficiency_1": np.linspace(0, 1, 11), "efficiency_2": np.linspace(0, 1, 11)}
    out = tmp_path / "scan"
    acai_scan(frame, axes, out=out, chunk_points=20)
    other = {"efficiency_1": np.linspace(0, 1, 6), "efficiency_3": np.linspace(0, 1, 6)}
    deleted = {"n": 0}
    real_unlink = Path.unlink

    def unlink(self: Path, missing_ok: bool = False) -> None:
        if self.parent == out and deleted["n"] >= stop_after:
            raise KeyboardInterrupt
        deleted["n"] += 1
        real_unlink(self, missing_ok=missing_ok)

    monkeypatch.setattr(Path, "unlink", unlink)
    with pytest.raises(KeyboardInterrupt):
        acai_scan(frame, other, out=out, chunk_points=20, force=True)
    monkeypatch.setattr(Path, "unlink", real_unlink)
    manifest = json.loads((out / "_rotorfault.json").read_text())
    assert manifest["complete"] is False  # never taken for a whole output
    resumed = acai_scan(frame, axes, out=out, chunk_points=20, resume=True)  # the old job, completed
    assert resumed.total == 121 and resumed.controllable_count() == acai_scan(frame, axes).controllable_count()
    replaced = acai_scan(frame, other, out=out, chunk_points=20, force=True)
    assert replaced.total == 36 and replaced.controllable_count() == acai_scan(frame, other).controllable_count()


def test_a_report_swap_cut_between_its_renames_is_undone(tmp_path: Path) -> None:
    """A writer killed between moving the old report aside and moving the new one in leaves no
    report and ``.report.<pid>.old``: the next writer (holding the lock) puts the old one back and
    removes the temporary directories."""
    from rotorfault._util.output import claim_output_directory, output_directory

    out = tmp_path / "report"
    with output_directory(out, {"generator": "test"}) as tmp:
        (tmp / "index.html").write_text("old")
    os.replace(out, tmp_path / ".report.999999.old")
    (tmp_path / ".report.abc.part").mkdir()
    with claim_output_directory("out", out, force=True) as checked:
        assert checked == out and (out / "index.html").read_text() == "old"
    assert sorted(p.name for p in tmp_path.iterdir() if not p.name.endswith(("-lock", "-lock.json"))) == ["report"]

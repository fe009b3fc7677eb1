"""Ctrl-C on the command line (issue 27): ``scan --out`` and ``campaign --out`` stopped by SIGINT
once a chunk is written exit with status 130 and one line on standard error (no traceback), keep
an output that ``--resume`` completes, and the completed rows equal an uninterrupted run's, row for
row. The writers are real processes that send themselves SIGINT right after their first chunk
file is written (``tests/signal_after_chunks.py``: a known point of the job on any machine), so the
signal is the operating system's; one arriving inside a long Rust call is
``tests/cross/test_interrupt.py``'s case."""

from __future__ import annotations

import json
import signal
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import rotorfault as rf
from signal_after_chunks import run_signalled
from rotorfault.cli.app import EXIT_INTERRUPTED
from rotorfault.studies import Campaign, run_campaign
from rotorfault.studies.scan import acai_scan

pytest.importorskip("pyarrow")


def _chunks(out: Path) -> list[Path]:
    return sorted(out.glob("chunk-*.parquet")) if out.is_dir() else []


def _interrupt_after_a_chunk(args: list[str], out: Path) -> str:
    """Runs the CLI, which receives SIGINT right after its first chunk file is in place; returns
    standard error."""
    proc = run_signalled(args, after_chunks=1, signum=signal.SIGINT)
    err = proc.stderr
    assert proc.returncode == EXIT_INTERRUPTED, err
    assert "Traceback" not in err and "Aborted" not in err, err
    # Progress bars redraw on standard error; the message is the last line, and one line.
    last = err.strip().splitlines()[-1]
    assert last == f"Error: interrupted (Ctrl-C): {out} keeps the chunks written; the same command with --resume completes it", err
    manifest = json.loads((out / "_rotorfault.json").read_text())
    assert manifest["complete"] is False and len(_chunks(out)) == 1 < manifest["chunks"]
    return err


def _resume(args: list[str]) -> None:
    done = subprocess.run([sys.executable, "-m", "rotorfault", *args, "--resume"], capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr


def _rows(out: Path) -> dict[str, np.ndarray[Any, Any]]:
    import pyarrow as pa
    import pyarrow.parquet as pq

    table = pa.concat_tables([pq.read_table(p) for p in _chunks(out)])
    return {name: table.column(name).to_numpy(zero_copy_only=False) for name in table.column_names}


@pytest.mark.timeout(600)
def test_scan_interrupted_exits_130_and_resume_completes_the_rows(tmp_path: Path) -> None:
    out = tmp_path / "scan"
    # 101^3 = 1.03 million points (seconds of work; the first chunk of 1,000 is written in milliseconds).
    args = ["scan", "-a", "hexa-pnpnpn", "--rotors", "1,2,3", "--step", "0.01", "--chunk-points", "1000", "--give-up-yaw", "--out", str(out)]
    _interrupt_after_a_chunk(args, out)
    # Resumed on a coarser grid would be refused: --resume completes exactly the job interrupted.
    _resume(args)
    manifest = json.loads((out / "_rotorfault.json").read_text())
    assert manifest["complete"] and len(_chunks(out)) == manifest["chunks"]
    levels = np.linspace(0.0, 1.0, 101)
    reference = acai_scan(rf.Airframe.preset("hexa-pnpnpn"), {f"efficiency_{r}": levels for r in (1, 2, 3)}, give_up_yaw=True)
    rows = _rows(out)
    assert sorted(rows) == sorted(reference.table.column_names)
    for name in reference.table.column_names:
        np.testing.assert_array_equal(rows[name], reference.table.column(name).to_numpy(zero_copy_only=False), err_msg=name)


@pytest.mark.timeout(600)
def test_campaign_interrupted_exits_130_and_resume_completes_the_rows(tmp_path: Path) -> None:
    campaign = Campaign(runs=40, chunk_size=2, duration_s=3.0, fault_time_s=(0.5, 1.0), gap_s=0.5, seed=11)
    file = tmp_path / "c.toml"
    file.write_text(campaign.to_toml())
    out = tmp_path / "campaign"
    args = ["campaign", str(file), "--out", str(out)]
    _interrupt_after_a_chunk(args, out)
    _resume(args)
    assert json.loads((out / "_rotorfault.json").read_text())["complete"]
    reference = run_campaign(campaign)
    rows = _rows(out)
    assert rows.keys() == reference.columns.keys()
    for name, column in reference.columns.items():
        np.testing.assert_array_equal(rows[name], column, err_msg=name)

"""The quick report as a user builds it (``rotorfault reproduce --quick --format json`` in a fresh
interpreter), built once per test session by the ``quick_report`` fixture (``conftest.py``):
each build flies every paper's quick flights and the quick campaign, about a minute on two
cores, so the tests that read a report (the browser check, the JSON schema) share one."""

from __future__ import annotations

import json
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any


@dataclass(frozen=True)
class QuickReport:
    """The report directory and the JSON document the command printed (``docs/cli.md``)."""

    out: Path
    document: dict[str, Any]


def build_quick_report(out: Path) -> QuickReport:
    done = subprocess.run([sys.executable, "-m", "rotorfault", "reproduce", "--quick", "--format", "json", "--out", str(out)],
                          capture_output=True, text=True, timeout=900, check=False)
    assert done.returncode == 0, done.stderr
    return QuickReport(out, json.loads(done.stdout))

"""Run Python code in a subprocess where ``slycot`` cannot be imported.

python-control takes other code paths when slycot is installed (``lqr``, ``ss`` from transfer
functions, ``minreal``, norms). rotorfault promises one answer per question on every install, so
the design tests run the same design here and in a subprocess that hides slycot, and compare.

Usage: ``result = run_without_slycot(code)``, where ``code`` prints one JSON document (the last
line of standard output) and ``result`` is that document, parsed. The subprocess checks that
python-control itself believes slycot is missing, so a test cannot pass by accident.
"""

from __future__ import annotations

import json
import subprocess
import sys
import textwrap
from typing import Any

_PRELUDE = '''
import sys

class _HideSlycot:
    """A meta-path finder that makes ``import slycot`` fail as on an install without it."""

    def find_spec(self, name, path=None, target=None):
        if name == "slycot" or name.startswith("slycot."):
            raise ImportError("slycot is hidden for this test")
        return None

sys.meta_path.insert(0, _HideSlycot())
import control
if control.exception.slycot_check():
    raise SystemExit("python-control still finds slycot")
'''


def run_without_slycot(code: str, *, timeout_s: float = 600.0) -> Any:
    """Runs ``code`` with slycot hidden and returns the JSON it printed last."""
    return _run(_PRELUDE + "\n" + textwrap.dedent(code), "slycot-free", timeout_s)


def run_with_slycot(code: str, *, timeout_s: float = 600.0) -> Any:
    """Runs ``code`` in a fresh interpreter as installed (slycot importable, checked) and returns
    the JSON it printed last: the twin of :func:`run_without_slycot`, so that a comparison of the
    two differs only by slycot, never by what the test session ran before (its BLAS threads,
    warnings filters or environment)."""
    prelude = "import control\nif not control.exception.slycot_check():\n    raise SystemExit('slycot is not installed')\n"
    return _run(prelude + textwrap.dedent(code), "slycot", timeout_s)


def _run(source: str, label: str, timeout_s: float) -> Any:
    done = subprocess.run(
        [sys.executable, "-c", source], capture_output=True, text=True, timeout=timeout_s, check=False
    )
    if done.returncode != 0:
        raise AssertionError(f"the {label} subprocess failed ({done.returncode}):\n{done.stderr[-4000:]}")
    lines = [line for line in done.stdout.splitlines() if line.strip()]
    if not lines:
        raise AssertionError(f"the {label} subprocess printed nothing")
    return json.loads(lines[-1])

"""Run Python code in a subprocess where some packages cannot be imported, as on an install
without an optional extra (pandas, dask, ...): the features that need them must say which extra
to install, before any work, and everything else must work as before.

Usage: ``result = run_without(("pandas",), code)``, where ``code`` prints one JSON document (the
last line of standard output) and ``result`` is that document, parsed. The subprocess checks that
each hidden package really cannot be imported, so a test cannot pass by accident.
"""

from __future__ import annotations

import json
import subprocess
import sys
import textwrap
from collections.abc import Sequence
from typing import Any


def prelude(packages: Sequence[str]) -> str:
    """Code that makes ``import <package>`` fail for each of ``packages`` (and their submodules)."""
    return textwrap.dedent(f'''
        import importlib.util
        import sys

        _HIDDEN = {tuple(packages)!r}

        class _Hide:
            """A meta-path finder that makes the hidden packages fail to import, as when not installed."""

            def find_spec(self, name, path=None, target=None):
                if name.split(".")[0] in _HIDDEN:
                    raise ImportError(f"{{name}} is hidden for this test", name=name)
                return None

        sys.meta_path.insert(0, _Hide())
        for _name in _HIDDEN:
            sys.modules.pop(_name, None)
            try:
                __import__(_name)
            except ImportError:
                pass
            else:
                raise SystemExit(f"{{_name}} can still be imported")
    ''')


def run_without(packages: Sequence[str], code: str, *, timeout_s: float = 600.0) -> Any:
    """Runs ``code`` with ``packages`` hidden and returns the JSON it printed last."""
    source = prelude(packages) + "\n" + textwrap.dedent(code)
    done = subprocess.run([sys.executable, "-c", source], capture_output=True, text=True, timeout=timeout_s, check=False)
    if done.returncode != 0:
        raise AssertionError(f"the subprocess without {', '.join(packages)} failed ({done.returncode}):\n{done.stderr[-4000:]}")
    lines = [line for line in done.stdout.splitlines() if line.strip()]
    if not lines:
        raise AssertionError(f"the subprocess without {', '.join(packages)} printed nothing")
    return json.loads(lines[-1])

"""The extension's type stubs (_rfcore.pyi) match the compiled module (mypy.stubtest), and the
public package type-checks under mypy --strict."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path



def test_stubtest_extension_module() -> None:
    done = subprocess.run(
        [sys.executable, "-m", "mypy.stubtest", "rotorfault._rfcore", "--ignore-missing-stub"],
        capture_output=True, text=True, check=False, timeout=600,
    )
    assert done.returncode == 0, done.stdout + done.stderr


def test_package_typechecks_strict(tmp_path: Path) -> None:
    done = subprocess.run(
        [sys.executable, "-m", "mypy", "--strict", "--no-incremental", "-p", "rotorfault"],
        cwd=tmp_path,  # a neutral directory, so the installed package is what gets checked
        capture_output=True, text=True, check=False, timeout=600,
    )
    assert done.returncode == 0, done.stdout + done.stderr

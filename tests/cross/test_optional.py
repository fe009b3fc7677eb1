"""Optional packages (issue 31): one helper says which extra installs a missing package, and the
features that need one ask before any work (the message names the feature and the command)."""

from __future__ import annotations

from pathlib import Path

import pytest

import rotorfault as rf
from rotorfault._util.optional import EXTRAS, MissingDependency, install_hint, require, require_available

from without_packages import run_without

PYPROJECT = Path(__file__).resolve().parents[2] / "pyproject.toml"


def test_every_extra_named_exists_and_installs_the_package() -> None:
    import tomllib

    extras = tomllib.loads(PYPROJECT.read_text())["project"]["optional-dependencies"]
    for package, extra in EXTRAS.items():
        assert extra in extras, extra
        names = " ".join(extras[extra]).lower()
        assert package in names or (package == "distributed" and "dask[distributed]" in names), (package, extra)
    assert any(d.startswith("pyarrow") for d in tomllib.loads(PYPROJECT.read_text())["project"]["dependencies"])


def test_the_message_names_the_feature_and_the_extra() -> None:
    assert install_hint("dask.distributed") == 'pip install "rotorfault[scale]"'
    assert install_hint("pandas") == 'pip install "rotorfault[pandas]"'
    with pytest.raises(MissingDependency, match=r"^plotting stars needs no_such_package_h31, which is not installed: pip install no_such_package_h31$"):
        require("no_such_package_h31", feature="plotting stars")
    with pytest.raises(ImportError):
        require_available("x", "no_such_package_h31")
    assert require("math", feature="x").sqrt(4.0) == 2.0


def test_without_dask_the_api_refuses_before_writing(tmp_path: Path) -> None:
    out = tmp_path / "scan.parquet"
    result = run_without(("dask", "distributed"), f"""
        import json
        import rotorfault as rf
        try:
            rf.acai_scan(rf.Airframe.preset("quad-x"), {{"efficiency_1": [0, 1]}}, out={str(out)!r}, backend="dask", dask="local:1")
        except ImportError as exc:
            print(json.dumps(str(exc)))
    """)
    assert result == "backend='dask' needs dask, which is not installed: pip install \"rotorfault[scale]\""
    assert not out.exists()
    assert rf.acai_scan(rf.Airframe.preset("quad-x"), {"efficiency_1": [0, 1]}).total == 2

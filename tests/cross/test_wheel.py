"""The package as users get it: an abi3 wheel (one wheel for CPython >= 3.11) built with
``maturin build --release``, installed into a fresh virtual environment (no access to this
environment's packages) and used there; and an sdist that builds. Slow (a release build and an
install), so it runs once per test session, in a temporary directory."""

from __future__ import annotations

import shutil
import subprocess
import sys
import venv
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]

pytestmark = pytest.mark.skipif(shutil.which("maturin") is None, reason="maturin is not installed")


def _run(args: list[str | Path], cwd: Path, timeout: int = 900) -> str:
    done = subprocess.run([str(a) for a in args], cwd=cwd, capture_output=True, text=True, timeout=timeout, check=False)
    assert done.returncode == 0, f"{args}: {done.stdout}\n{done.stderr}"
    return done.stdout


@pytest.fixture(scope="module")
def built(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    out = tmp_path_factory.mktemp("dist")
    _run(["maturin", "build", "--release", "--out", out], ROOT)
    _run(["maturin", "sdist", "--out", out], ROOT)
    wheels = sorted(out.glob("*.whl"))
    sdists = sorted(out.glob("*.tar.gz"))
    assert len(wheels) == 1 and len(sdists) == 1, sorted(p.name for p in out.iterdir())
    return wheels[0], sdists[0]


def test_the_wheel_is_abi3_and_carries_the_package(built: tuple[Path, Path]) -> None:
    wheel, _ = built
    assert "-cp311-abi3-" in wheel.name, wheel.name
    names = zipfile.ZipFile(wheel).namelist()
    for required in ("rotorfault/_rfcore.pyi", "rotorfault/py.typed", "rotorfault/presets/hexa-pnpnpn.toml",
                     "rotorfault/presets/ftc/ke-hil.toml", "rotorfault/control/ke.py", "rotorfault/papers/ke.py",
                     "rotorfault/papers/templates/reproduce.html.j2"):
        assert required in names, required
    assert any(n.startswith("rotorfault/_rfcore") and n.endswith(".so") for n in names), names


def test_the_sdist_holds_both_crates_and_the_python_source(built: tuple[Path, Path]) -> None:
    _, sdist = built
    import tarfile

    names = tarfile.open(sdist).getnames()
    for required in ("Cargo.toml", "crates/rfcore/src/lib.rs", "crates/rfcore-py/src/lib.rs", "python/rotorfault/__init__.py"):
        assert any(n.endswith(required) for n in names), required


def test_the_wheel_installs_into_a_fresh_environment_and_works(built: tuple[Path, Path], tmp_path: Path) -> None:
    wheel, _ = built
    env = tmp_path / "venv"
    venv.EnvBuilder(with_pip=True, system_site_packages=False).create(env)
    python = env / "bin" / "python"
    _run([python, "-m", "pip", "install", "--quiet", wheel], tmp_path)
    # From a neutral directory, so nothing of the source tree can be imported by accident.
    script = (
        "import rotorfault as rf, pathlib; "
        "assert 'site-packages' in pathlib.Path(rf.__file__).as_posix(), rf.__file__; "
        "print(round(rf.acai(rf.Airframe.preset('hexa-pnpnpn')), 4)); "
        "print(round(rf.acai(rf.Airframe.preset('hexa-ppnnpn').with_failed_rotors([1])), 4)); "
        "tr = rf.Simulator(rf.Airframe.preset('quad-x')).run(rf.State(position=(0, 0, -10)), 0.5); "
        "print(len(tr.t))"
    )
    out = _run([python, "-c", script], tmp_path).split()
    assert out == ["1.4861", "0.7221", "201"], out  # Du Table II, Table III, 0.5 s at 400 Hz
    cli = _run([env / "bin" / "rotorfault", "acai", "-a", "hexa-pnpnpn"], tmp_path)
    assert "1.4861" in cli, cli
    assert sys.version_info >= (3, 11)

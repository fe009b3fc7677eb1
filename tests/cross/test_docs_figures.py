"""Every PNG in ``docs/`` is made by one script, ``python docs/make_figures.py``, and is not older
than the code that draws it: the manifest beside the PNGs (``docs/figures.json``) holds the
SHA-256 of each figure's sources and parameters and of the PNG written; a figure whose code or
parameters changed since (or whose PNG is not the one recorded) fails here, naming the command
that regenerates it. Hashes, not pixels: independent of the machine's fonts."""

from __future__ import annotations

import hashlib
import importlib.util
import json
import sys
from pathlib import Path
from types import ModuleType

import pytest

ROOT = Path(__file__).resolve().parents[2]
DOCS = ROOT / "docs"


def _script() -> ModuleType:
    spec = importlib.util.spec_from_file_location("make_figures", DOCS / "make_figures.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules.setdefault("make_figures", module)  # dataclasses resolve their module by name
    spec.loader.exec_module(sys.modules["make_figures"])
    return sys.modules["make_figures"]


@pytest.fixture(scope="module")
def script() -> ModuleType:
    return _script()


def test_every_png_in_docs_is_made_by_the_script(script: ModuleType) -> None:
    assert {p.name for p in DOCS.glob("*.png")} == {s.name for s in script.FIGURES}


def _stale(script: ModuleType, manifest: dict[str, object], name: str) -> list[str]:
    """Why ``docs/<name>`` is stale against ``manifest`` (empty: up to date)."""
    spec = next(s for s in script.FIGURES if s.name == name)
    recorded = manifest["figures"].get(name)  # type: ignore[attr-defined]
    if recorded is None:
        return ["not in docs/figures.json"]
    now = script.entry(spec)
    why = [f"{p} changed" for p in sorted(set(now["sources"]) | set(recorded["sources"]))
           if now["sources"].get(p) != recorded["sources"].get(p)]
    if now["parameters_sha256"] != recorded["parameters_sha256"]:
        why.append("its parameters changed")
    if hashlib.sha256((DOCS / name).read_bytes()).hexdigest() != recorded["png_sha256"]:
        why.append("the PNG is not the one the script wrote")
    return why


@pytest.mark.parametrize("name", [s.name for s in _script().FIGURES])
def test_each_png_is_regenerated_since_its_code_changed(script: ModuleType, name: str) -> None:
    manifest = json.loads((DOCS / "figures.json").read_text(encoding="utf-8"))
    assert manifest["schema"] == script.SCHEMA
    why = _stale(script, manifest, name)
    assert not why, f"docs/{name} is stale ({'; '.join(why)}): run python docs/make_figures.py {name} and commit it"


def test_the_check_fails_when_a_source_or_a_parameter_changed(script: ModuleType) -> None:
    """The check itself can fail: a manifest that recorded another digest of the plotting code,
    other parameters or another PNG makes the figure stale."""
    manifest = json.loads((DOCS / "figures.json").read_text(encoding="utf-8"))
    name = "fig4-pnpnpn.png"
    assert _stale(script, manifest, name) == []
    source = "python/rotorfault/plotting/regions.py"
    for key, value, why in (
        ("sources", {**manifest["figures"][name]["sources"], source: "0" * 64}, f"{source} changed"),
        ("parameters_sha256", "0" * 64, "its parameters changed"),
        ("png_sha256", "0" * 64, "the PNG is not the one the script wrote"),
    ):
        changed = {**manifest, "figures": {**manifest["figures"], name: {**manifest["figures"][name], key: value}}}
        assert _stale(script, changed, name) == [why]

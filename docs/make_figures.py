"""Regenerates every PNG in ``docs/`` and their manifest, ``docs/figures.json``:

    python docs/make_figures.py            # every figure
    python docs/make_figures.py fig4-pnpnpn.png

Each figure (:data:`FIGURES`) names the files that produce it (the plotting code, the module that
computes what it shows, the presets it reads; for the report's screenshot the page's template and
renderer) and its parameters. The manifest keeps, per figure, the SHA-256 of each source, of the
parameters and of the PNG written. ``tests/cross/test_docs_figures.py`` recomputes the source and
parameter digests and fails when a figure's code or parameters changed since its PNG was made (or
the PNG is not the one the manifest recorded): run this script and commit both. It compares
hashes, not pixels, so it does not depend on the machine's fonts. The Rust core's numbers are
tested elsewhere and not hashed here.

``report.png`` is a headless-Chromium screenshot of ``rotorfault reproduce --quick`` (Debian's
``chromium``); without a browser the script stops before writing anything.
"""

from __future__ import annotations

import hashlib
import json
import os
import shutil
import subprocess
import sys
import tempfile
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

DOCS = Path(__file__).resolve().parent
ROOT = DOCS.parent
MANIFEST = DOCS / "figures.json"
SCHEMA = "rotorfault-docs-figures/1"


@dataclass(frozen=True)
class FigureSpec:
    """A PNG of ``docs/``: the repository files that produce it, its parameters and how to draw
    it (``draw(path, **parameters)``)."""

    name: str
    sources: tuple[str, ...]
    parameters: dict[str, Any] = field(default_factory=dict)
    draw: Callable[..., None] = lambda path, **_: None


def _fig4(path: Path, *, airframe: str, rotors: list[int], step: float) -> None:
    import rotorfault as rf

    rf.efficiency_scan(rf.Airframe.preset(airframe), tuple(rotors), step).plot(str(path))


def _attainable(path: Path, *, airframe: str) -> None:
    import rotorfault as rf
    from rotorfault.allocation import plot_attainable_slices

    plot_attainable_slices(rf.Airframe.preset(airframe), path=str(path))


def _report(path: Path, *, window: list[int], quick: bool) -> None:
    chromium = shutil.which("chromium") or shutil.which("chromium-browser") or shutil.which("google-chrome")
    if chromium is None:
        raise SystemExit("report.png needs a headless Chromium (apt-get install -y chromium); nothing was written")
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "report"
        command = [sys.executable, "-m", "rotorfault", "reproduce", "--out", str(out)] + (["--quick"] if quick else [])
        subprocess.run(command, check=True, capture_output=True, text=True)
        shot = Path(tmp) / "shot.png"
        subprocess.run(
            [chromium, "--headless", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage", f"--user-data-dir={tmp}/profile",
             "--hide-scrollbars", f"--window-size={window[0]},{window[1]}", "--virtual-time-budget=10000",
             f"--screenshot={shot}", (out / "index.html").as_uri()],
            check=True, capture_output=True, text=True, timeout=120,
        )
        shutil.copyfile(shot, path)


_PLOTTING = ("python/rotorfault/plotting/style.py",)
#: Every PNG of docs/, what produces it and its parameters.
FIGURES: tuple[FigureSpec, ...] = (
    FigureSpec(
        "fig4-pnpnpn.png",
        (*_PLOTTING, "python/rotorfault/plotting/regions.py", "python/rotorfault/studies/scan.py",
         "python/rotorfault/presets/hexa-pnpnpn.toml"),
        {"airframe": "hexa-pnpnpn", "rotors": [1, 2, 5], "step": 0.04},
        _fig4,
    ),
    FigureSpec(
        "attainable-hexa-ppnnpn.png",
        (*_PLOTTING, "python/rotorfault/plotting/attainable.py", "python/rotorfault/allocation/attainable.py",
         "python/rotorfault/presets/hexa-ppnnpn.toml"),
        {"airframe": "hexa-ppnnpn"},
        _attainable,
    ),
    FigureSpec(
        "report.png",
        ("python/rotorfault/papers/templates/reproduce.html.j2", "python/rotorfault/papers/reproduce.py",
         "python/rotorfault/papers/_report.py", "python/rotorfault/papers/_numbers.py"),
        {"window": [1300, 2200], "quick": True},
        _report,
    ),
)


def _sha256(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def source_digests(spec: FigureSpec) -> dict[str, str]:
    """SHA-256 of each source file of ``spec`` (line endings as stored)."""
    return {path: _sha256((ROOT / path).read_bytes()) for path in spec.sources}


def parameters_digest(spec: FigureSpec) -> str:
    return _sha256(json.dumps(spec.parameters, sort_keys=True).encode("utf-8"))


def entry(spec: FigureSpec) -> dict[str, Any]:
    """The manifest entry ``spec`` has now (without the PNG's digest)."""
    return {"sources": source_digests(spec), "parameters": spec.parameters, "parameters_sha256": parameters_digest(spec)}


def read_manifest() -> dict[str, Any]:
    if not MANIFEST.is_file():
        return {"schema": SCHEMA, "figures": {}}
    data: dict[str, Any] = json.loads(MANIFEST.read_text(encoding="utf-8"))
    return data


def make(names: list[str] | None = None) -> list[str]:
    """Draws the figures (all, or those named), each into a temporary file renamed over the old
    one when complete, and updates their manifest entries. Returns the names written."""
    import matplotlib

    matplotlib.use("Agg")
    chosen = [s for s in FIGURES if names is None or not names or s.name in names]
    unknown = set(names or ()) - {s.name for s in FIGURES}
    if unknown:
        raise SystemExit(f"unknown figure(s) {sorted(unknown)}; docs/ has {[s.name for s in FIGURES]}")
    manifest = read_manifest()
    written = []
    for spec in chosen:
        target = DOCS / spec.name
        tmp = target.with_name(f".{spec.name}.tmp.png")
        spec.draw(tmp, **spec.parameters)
        os.replace(tmp, target)
        manifest["figures"][spec.name] = {**entry(spec), "png_sha256": _sha256(target.read_bytes())}
        written.append(spec.name)
        print(f"docs/{spec.name}", flush=True)
    manifest["schema"] = SCHEMA
    manifest["figures"] = dict(sorted(manifest["figures"].items()))
    MANIFEST.write_text(json.dumps(manifest, indent=1, sort_keys=True) + "\n", encoding="utf-8")
    return written


if __name__ == "__main__":
    make(sys.argv[1:])

"""Machine-readable bench results (not part of the package): every bench script takes
``--json PATH`` and writes its figures there with the machine, the date and the command, so the
reproduce-all report (``rotorfault reproduce``) reads the figures instead of copying them by hand.

Schema (``SCHEMA``), one JSON object per file::

    {"schema": "rotorfault-bench/1", "bench": "acai_grid", "title": "...",
     "command": "python benches/acai_grid.py --json ...", "date": "2026-11-23T11:40:00+00:00",
     "machine": {"cpu": "...", "cpus": 2, "system": "Linux ...", "python": "3.11.2",
                 "rotorfault": "0.1.0", "load_average_1min": 1.2},
     "reduced": null,                     # or a sentence: which sizes were cut, and why
     "figures": [{"what": "...", "value": 7.0e6, "unit": "evaluations/s",
                  "baseline": "NumPy, the paper's per-point procedure", "baseline_value": 2.2e4,
                  "ratio": 312.0, "target": ">= 2e6"}]}

``ratio`` is rotorfault's advantage over the baseline (> 1: rotorfault is faster), whichever way
the unit runs; ``baseline``, ``baseline_value``, ``ratio`` and ``target`` may be null.
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import platform
import sys
from pathlib import Path
from typing import Any

SCHEMA = "rotorfault-bench/1"


def add_json_option(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--json", dest="json_path", metavar="PATH", default=None,
                        help="also write the figures, the machine and the date to PATH (JSON)")


def _cpu_name() -> str:
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as handle:
            for line in handle:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def machine() -> dict[str, Any]:
    try:
        import rotorfault

        version = rotorfault.__version__
    except Exception:  # pragma: no cover - the bench runs without the package only by mistake
        version = "unknown"
    cpus = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
    return {
        "cpu": _cpu_name(),
        "cpus": cpus,
        "system": f"{platform.system()} {platform.release()} {platform.machine()}",
        "python": platform.python_version(),
        "rotorfault": version,
        "load_average_1min": round(os.getloadavg()[0], 2) if hasattr(os, "getloadavg") else None,
    }


def figure(what: str, value: float, unit: str, *, baseline: str | None = None, baseline_value: float | None = None,
           ratio: float | None = None, target: str | None = None) -> dict[str, Any]:
    return {"what": what, "value": float(value), "unit": unit, "baseline": baseline,
            "baseline_value": None if baseline_value is None else float(baseline_value),
            "ratio": None if ratio is None else float(ratio), "target": target}


def write(path: str | None, bench: str, title: str, figures: list[dict[str, Any]], *, reduced: str | None = None) -> None:
    """Writes the results to ``path`` (nothing when ``path`` is None), atomically."""
    if path is None:
        return
    record = {
        "schema": SCHEMA,
        "bench": bench,
        "title": title,
        "command": "python " + " ".join([f"benches/{Path(sys.argv[0]).name}", *sys.argv[1:]]),
        "date": datetime.datetime.now(datetime.timezone.utc).replace(microsecond=0).isoformat(),
        "machine": machine(),
        "reduced": reduced,
        "figures": figures,
    }
    target = Path(path)
    tmp = target.with_name(f".{target.name}.part")
    tmp.write_text(json.dumps(record, indent=2) + "\n", encoding="utf-8")
    os.replace(tmp, target)
    print(f"results written to {target}")

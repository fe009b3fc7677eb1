"""Recorded batches in bounded memory (issue 32, "Recordings that stream").

Run:  python benches/recording.py [--runs N] [--duration S] [--json PATH]   (about 2 minutes;
      ``--runs`` below 1,000 or ``--duration`` below 10 is a reduced run, labelled so in the JSON)

The batch: ``--runs`` runs (default 1,000) of ``--duration`` s (default 10) of the quad-x preset
hovering under its LQR from starts scattered 0.3 m about the setpoint, every control step
recorded at 400 Hz (4,001 rows a run). Each way of recording runs in a fresh subprocess, so its
peak resident memory (``ru_maxrss``) is its own:

- **per-run** (the baseline: the path ``simulate_batch`` took before the columns): the core
  returns one ``Trajectory`` per run, Python converts each into a ``rotorfault.Trajectory``
  (arrays per run) and stacks the batch arrays from them;
- **columns**: ``simulate_batch`` as it is now, the core filling one buffer per signal handed to
  NumPy without a copy, runs viewed on demand (float64, then ``dtype="float32"``);
- **stream**: ``rotorfault.studies.record_batch`` writing the runs to a Parquet directory as
  they finish (float64 and float32).

Reported per way: peak RSS (MiB) against the per-run baseline's (and what the process held
before the call: the interpreter, NumPy, rotorfault and the LQR design's imports, pyarrow for
the streamed ways), and for the in-memory ways the
wall time of the call and the share of it spent outside the core call (the Python wrapper).
Targets: streaming 1,000 x 10 s at 400 Hz in <= 300 MB peak RSS; the wrapper under 10 % of the
call.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

RUNS = 1000
DURATION_S = 10.0
TARGET_RSS_MB = 300.0
TARGET_WRAPPER_SHARE = 0.10
MODES = ("per-run", "columns", "columns-float32", "stream", "stream-float32")


def _inputs(runs: int) -> tuple[Any, list[Any], Any]:
    import rotorfault as rf

    sim = rf.Simulator(rf.Airframe.preset("quad-x"))
    controller = rf.lqr_hover(sim, position=(0, 0, -10))
    offsets = np.random.default_rng(0).normal(0.0, 0.3, (runs, 2))
    return sim, [rf.State(position=(float(a), float(b), -10.0)) for a, b in offsets], controller


def _per_run(sim: Any, x0s: list[Any], controller: Any, duration_s: float) -> Any:
    """The recording path before the columns: one core Trajectory per run, converted and
    stacked in Python (the former ``simulate_batch`` body, kept here as the baseline)."""
    from rotorfault import _rfcore
    from rotorfault.flight.trajectory import Trajectory

    core = controller.core(sim.dt_s)
    start = [float(v) for v in sim._start(controller, None)]
    raws = _rfcore.simulate_batch(sim.airframe._core, sim.actuator, sim.drag, [core] * len(x0s), [s._packed() for s in x0s],
                                  [[] for _ in x0s], sim.airframe.efficiency, [start] * len(x0s), sim._config(duration_s))
    runs = [Trajectory._from_core(raw, ()) for raw in raws]
    grid = sim._config(duration_s).record_times()
    stacked = {}
    for name in ("position", "velocity", "euler", "omega", "rotor_thrust", "efficiency"):
        arrays = [getattr(tr, name) for tr in runs]
        out = np.full((len(runs), len(grid), *arrays[0].shape[1:]), np.nan)
        for i, a in enumerate(arrays):
            rows = min(len(a), len(grid))
            out[i, :rows] = a[:rows]
        stacked[name] = out
    return runs, stacked


def child(mode: str, runs: int, duration_s: float) -> dict[str, Any]:
    """One way of recording, in this (fresh) process: wall time, core time, peak RSS."""
    import rotorfault as rf
    from rotorfault import _rfcore

    sim, x0s, controller = _inputs(runs)
    if mode.startswith("stream"):
        import pyarrow.parquet  # noqa: F401  (its import is the writer's, not the recording's)
    # What the process holds before recording: the interpreter, NumPy, rotorfault, and the LQR
    # design's imports (python-control, SciPy, matplotlib: about 110 MiB).
    before_mib = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    core_seconds = [0.0]
    for name in ("simulate_batch", "simulate_batch_columns"):
        original = getattr(_rfcore, name)

        def timed(*args: Any, _original: Any = original, **kwargs: Any) -> Any:
            t = time.perf_counter()
            try:
                return _original(*args, **kwargs)
            finally:
                core_seconds[0] += time.perf_counter() - t

        setattr(_rfcore, name, timed)
    started = time.perf_counter()
    if mode == "per-run":
        _per_run(sim, x0s, controller, duration_s)
    elif mode.startswith("columns"):
        dtype = "float32" if mode.endswith("float32") else "float64"
        batch = rf.simulate_batch(sim, x0s, duration_s, controllers=controller, dtype=dtype, memory_budget_bytes=2**40)
        assert batch.position.shape == (runs, round(duration_s / sim.dt_s) + 1, 3)
    else:
        from rotorfault.studies import record_batch

        dtype = "float32" if mode.endswith("float32") else "float64"
        with tempfile.TemporaryDirectory() as tmp:
            result = record_batch(sim, x0s, duration_s, out=Path(tmp) / "runs", controllers=controller, dtype=dtype)
            size = sum(f.stat().st_size for f in (Path(tmp) / "runs").iterdir())
            assert result.total_rows == runs
    seconds = time.perf_counter() - started
    peak_mib = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024  # KiB on Linux
    record = {"mode": mode, "seconds": seconds, "core_seconds": core_seconds[0], "peak_rss_mib": peak_mib, "before_mib": before_mib}
    if mode.startswith("stream"):
        record["parquet_mib"] = size / 2**20
    return record


def _run_child(mode: str, runs: int, duration_s: float) -> dict[str, Any]:
    proc = subprocess.run([sys.executable, __file__, "--child", mode, "--runs", str(runs), "--duration", str(duration_s)],
                          check=True, capture_output=True, text=True)
    return dict(json.loads(proc.stdout.strip().splitlines()[-1]))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=RUNS)
    parser.add_argument("--duration", type=float, default=DURATION_S)
    parser.add_argument("--child", choices=MODES, help=argparse.SUPPRESS)
    sys.path.insert(0, str(Path(__file__).parent))
    from _results import add_json_option, figure, write

    add_json_option(parser)
    args = parser.parse_args()
    if args.child:
        print(json.dumps(child(args.child, args.runs, args.duration)))
        return
    print(f"{args.runs:,} runs x {args.duration:g} s at 400 Hz, quad-x LQR hover; load {os.getloadavg()[0]:.1f}")
    results = {mode: _run_child(mode, args.runs, args.duration) for mode in MODES}
    base = results["per-run"]
    figures = []
    print(f"{'way':<17}{'peak RSS MiB':>14}{'before call':>13}{'vs per-run':>12}{'call s':>9}{'wrapper':>9}")
    for mode, r in results.items():
        share = (r["seconds"] - r["core_seconds"]) / r["seconds"]
        in_memory = not mode.startswith("stream")
        print(f"{mode:<17}{r['peak_rss_mib']:>14.0f}{r['before_mib']:>13.0f}{base['peak_rss_mib'] / r['peak_rss_mib']:>11.1f}x{r['seconds']:>9.2f}"
              f"{f'{share:.1%}' if in_memory else '-':>9}" + (f"   ({r['parquet_mib']:.0f} MiB of Parquet)" if not in_memory else ""))
        if mode != "per-run":
            figures.append(figure(f"peak RSS, {mode}, {args.runs} runs x {args.duration:g} s at 400 Hz", r["peak_rss_mib"] * 2**20 / 1e6, "MB",
                                  baseline="per-run recording (before the columns)", baseline_value=base["peak_rss_mib"] * 2**20 / 1e6,
                                  ratio=base["peak_rss_mib"] / r["peak_rss_mib"],
                                  target=f"<= {TARGET_RSS_MB:g} MB" if mode.startswith("stream") else None))
        if in_memory:
            base_share = (base["seconds"] - base["core_seconds"]) / base["seconds"]
            figures.append(figure(f"Python wrapper share of the call, {mode}", 100 * share, "%",
                                  baseline="per-run recording (before the columns)" if mode != "per-run" else None,
                                  baseline_value=100 * base_share if mode != "per-run" else None,
                                  ratio=base_share / share if mode != "per-run" and share > 0 else None,
                                  target=f"< {100 * TARGET_WRAPPER_SHARE:g} %" if mode != "per-run" else None))
    reduced = None if args.runs >= RUNS and args.duration >= DURATION_S else f"{args.runs} runs x {args.duration:g} s (the target is 1,000 x 10 s)"
    write(args.json_path, "recording", "Recorded batches: peak memory and the Python wrapper's share", figures, reduced=reduced)


if __name__ == "__main__":
    main()

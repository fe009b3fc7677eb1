"""Scans at scale (issue 12): streaming to Parquet and the Dask backend, against in-memory
``acai_batch`` on the same points, measured in the same run.

Run:  python benches/scan_scale.py [--points N] [--big N]

Scan: octocopter ``octo-x``, efficiencies of rotors 1..k over a regular grid (the other rotors at
1), both ACAI formulas, hover code, verdict and rank columns (``rotorfault.scan``).

1. Streaming overhead: ``acai_scan(..., out=dir)`` (chunks of 2^20 points written to Parquet, zstd)
   against the baseline: the same ``acai_batch(..., with_hover=True)`` calls (both formulas) on
   the same points in a loop, results discarded (in memory, nothing written). Target <= 1.15.
2. Dask: the same streamed scan with ``backend="dask"`` on a ``LocalCluster`` of 2 single-thread
   worker processes, chunks of 10^6 points, against the local backend. Target: time ratio <= 1.20
   (scheduling overhead <= 20 %).
3. The big scan (``--big``, default 10^8 points): streamed to Parquet, wall time and the peak
   resident memory of the process (``ru_maxrss``, measured in a fresh subprocess so the other
   parts do not count). Targets: < 600 s and < 1 GB.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import rotorfault as rf
from rotorfault.studies.scan import acai_scan

PRESET = "octo-x"


def grid(points: int) -> dict[str, np.ndarray]:
    """Axes efficiency_1..8 with at least ``points`` points: 8 levels in [0.3, 1] on each of the
    first k axes and enough levels in [0, 1] on the last one."""
    axes: dict[str, np.ndarray] = {}
    remaining = points
    r = 1
    while remaining >= 8 * 8 and r < 8:
        axes[f"efficiency_{r}"] = np.linspace(0.3, 1.0, 8)
        remaining //= 8
        r += 1
    others = int(np.prod([len(v) for v in axes.values()])) if axes else 1
    axes[f"efficiency_{r}"] = np.linspace(0.0, 1.0, max(-(-points // others), 2))
    return axes


def baseline(frame: rf.Airframe, axes: dict[str, np.ndarray], chunk: int) -> float:
    from rotorfault.studies.scan import _ScanTask

    task = _ScanTask(frame.to_toml(), tuple(axes), tuple(tuple(map(float, v)) for v in axes.values()), None, False, ("eq13",))
    total = task.total
    started = time.perf_counter()
    for start in range(0, total, chunk):
        stop = min(start + chunk, total)
        coords = task.coordinates(start, stop)
        etas = np.ones((stop - start, 8))
        for name, c in zip(axes, coords):
            etas[:, int(name.split("_")[1]) - 1] = c
        for formula in ("eq13", "facet-margin"):
            rf.acai_batch(frame, etas, formula=formula, with_hover=True)  # type: ignore[call-overload]
    return time.perf_counter() - started


def streamed(frame: rf.Airframe, axes: dict[str, np.ndarray], chunk: int, **kwargs: object) -> float:
    tmp = Path(tempfile.mkdtemp(prefix="scan-bench-"))
    try:
        started = time.perf_counter()
        acai_scan(frame, axes, out=tmp / "scan.parquet", chunk_points=chunk, progress=False, **kwargs)  # type: ignore[arg-type]
        return time.perf_counter() - started
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def big(points: int, out: str) -> None:
    frame = rf.Airframe.preset(PRESET)
    started = time.perf_counter()
    result = acai_scan(frame, grid(points), out=out, progress=True)
    seconds = time.perf_counter() - started
    rss_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    size = sum(p.stat().st_size for p in Path(out).iterdir())
    print(json.dumps({"points": result.total, "seconds": seconds, "peak_rss_mb": rss_mb, "bytes": size, "controllable": result.controllable_count()}))


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--points", type=int, default=8_000_000, help="points of parts 1 and 2")
    parser.add_argument("--big", type=int, default=100_000_000, help="points of part 3 (0: skip)")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--big-child", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.big_child:
        big(args.big, args.big_child)
        return
    from rotorfault._util.optional import MissingDependency, require_available

    try:  # before any work: part 2 runs on a Dask LocalCluster
        require_available("the Dask part of this bench", "dask", "distributed")
    except MissingDependency as exc:
        raise SystemExit(str(exc)) from None
    frame = rf.Airframe.preset(PRESET)
    axes = grid(args.points)
    total = int(np.prod([len(v) for v in axes.values()]))
    print(f"octo-x efficiency scan, {total:,} points, {os.cpu_count()} CPUs, load {os.getloadavg()[0]:.1f}")
    # 1. streaming + Parquet vs in-memory acai_batch (interleaved rounds, best of each).
    base, stream = [], []
    for _ in range(args.rounds):
        base.append(baseline(frame, axes, 1 << 20))
        stream.append(streamed(frame, axes, 1 << 20))
    b, s = min(base), min(stream)
    print(f"1. in-memory acai_batch (both formulas): {b:.2f} s ({total / b:,.0f} points/s)")
    print(f"   streamed to Parquet (local backend):  {s:.2f} s ({total / s:,.0f} points/s)")
    print(f"   ratio streamed / in-memory = {s / b:.3f}  (target <= 1.15)")
    # 2. Dask LocalCluster, 2 workers, chunks of 10^6.
    from distributed import Client, LocalCluster

    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0") as cluster, Client(cluster) as client:
        streamed(frame, grid(2_000_000), 1_000_000, backend="dask", dask=client)  # warm the workers
        local, remote = [], []
        for _ in range(args.rounds):
            local.append(streamed(frame, axes, 1_000_000))
            remote.append(streamed(frame, axes, 1_000_000, backend="dask", dask=client))
    lo, re_ = min(local), min(remote)
    print(f"2. local backend, chunks of 10^6:       {lo:.2f} s ({total / lo:,.0f} points/s)")
    print(f"   Dask LocalCluster, 2 workers:         {re_:.2f} s ({total / re_:,.0f} points/s)")
    print(f"   ratio dask / local = {re_ / lo:.3f}  (target <= 1.20)")
    # 3. The big scan in a fresh process (its own peak RSS).
    if args.big:
        tmp = Path(tempfile.mkdtemp(prefix="scan-big-"))
        try:
            proc = subprocess.run(
                [sys.executable, __file__, "--big", str(args.big), "--big-child", str(tmp / "big.parquet")],
                check=True, capture_output=True, text=True,
            )
        finally:
            shutil.rmtree(tmp, ignore_errors=True)
        r = json.loads(proc.stdout.strip().splitlines()[-1])
        print(
            f"3. {r['points']:,}-point scan streamed to Parquet: {r['seconds']:.0f} s ({r['points'] / r['seconds']:,.0f} points/s; "
            f"target < 600 s), peak RSS {r['peak_rss_mb']:.0f} MB (target < 1024 MB), {r['bytes'] / 1e9:.2f} GB on disk, "
            f"{r['controllable']:,} controllable"
        )


if __name__ == "__main__":
    main()

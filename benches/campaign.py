"""Fault campaigns: summaries-only throughput and one robust tuning run.

Run:  python benches/campaign.py [--runs N] [--quick]

(a) ``run_campaign``: N runs (default 100,000; ``--quick`` 2,000) of 30 s of Ke's FTC
    (``ke-hil``, 400 Hz, 4 substeps) through every single failure at a random time, per-run
    summaries only; control steps/s and peak memory (ru_maxrss).
(b) baseline in the same run: the same runs' faults through ``simulate_batch`` with recording
    thinned to 1 Hz (``record_every=400``), on the first 1,000 runs: the previous fastest path.
(c) one tuning run: differential evolution over 5 Ke gains, >= 50 candidates x 200 scenarios
    (single and double failures), validated on a fresh campaign (``--quick``: 12 x 24).
(d) the same campaign as (a) streamed to Parquet (``run_campaign(out=...)``) on the local backend
    and on a Dask ``LocalCluster`` of 2 single-thread worker processes (started and warmed before
    timing), interleaved rounds, best of each; the Dask overhead is dask / local - 1.
Targets (issue 13): (a) >= 1.5 M control steps/s on 2 cores, memory < 1 GB; (c) < 15 minutes;
(d) Dask overhead <= 20 %.

A small run (the machine shared): ``python benches/campaign.py --runs 2000 --chunk-size 250
--skip-tuning`` (``--skip-dask`` leaves (d) out).
"""

from __future__ import annotations

import argparse
import os
import resource
import shutil
import tempfile
import time
from pathlib import Path


import rotorfault as rf
from rotorfault.studies import Campaign, run_campaign, tune, tuning_campaign


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--runs", type=int, default=None)
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--skip-tuning", action="store_true")
    parser.add_argument("--skip-dask", action="store_true")
    parser.add_argument("--chunk-size", type=int, default=2_000, help="runs per chunk (the unit Dask distributes)")
    parser.add_argument("--rounds", type=int, default=1, help="rounds of (d), interleaved, best of each")
    args = parser.parse_args()
    if not args.skip_dask:
        from rotorfault._util.optional import MissingDependency, require_available

        try:  # before any work (--skip-dask leaves the comparison out)
            require_available("the Dask comparison (--skip-dask leaves it out)", "dask", "distributed")
        except MissingDependency as exc:
            raise SystemExit(str(exc)) from None
    runs = args.runs or (2_000 if args.quick else 100_000)
    print(f"rotorfault {rf.__version__}, {os.cpu_count()} CPUs, load {os.getloadavg()[0]:.1f}")
    c = Campaign(runs=runs, seed=1, duration_s=30.0, chunk_size=args.chunk_size)
    steps = runs * 12_000
    t = time.perf_counter()
    result = run_campaign(c, progress=True)
    wall = time.perf_counter() - t
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**20
    rate = steps / wall
    print(f"(a) campaign, summaries only: {runs:,} runs, {steps / 1e6:.0f} M control steps in {wall:.1f} s: "
          f"{rate / 1e6:.2f} M steps/s; peak RSS {rss:.2f} GiB; survival {100 * result.survival()[0].rate:.1f} %")
    n = min(1_000, runs)
    specs = [c.sample(i) for i in range(n)]
    sim = c.nominal_simulator()
    controller = c.controller_object()
    t = time.perf_counter()
    rf.simulate_batch(sim, [rf.State(position=(0, 0, -10))] * n, 30.0, controllers=controller,
                      faults=[s.faults(c) for s in specs], record_every=400)
    base = n * 12_000 / (time.perf_counter() - t)
    print(f"(b) baseline simulate_batch, record_every=400, {n:,} runs: {base / 1e6:.2f} M steps/s; ratio (a)/(b) = {rate / base:.2f}")
    print(f"    target >= 1.5 M steps/s: {'PASS' if rate >= 1.5e6 else 'FAIL'}; memory < 1 GiB: {'PASS' if rss < 1 else 'FAIL'}")
    if not args.skip_dask:
        dask_overhead(c, args.rounds)
    if args.skip_tuning:
        return
    scenarios, (maxiter, popsize) = (24, (1, 1)) if args.quick else (200, (9, 1))
    t = time.perf_counter()
    tuned = tune(tuning_campaign(runs=scenarios), maxiter=maxiter, popsize=popsize, progress=True)
    wall = time.perf_counter() - t
    print(tuned.table())
    print(f"(c) tuning: {tuned.candidates} candidates x {tuned.scenarios} scenarios in {wall / 60:.1f} min "
          f"(target < 15 min: {'PASS' if wall < 900 else 'FAIL'})")


def dask_overhead(c: Campaign, rounds: int) -> None:
    from dataclasses import replace

    from distributed import Client, LocalCluster

    tmp = Path(tempfile.mkdtemp(prefix="campaign-bench-"))
    steps = c.runs * round(c.duration_s / c.dt_s)

    def streamed(name: str, **kwargs: object) -> float:
        out = tmp / name
        t = time.perf_counter()
        run_campaign(c, out=out, force=True, **kwargs)  # type: ignore[arg-type]
        return time.perf_counter() - t

    try:
        t = time.perf_counter()
        with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0") as cluster, Client(cluster) as client:
            start = time.perf_counter() - t
            warm = replace(c, runs=4, chunk_size=2, duration_s=2.0, fault_time_s=(0.5, 1.0))
            run_campaign(warm, backend="dask", dask=client)  # imports and presets cached on every worker
            local, remote = [], []
            for _ in range(rounds):
                local.append(streamed("local"))
                remote.append(streamed("dask", backend="dask", dask=client))
        lo, re_ = min(local), min(remote)
        chunks = c.chunk_count()
        print(f"(d) the campaign of (a) streamed to Parquet, {chunks} chunks of {c.chunk_size} runs, best of {rounds}:")
        print(f"    local backend:                    {lo:.1f} s ({steps / lo / 1e6:.2f} M steps/s)")
        print(f"    Dask LocalCluster, 2 workers:     {re_:.1f} s ({steps / re_ / 1e6:.2f} M steps/s); cluster start {start:.1f} s, not counted")
        print(f"    ratio dask / local = {re_ / lo:.3f}: overhead {100 * (re_ / lo - 1):+.1f} % "
              f"(target <= 20 %: {'PASS' if re_ / lo <= 1.2 else 'FAIL'})")
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()

"""Scale out, measured (issue 32): the same campaign on a Dask LocalCluster of 1 worker and of 2.

Run:  python benches/scale_out.py [--runs N] [--duration S] [--rounds R] [--json PATH]
      (defaults: 400 runs of 10 s, 8 chunks, 2 rounds: about 2 minutes on an idle 2-core machine)

The campaign: ``Campaign(runs=N, seed=1, duration_s=S)`` (Ke's FTC on ke-hil at 400 Hz, every
single failure at a random time, per-run summaries), cut into 8 chunks, so each of 2 workers
gets 4 chunks and neither waits long for the last one.

(a) Dask ``LocalCluster(n_workers=W, threads_per_worker=1, processes=True)``, W = 1 and W = 2,
    both started and warmed before timing (a tiny campaign imports everything on every worker),
    then timed in interleaved rounds (1, 2, 1, 2, ...), best of each. Each worker process runs
    the Rust batches on one rayon thread (``RAYON_NUM_THREADS=1`` in the workers' environment,
    what ``dask="local:N"`` sets on a machine of N cores): otherwise one worker already keeps
    every core busy and there is nothing left for a second. Target: W = 2 >= 1.8x W = 1.
(b) the ceiling of the same split on this machine: the same chunks (``run_chunk``, the function a
    worker runs) in a ``multiprocessing`` pool (spawn) of 1 process and of 2, with the same
    one-thread setting, interleaved with (a). No scheduler, no serialisation of results: what two
    processes of this work gain here at all.

Rows are checked identical between every variant before anything is reported. The load
average is printed before and after: on a shared machine the ratio is bounded by the cores the
other jobs leave free, and (b) shows that bound.
"""

from __future__ import annotations

import argparse
import logging
import multiprocessing
import os
import time
from dataclasses import replace

import numpy as np

import rotorfault as rf
from rotorfault.studies import Campaign, run_campaign
from rotorfault.studies.campaign import run_chunk

CHUNKS = 8
TARGET = 1.8
ONE_THREAD = {"RAYON_NUM_THREADS": "1"}


def load() -> str:
    one, five, fifteen = os.getloadavg()
    return f"{one:.2f}, {five:.2f}, {fifteen:.2f}"


def pool_chunks(pool: multiprocessing.pool.Pool, campaign: Campaign) -> list[dict[str, np.ndarray]]:
    return pool.starmap(run_chunk, [(campaign, i) for i in range(campaign.chunk_count())], chunksize=1)


def main() -> None:
    from _results import add_json_option, figure, write
    from distributed import Client, LocalCluster

    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--runs", type=int, default=400)
    parser.add_argument("--duration", type=float, default=10.0, help="seconds flown per run")
    parser.add_argument("--rounds", type=int, default=2)
    add_json_option(parser)
    args = parser.parse_args()
    if args.runs < CHUNKS or args.runs % CHUNKS:
        raise SystemExit(f"--runs: a positive multiple of {CHUNKS} (the chunks), got {args.runs}")
    campaign = Campaign(runs=args.runs, seed=1, duration_s=args.duration, chunk_size=args.runs // CHUNKS)
    steps = campaign.runs * round(campaign.duration_s / campaign.dt_s)
    cores = len(os.sched_getaffinity(0))
    print(f"rotorfault {rf.__version__}, {cores} usable cores; load average (1, 5, 15 min) before: {load()}")
    print(f"campaign: {campaign.runs} runs x {campaign.duration_s:g} s at {1 / campaign.dt_s:g} Hz = "
          f"{steps / 1e6:.1f} M control steps, {campaign.chunk_count()} chunks of {campaign.chunk_size}")

    # The pools' children read the variable when their rayon pool starts; spawn gives fresh processes.
    os.environ.update(ONE_THREAD)
    spawn = multiprocessing.get_context("spawn")
    warm = replace(campaign, runs=4, chunk_size=2, duration_s=1.0, fault_time_s=(0.5, 0.6))
    times: dict[str, list[float]] = {"dask1": [], "dask2": [], "pool1": [], "pool2": []}
    rows: dict[str, dict[str, np.ndarray]] = {}
    clusters = [LocalCluster(n_workers=w, threads_per_worker=1, processes=True, dashboard_address=":0", env=ONE_THREAD,
                             silence_logs=logging.ERROR)
                for w in (1, 2)]
    try:
        clients = [Client(cluster) for cluster in clusters]
        pools = [spawn.Pool(w) for w in (1, 2)]
        for client in clients:
            run_campaign(warm, backend="dask", dask=client)
        for pool in pools:
            pool_chunks(pool, warm)
        for _ in range(args.rounds):
            for w, (client, pool) in enumerate(zip(clients, pools), start=1):
                t = time.perf_counter()
                result = run_campaign(campaign, backend="dask", dask=client)
                times[f"dask{w}"].append(time.perf_counter() - t)
                rows[f"dask{w}"] = result.columns
                t = time.perf_counter()
                chunks = pool_chunks(pool, campaign)
                times[f"pool{w}"].append(time.perf_counter() - t)
                rows[f"pool{w}"] = {k: np.concatenate([c[k] for c in chunks]) for k in chunks[0]}
        for pool in pools:
            pool.close()
        for client in clients:
            client.close()
    finally:
        for cluster in clusters:
            cluster.close()
    reference = rows["dask1"]
    for name, got in rows.items():
        for key, ref in reference.items():
            if not np.array_equal(got[key], ref, equal_nan=ref.dtype.kind == "f"):
                raise AssertionError(f"{name}: column {key} differs from one Dask worker's")
    print(f"rows identical in all four variants (all {len(reference)} columns); load average after: {load()}")
    best = {k: min(v) for k, v in times.items()}
    dask_ratio = best["dask1"] / best["dask2"]
    pool_ratio = best["pool1"] / best["pool2"]
    print(f"\nbest of {args.rounds} interleaved rounds (s), control steps/s (the machine is shared: the best round is the one"
          " least disturbed by other jobs):")
    for key, label in [("dask1", "(a) Dask LocalCluster, 1 worker"), ("dask2", "(a) Dask LocalCluster, 2 workers"),
                       ("pool1", "(b) multiprocessing, 1 process"), ("pool2", "(b) multiprocessing, 2 processes")]:
        print(f"  {label:<36} {best[key]:7.2f} s  {steps / best[key] / 1e6:6.2f} M steps/s   (all: "
              + ", ".join(f"{t:.2f}" for t in times[key]) + ")")
    print(f"\n(a) Dask 2 workers / 1 worker: {dask_ratio:.2f}x (target >= {TARGET}x: {'PASS' if dask_ratio >= TARGET else 'MISS'})")
    print(f"(b) the ceiling here, multiprocessing 2 / 1: {pool_ratio:.2f}x; Dask reaches {dask_ratio / pool_ratio:.0%} of it")
    write(args.json_path, "scale_out", f"a campaign ({campaign.runs} runs x {campaign.duration_s:g} s) on a Dask LocalCluster, 2 workers vs 1", [
        figure("Dask LocalCluster, 2 workers", steps / best["dask2"], "control steps/s", baseline="the same cluster with 1 worker",
               baseline_value=steps / best["dask1"], ratio=dask_ratio, target=f">= {TARGET}x"),
        figure("multiprocessing, 2 processes (the ceiling of the split)", steps / best["pool2"], "control steps/s",
               baseline="1 process", baseline_value=steps / best["pool1"], ratio=pool_ratio),
    ])


if __name__ == "__main__":
    main()

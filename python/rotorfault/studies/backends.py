"""Execution backends: where a study's work runs. ``"local"``: a small thread pool on this
machine (the Rust kernels release the GIL and are parallel themselves; the pool only overlaps
computing one chunk with writing the previous one, or flies two chunks of runs side by side).
``"dask"``: the same picklable tasks on a ``dask.distributed`` cluster (a ``Client``, an address
``"tcp://host:port"``, or ``"local:N"`` for a ``LocalCluster`` of N worker processes made for the
call); Dask schedules, retries and, when a worker dies, recomputes its tasks elsewhere. Results
come back to the caller in a known order, so the caller stays the only writer.
"""

from __future__ import annotations

import contextlib
import os
from collections.abc import Callable, Iterable, Iterator
from concurrent.futures import Future, ThreadPoolExecutor
from typing import TYPE_CHECKING, Any

from .._util.optional import require_available
from .storage import ChunkSpec

if TYPE_CHECKING:
    from distributed import Client

#: A chunk's work: rows ``spec.start`` up to ``spec.stop`` of the job, as an Arrow table.
ChunkTask = Callable[[ChunkSpec], Any]


def check_dask(dask: Any) -> None:
    """Checks, before any work or output, that the Dask backend can run here with ``dask`` (a
    Client, an address or ``"local:N"``): Dask installed, the argument well formed."""
    require_available("backend='dask'", "dask", "distributed")
    from distributed import Client

    if dask is None:
        raise ValueError("dask: backend='dask' needs a distributed.Client, an address or 'local:N'")
    if isinstance(dask, Client):
        return
    if not isinstance(dask, str):
        raise TypeError(f"dask: expected a distributed.Client, an address or 'local:N', got {type(dask).__name__}")
    if dask.startswith("local:"):
        text = dask[len("local:") :]
        if not (text.isdigit() and int(text) >= 1):
            raise ValueError(f"dask: 'local:N' needs a positive worker count N, got {dask!r}")
        if int(text) > 256:
            raise ValueError(f"dask: 'local:N' starts N worker processes on this machine; at most 256, got {dask!r}")
    elif "://" not in dask:
        raise ValueError(f"dask: expected a scheduler address like 'tcp://host:8786' or 'local:N', got {dask!r}")


@contextlib.contextmanager
def dask_client(dask: Client | str) -> Iterator[Client]:
    """A ``distributed.Client`` for ``dask``: the client itself, an address, or ``"local:N"``
    (a ``LocalCluster`` of N single-threaded worker processes, closed at the end)."""
    from distributed import Client, LocalCluster

    if isinstance(dask, Client):
        yield dask
        return
    if not isinstance(dask, str):
        raise TypeError(f"dask: expected a distributed.Client, an address or 'local:N', got {type(dask).__name__}")
    if dask.startswith("local:"):
        try:
            workers = int(dask[len("local:") :])
        except ValueError:
            workers = 0
        if workers < 1:
            raise ValueError(f"dask: 'local:N' needs a positive worker count N, got {dask!r}")
        with LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=":0", env=worker_env(workers)) as cluster, Client(cluster) as client:  # type: ignore[no-untyped-call]
            yield client
        return
    if "://" not in dask:
        raise ValueError(f"dask: expected a scheduler address like 'tcp://host:8786' or 'local:N', got {dask!r}")
    with Client(dask) as client:  # type: ignore[no-untyped-call]
        yield client


def worker_env(workers: int) -> dict[str, str]:
    """The environment of ``"local:N"``'s worker processes: each runs the Rust batches on its share
    of this machine's cores (``RAYON_NUM_THREADS``), so N workers do not start N pools of every
    core each and fight over them (measured in ``benches/scale_out.py``). A value the caller set
    is kept. Thread counts never change a result (every run is computed alone)."""
    if "RAYON_NUM_THREADS" in os.environ:
        return {}
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
    return {"RAYON_NUM_THREADS": str(max(1, cores // workers))}


def run_local(task: ChunkTask, pending: Iterable[ChunkSpec], accept: Callable[[ChunkSpec, Any], None], advance: Callable[[int], None]) -> None:
    # Two in flight: one computing while the previous is written. Results are accepted in chunk
    # order, so an interrupted local run leaves a prefix (plus at most one) of the chunks.
    in_flight = 2
    with ThreadPoolExecutor(max_workers=in_flight) as pool:
        queue: list[tuple[ChunkSpec, Future[Any]]] = []
        it = iter(pending)
        try:
            for spec in it:
                queue.append((spec, pool.submit(task, spec)))
                if len(queue) >= in_flight:
                    head, future = queue.pop(0)
                    accept(head, future.result())
                    advance(head.rows)
            while queue:
                head, future = queue.pop(0)
                accept(head, future.result())
                advance(head.rows)
        except BaseException:
            for _, future in queue:
                future.cancel()
            raise


def run_dask(client: Client, task: ChunkTask, pending: Iterable[ChunkSpec], accept: Callable[[ChunkSpec, Any], None], advance: Callable[[int], None]) -> None:
    from distributed import as_completed

    workers = max(1, len(client.scheduler_info().get("workers", {})))
    in_flight = 2 * workers
    it = iter(pending)
    # Retries cover a task that raised on a worker that then died; a killed worker's tasks are
    # rescheduled by Dask itself (up to the scheduler's allowed-failures).
    first = _take(it, in_flight)
    submitted = [client.submit(task, spec, pure=False, retries=2) for spec in first]
    specs = {future.key: spec for future, spec in zip(submitted, first)}
    queue = as_completed(submitted)  # type: ignore[no-untyped-call]
    try:
        for future in queue:
            spec = specs.pop(future.key)
            table = future.result()
            future.release()
            accept(spec, table)
            advance(spec.rows)
            for nxt in _take(it, 1):
                new = client.submit(task, nxt, pure=False, retries=2)
                specs[new.key] = nxt
                queue.add(new)  # type: ignore[no-untyped-call]
    except BaseException:
        client.cancel(list(queue.futures) if hasattr(queue, "futures") else [])  # type: ignore[no-untyped-call]
        raise


def _take(it: Iterator[ChunkSpec], n: int) -> list[ChunkSpec]:
    out = []
    for _ in range(n):
        try:
            out.append(next(it))
        except StopIteration:
            break
    return out


__all__ = ["ChunkTask", "check_dask", "dask_client", "run_dask", "run_local"]

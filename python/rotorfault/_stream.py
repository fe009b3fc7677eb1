"""Chunked work streamed to a Parquet dataset directory: resumable, atomic per chunk, on threads
or on a Dask cluster.

Generic on purpose (scans use it, fault campaigns can): a job is ``total`` rows cut into chunks
of ``chunk_rows`` with deterministic ids (chunk ``k`` holds rows ``k * chunk_rows`` up to the next
chunk); a *task* is a picklable callable ``task(spec: ChunkSpec) -> pyarrow.Table`` that returns
exactly the chunk's rows. :func:`run_chunks` runs the tasks and either concatenates the tables in
memory or writes one Parquet file per chunk into an output directory::

    out/
      _rotorfault.json          what the directory holds: kind, arguments, schema, chunking,
                                rotorfault version, any extra metadata (e.g. the airframe TOML)
      chunk-000000000.parquet   rows 0 .. chunk_rows - 1
      chunk-000000001.parquet   ...

Every file is written under a temporary name and renamed into place when complete, so a chunk
file that exists is whole; the manifest is written before any chunk and marked ``complete`` at the
end. A re-run with ``resume=True`` and the same arguments skips the chunks present (each one is
checked: readable, the expected rows and schema) and never writes a row twice; an output written
with other arguments is refused, naming the arguments that differ; ``force=True`` replaces it.

Backends: ``"local"`` runs the tasks on a small thread pool (the Rust batch kernels release the
GIL and are parallel themselves; the pool only overlaps computing one chunk with writing the
previous one). ``"dask"`` submits the same tasks to a ``dask.distributed`` cluster (a ``Client``,
an address ``"tcp://host:port"``, or ``"local:N"`` for a ``LocalCluster`` of N worker processes
made for the call); Dask schedules, retries and, when a worker dies, recomputes its tasks
elsewhere. Results come back to the caller, which is the only writer, so a chunk is written once
whatever happened on the cluster. Memory is bounded by the chunk size times the tasks in flight
(two per worker, or two locally).

This module depends only on ``_output``, ``_progress`` and ``_convert`` (not on the airframe).
"""

from __future__ import annotations

import contextlib
import errno
import json
import os
import shutil
import time
from collections.abc import Callable, Iterator, Mapping
from concurrent.futures import FIRST_COMPLETED, Future, ThreadPoolExecutor, wait
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, TypeAlias

from ._convert import flag
from ._output import _check_parent, atomic_path, write_text
from ._progress import progress_bar
from ._typing import ScanBackend as Backend

if TYPE_CHECKING:
    from distributed import Client

#: ``pyarrow.Table`` / ``pyarrow.Schema`` (pyarrow has no type information: Any to the checker).
Table: TypeAlias = Any
Schema: TypeAlias = Any


def pyarrow_module() -> Any:
    """``pyarrow``, imported on first use, with the install hint when it is missing."""
    return _import("pyarrow")


def parquet_module() -> Any:
    """``pyarrow.parquet``, imported on first use."""
    return _import("pyarrow.parquet")


def _import(name: str) -> Any:
    import importlib

    try:
        return importlib.import_module(name)
    except ImportError:
        raise ImportError(f"{name} is needed for scans at scale: pip install 'rotorfault[scale]'") from None

#: Name of the manifest inside an output directory.
STREAM_MANIFEST = "_rotorfault.json"
#: Format version of the directory layout (a reader refuses other versions).
STREAM_FORMAT = 1
CHUNK_PREFIX = "chunk-"
CHUNK_SUFFIX = ".parquet"

#: A chunk's work: rows ``spec.start`` up to ``spec.stop`` of the job, as an Arrow table.
ChunkTask: TypeAlias = Callable[["ChunkSpec"], Any]


@dataclass(frozen=True)
class ChunkSpec:
    """One chunk: its id (``index``) and its rows ``start <= row < stop`` of the whole job."""

    index: int
    start: int
    stop: int

    @property
    def rows(self) -> int:
        return self.stop - self.start


def chunk_specs(total: int, chunk_rows: int) -> list[ChunkSpec]:
    """The deterministic chunking of ``total`` rows: chunk ``k`` starts at ``k * chunk_rows``."""
    return [ChunkSpec(k, start, min(start + chunk_rows, total)) for k, start in enumerate(range(0, total, chunk_rows))]


def chunk_file_name(index: int) -> str:
    return f"{CHUNK_PREFIX}{index:09d}{CHUNK_SUFFIX}"


@dataclass(frozen=True)
class StreamResult:
    """What :func:`run_chunks` did: the in-memory table (``out=None``) or the output directory."""

    table: Table | None
    out: Path | None
    total_rows: int
    chunks: int
    #: Chunks computed in this call (the rest were already present and skipped on resume).
    computed_chunks: int
    skipped_chunks: int
    seconds: float


# -- the output directory ---------------------------------------------------------------------------


def read_manifest(path: str | os.PathLike[str]) -> dict[str, Any]:
    """The manifest of a streamed output directory (ValueError if it is not one)."""
    p = Path(path)
    manifest = p / STREAM_MANIFEST
    if not p.is_dir() or not manifest.is_file():
        raise ValueError(f"out: {str(p)!r} is not a rotorfault streamed output (no {STREAM_MANIFEST} inside)")
    try:
        data = json.loads(manifest.read_text(encoding="utf-8"))
    except (OSError, ValueError) as exc:
        raise ValueError(f"out: {str(manifest)!r} is unreadable ({exc})") from None
    if not isinstance(data, dict) or data.get("format") != STREAM_FORMAT:
        raise ValueError(f"out: {str(manifest)!r} is not a format-{STREAM_FORMAT} rotorfault manifest")
    return data


def _describe_differences(old: Mapping[str, Any], new: Mapping[str, Any]) -> str:
    keys = sorted(set(old) | set(new))
    parts = []
    for key in keys:
        if old.get(key) != new.get(key):
            a, b = json.dumps(old.get(key)), json.dumps(new.get(key))
            a = a if len(a) <= 60 else a[:57] + "..."
            b = b if len(b) <= 60 else b[:57] + "..."
            parts.append(f"{key} (written {a}, asked {b})")
    return "; ".join(parts)


def _prepare_output(out: Path, identity: dict[str, Any], *, resume: bool, force: bool) -> set[int]:
    """Checks ``out`` before any work and returns the chunk ids already complete (resume)."""
    _check_parent("out", out.absolute())
    if out.exists() and not out.is_dir():
        raise ValueError(f"out: {str(out)!r} exists and is not a directory (a streamed output is a directory of Parquet files)")
    if not out.is_dir() or not any(out.iterdir()):
        return set()
    if not (out / STREAM_MANIFEST).is_file():
        raise ValueError(f"out: {str(out)!r} is not empty and holds no {STREAM_MANIFEST} (not a rotorfault output); choose a new or empty directory")
    old = read_manifest(out)
    foreign = sorted(
        e.name for e in out.iterdir()
        if e.name != STREAM_MANIFEST and not (e.name.startswith(CHUNK_PREFIX) and e.name.endswith(CHUNK_SUFFIX))
        and not e.name.startswith(".")
    )
    if foreign:
        raise ValueError(f"out: {str(out)!r} holds files that are not part of a rotorfault output ({', '.join(foreign[:5])}); choose a new or empty directory")
    if force:
        for entry in out.iterdir():
            entry.unlink() if not entry.is_dir() else shutil.rmtree(entry)
        return set()
    same = {k: old.get(k) for k in identity} == identity
    if not same:
        raise ValueError(
            f"out: {str(out)!r} holds an output written with other arguments: "
            f"{_describe_differences({k: old.get(k) for k in identity}, identity)}; "
            "choose another output or pass --force (force=True) to replace it"
        )
    if not resume:
        state = "a complete output" if old.get("complete") else "an interrupted output"
        raise ValueError(f"out: {str(out)!r} holds {state} of this {str(identity['kind']).removeprefix('rotorfault-')}; pass --resume (resume=True) to continue it or --force (force=True) to replace it")
    return _complete_chunks(out, identity)


def _complete_chunks(out: Path, identity: Mapping[str, Any]) -> set[int]:
    pq = parquet_module()

    expected = {spec.index: spec.rows for spec in chunk_specs(identity["total_rows"], identity["chunk_rows"])}
    done: set[int] = set()
    for entry in out.iterdir():
        name = entry.name
        if name.startswith("."):
            # A temporary file of an interrupted write: never part of the output.
            entry.unlink(missing_ok=True) if entry.is_file() else shutil.rmtree(entry, ignore_errors=True)
            continue
        if not (name.startswith(CHUNK_PREFIX) and name.endswith(CHUNK_SUFFIX)):
            continue
        try:
            index = int(name[len(CHUNK_PREFIX) : -len(CHUNK_SUFFIX)])
            meta = pq.read_metadata(entry)
            ok = index in expected and meta.num_rows == expected[index] and meta.schema.to_arrow_schema().remove_metadata().to_string() == identity["schema"]
        except (ValueError, OSError):
            ok = False
        if ok:
            done.add(index)
        else:
            # Not a chunk this job would write (should not happen: files are renamed into place
            # whole); recomputing it is the safe choice.
            entry.unlink()
    return done


def _write_chunk(out: Path, spec: ChunkSpec, table: Table, file_metadata: Mapping[str, str], compression: str) -> None:
    pq = parquet_module()

    final = out / chunk_file_name(spec.index)
    if final.exists():  # the caller is the only writer; never a second copy of a chunk
        raise RuntimeError(f"chunk {spec.index} written twice")
    table = table.replace_schema_metadata({**(table.schema.metadata or {}), **{k.encode(): v.encode() for k, v in file_metadata.items()}})
    try:
        with atomic_path(final) as tmp:
            pq.write_table(table, tmp, compression=compression)
    except OSError as exc:
        reason = os.strerror(exc.errno) if exc.errno else str(exc)
        hint = " (disk full)" if exc.errno == errno.ENOSPC else ""
        raise OSError(
            exc.errno or errno.EIO,
            f"out: writing chunk {spec.index} ({chunk_file_name(spec.index)}) to {str(out)!r} failed: {reason}{hint}; "
            "the chunks already written are complete and valid: free space or fix the directory, then re-run with --resume (resume=True)",
        ) from exc


# -- running ------------------------------------------------------------------------------------


def _check_table(spec: ChunkSpec, table: Any, schema: Schema | None) -> Table:
    pa = pyarrow_module()

    if not isinstance(table, pa.Table):
        raise TypeError(f"task: must return a pyarrow.Table, got {type(table).__name__} for chunk {spec.index}")
    if table.num_rows != spec.rows:
        raise ValueError(f"task: chunk {spec.index} must have {spec.rows} rows, got {table.num_rows}")
    if schema is not None and not table.schema.remove_metadata().equals(schema):
        raise ValueError(f"task: chunk {spec.index} has schema {table.schema} instead of {schema}")
    return table


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
        with LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=":0") as cluster, Client(cluster) as client:  # type: ignore[no-untyped-call]
            yield client
        return
    if "://" not in dask:
        raise ValueError(f"dask: expected a scheduler address like 'tcp://host:8786' or 'local:N', got {dask!r}")
    with Client(dask) as client:  # type: ignore[no-untyped-call]
        yield client


def run_chunks(
    task: ChunkTask,
    *,
    total_rows: int,
    chunk_rows: int,
    schema: Schema,
    arguments: Mapping[str, Any],
    kind: str,
    out: str | os.PathLike[str] | None = None,
    metadata: Mapping[str, Any] | None = None,
    resume: bool = False,
    force: bool = False,
    backend: Backend = "local",
    dask: Client | str | None = None,
    progress: bool | None = None,
    description: str = "chunks",
    compression: str = "zstd",
    on_chunk_written: Callable[[ChunkSpec], None] | None = None,
) -> StreamResult:
    """Runs ``task`` over every chunk of ``total_rows`` rows and gathers the tables in memory
    (``out=None``) or streams them to the directory ``out`` (see the module docstring).

    ``arguments`` (JSON-able) identify the job: with ``kind``, the schema and the chunking they
    decide whether an existing output may be resumed. ``metadata`` (JSON-able) is recorded in the
    manifest too but not compared (e.g. the rotorfault version). ``on_chunk_written`` is called
    after each chunk is in place (or gathered)."""
    pa = pyarrow_module()

    from . import _rfcore

    if not callable(task):
        raise TypeError(f"task: expected a callable returning a pyarrow.Table, got {type(task).__name__}")
    if isinstance(total_rows, bool) or not isinstance(total_rows, int) or total_rows < 0:
        raise ValueError(f"total_rows: must be a non-negative integer, got {total_rows!r}")
    if isinstance(chunk_rows, bool) or not isinstance(chunk_rows, int):
        raise TypeError(f"chunk_rows: expected an integer, got {type(chunk_rows).__name__}")
    if chunk_rows < 1:
        raise ValueError(f"chunk_rows: must be at least 1, got {chunk_rows}")
    resume = flag("resume", resume)
    force = flag("force", force)
    if backend not in ("local", "dask"):
        raise ValueError(f"backend: must be 'local' or 'dask', got {backend!r}")
    if backend == "dask" and dask is None:
        raise ValueError("dask: backend='dask' needs a distributed.Client, an address or 'local:N'")
    schema = schema.remove_metadata()
    identity: dict[str, Any] = {
        "kind": kind,
        "arguments": json.loads(json.dumps(dict(arguments))),
        "schema": schema.to_string(),
        "total_rows": total_rows,
        "chunk_rows": chunk_rows,
    }
    specs = chunk_specs(total_rows, chunk_rows)
    out_path: Path | None = None
    done: set[int] = set()
    started = time.perf_counter()
    if out is not None:
        if not isinstance(out, (str, os.PathLike)):
            raise TypeError(f"out: expected a directory path, got {type(out).__name__}")
        out_path = Path(out)
        done = _prepare_output(out_path, identity, resume=resume, force=force)
        manifest = {
            "format": STREAM_FORMAT,
            **identity,
            "chunks": len(specs),
            "chunk_file": f"{CHUNK_PREFIX}<index, 9 digits>{CHUNK_SUFFIX}",
            "rotorfault_version": _rfcore.__version__,
            "metadata": json.loads(json.dumps(dict(metadata or {}))),
            "complete": False,
        }
        out_path.mkdir(exist_ok=True)
        write_text(out_path / STREAM_MANIFEST, json.dumps(manifest, indent=2) + "\n")
        file_metadata = {"rotorfault": json.dumps({k: manifest[k] for k in ("kind", "arguments", "rotorfault_version", "total_rows", "chunk_rows")})}
    pending = [spec for spec in specs if spec.index not in done]
    gathered: dict[int, Table] = {}

    def accept(spec: ChunkSpec, table: Any) -> None:
        table = _check_table(spec, table, schema)
        if out_path is None:
            gathered[spec.index] = table
        else:
            _write_chunk(out_path, spec, table, file_metadata, compression)
        if on_chunk_written is not None:
            on_chunk_written(spec)

    already = sum(spec.rows for spec in specs if spec.index in done)
    with progress_bar(total_rows, description=description, show=progress, default_show=total_rows > 10_000_000, completed=already) as advance:
        if not pending:
            pass  # nothing left (a complete output resumed): no cluster is started
        elif backend == "local":
            _run_local(task, pending, accept, advance)
        else:
            assert dask is not None
            with dask_client(dask) as client:
                _run_dask(client, task, pending, accept, advance)
    if out_path is not None:
        manifest["complete"] = True
        write_text(out_path / STREAM_MANIFEST, json.dumps(manifest, indent=2) + "\n")
        table = None
    else:
        table = pa.concat_tables([gathered[k] for k in sorted(gathered)]) if gathered else schema.empty_table()
    return StreamResult(table, out_path, total_rows, len(specs), len(pending), len(done), time.perf_counter() - started)


def _run_local(task: ChunkTask, pending: list[ChunkSpec], accept: Callable[[ChunkSpec, Any], None], advance: Callable[[int], None]) -> None:
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


def _run_dask(client: Client, task: ChunkTask, pending: list[ChunkSpec], accept: Callable[[ChunkSpec, Any], None], advance: Callable[[int], None]) -> None:
    from distributed import as_completed

    workers = max(1, len(client.scheduler_info().get("workers", {})))
    in_flight = 2 * workers
    it = iter(pending)
    # Retries cover a task that raised on a worker that then died; a killed worker's tasks are
    # rescheduled by Dask itself (up to the scheduler's allowed-failures).
    submitted = [client.submit(task, spec, pure=False, retries=2) for spec in _take(it, in_flight)]
    specs = {future.key: spec for future, spec in zip(submitted, pending)}
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


def iter_tables(path: str | os.PathLike[str], columns: list[str] | None = None, *, require_complete: bool = True) -> Iterator[Table]:
    """The chunks of a streamed output, in row order, one table at a time (``columns``: only
    these), so an output larger than memory can be read chunk by chunk."""
    pq = parquet_module()

    p = Path(path)
    manifest = read_manifest(p)
    if require_complete and not manifest.get("complete"):
        raise ValueError(f"out: {str(p)!r} is an interrupted output; finish it with --resume (resume=True) first")
    for spec in chunk_specs(manifest["total_rows"], manifest["chunk_rows"]):
        file = p / chunk_file_name(spec.index)
        if not file.is_file():
            if require_complete:
                raise ValueError(f"out: {str(p)!r} is missing {file.name}")
            continue
        yield pq.read_table(file, columns=columns)


__all__ = [
    "Backend",
    "ChunkSpec",
    "ChunkTask",
    "STREAM_MANIFEST",
    "StreamResult",
    "chunk_file_name",
    "chunk_specs",
    "dask_client",
    "iter_tables",
    "parquet_module",
    "pyarrow_module",
    "read_manifest",
    "run_chunks",
]

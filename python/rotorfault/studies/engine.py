"""The study engine: one job of many rows (a scan's points, a campaign's runs), cut into
chunks, computed on an execution backend (:mod:`~rotorfault.studies.backends`: threads or Dask)
and gathered in memory or written to a Parquet directory (:mod:`~rotorfault.studies.storage`).

A *task* is a picklable callable ``task(spec: ChunkSpec) -> pyarrow.Table`` that returns exactly
the chunk's rows; :func:`run_chunks` runs it over every chunk not already written. Memory is
bounded by the chunk size times the tasks in flight (two per worker, or two locally).
"""

from __future__ import annotations

import contextlib
import json
import os
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from .._typing import ScanBackend as Backend
from .._util.convert import flag
from .._util.lock import output_lock
from .._util.output import check_parent, write_text
from .._util.progress import progress_bar
from .backends import ChunkTask, check_dask, dask_client, run_dask, run_local
from .storage import (
    CHUNK_PREFIX,
    CHUNK_SUFFIX,
    STREAM_FORMAT,
    STREAM_MANIFEST,
    ChunkSpec,
    Schema,
    Table,
    chunk_count,
    chunk_spec,
    chunk_specs,
    prepare_output,
    pyarrow_module,
    write_chunk,
)

if TYPE_CHECKING:
    from distributed import Client


#: The most a study gathers in memory (``out=None``): 1 GiB of result columns. The machine it
#: was sized on has 24 GB shared by several jobs, and reading the result (``to_pandas()``, a
#: campaign's NumPy columns) copies it once more; above this a study streams to Parquet (``out=``,
#: CLI ``--out``), whose memory is bounded by the chunk size instead.
MAX_IN_MEMORY_BYTES = 1 << 30
#: What one string cell is counted as: Arrow's 4-byte offset and its characters, plus the NumPy
#: copy of 4 bytes per character a campaign's columns keep (its strings are short words and rotor
#: lists, well under 12 characters).
STRING_CELL_BYTES = 64


def row_bytes(schema: Schema) -> int:
    """Bytes one row of ``schema`` takes in memory: each fixed-width column's width (a bool
    counted as NumPy's one byte, not Arrow's bit), a string as :data:`STRING_CELL_BYTES`. A scan
    over three efficiency axes with both formulas takes 3 x 8 + 2 x 8 + 3 = 43 bytes a row; a
    campaign's row 472."""
    pa = pyarrow_module()

    total = 0
    for f in schema:
        if pa.types.is_string(f.type) or pa.types.is_large_string(f.type):
            total += STRING_CELL_BYTES
        elif pa.types.is_boolean(f.type):
            total += 1
        else:
            total += f.type.bit_width // 8
    return total


def check_in_memory(field: str, rows: int, bytes_per_row: int, *, remedy: str = "stream them to Parquet with out=DIR (CLI: --out DIR)",
                    at_least: bool = False) -> None:
    """Refuses, naming ``field``, a result of ``rows`` rows of ``bytes_per_row`` bytes that would
    exceed :data:`MAX_IN_MEMORY_BYTES` (on Python integers: never wraps), before any work.
    ``at_least``: ``rows`` is a lower bound (the count was stopped once past the limit)."""
    need = rows * bytes_per_row
    if need > MAX_IN_MEMORY_BYTES:
        most = MAX_IN_MEMORY_BYTES // bytes_per_row
        raise ValueError(
            f"{field}: {'at least ' if at_least else ''}{rows:,} rows of {bytes_per_row} bytes ({need / 2**30:,.1f} GiB) exceed the in-memory limit of "
            f"{MAX_IN_MEMORY_BYTES / 2**30:g} GiB of results ({most:,} rows); {remedy}"
        )


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


def _check_table(spec: ChunkSpec, table: Any, schema: Schema | None) -> Table:
    pa = pyarrow_module()

    if not isinstance(table, pa.Table):
        raise TypeError(f"task: must return a pyarrow.Table, got {type(table).__name__} for chunk {spec.index}")
    if table.num_rows != spec.rows:
        raise ValueError(f"task: chunk {spec.index} must have {spec.rows} rows, got {table.num_rows}")
    if schema is not None and not table.schema.remove_metadata().equals(schema):
        raise ValueError(f"task: chunk {spec.index} has schema {table.schema} instead of {schema}")
    return table


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
    rows_field: str = "total_rows",
) -> StreamResult:
    """Runs ``task`` over every chunk of ``total_rows`` rows and gathers the tables in memory
    (``out=None``) or streams them to the directory ``out`` (see the module docstring).

    ``arguments`` (JSON-able) identify the job: with ``kind``, the schema and the chunking they
    decide whether an existing output may be resumed. ``metadata`` (JSON-able) is recorded in the
    manifest too but not compared (e.g. the rotorfault version). ``on_chunk_written`` is called
    after each chunk is in place (or gathered). Gathered in memory, the rows may take at most
    :data:`MAX_IN_MEMORY_BYTES` (:func:`row_bytes` of ``schema`` each): more is refused before
    any work, naming ``rows_field`` (the caller's name for the row count)."""
    pyarrow_module()  # the install hint before anything else

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
    if backend == "dask":
        check_dask(dask)
    schema = schema.remove_metadata()
    if out is None:
        check_in_memory(rows_field, total_rows, row_bytes(schema))
    identity: dict[str, Any] = {
        "kind": kind,
        "arguments": json.loads(json.dumps(dict(arguments))),
        "schema": schema.to_string(),
        "total_rows": total_rows,
        "chunk_rows": chunk_rows,
    }
    specs = chunk_count(total_rows, chunk_rows)
    out_path: Path | None = None
    done: set[int] = set()
    started = time.perf_counter()
    held = contextlib.ExitStack()
    if out is not None:
        if not isinstance(out, (str, os.PathLike)):
            raise TypeError(f"out: expected a directory path, got {type(out).__name__}")
        out_path = Path(out)
        check_parent("out", out_path.absolute())
        # One writer: the lock is taken before the directory is looked at and held until the
        # manifest says complete (a second run, --resume or --force is refused, naming this one).
        held.enter_context(output_lock("out", out_path))
    with held:
        return _run(task, specs, identity, out_path, done, started, resume, force, metadata, schema, backend, dask,
                    progress, description, compression, on_chunk_written, total_rows)


def _run(
    task: ChunkTask, chunks: int, identity: dict[str, Any], out_path: Path | None, done: set[int], started: float,
    resume: bool, force: bool, metadata: Mapping[str, Any] | None, schema: Schema, backend: Backend, dask: Any,
    progress: bool | None, description: str, compression: str, on_chunk_written: Callable[[ChunkSpec], None] | None,
    total_rows: int,
) -> StreamResult:
    pa = pyarrow_module()

    from .. import _rfcore

    if out_path is not None:
        done = prepare_output(out_path, identity, resume=resume, force=force)
        manifest = {
            "format": STREAM_FORMAT,
            **identity,
            "chunks": chunks,
            "chunk_file": f"{CHUNK_PREFIX}<index, 9 digits>{CHUNK_SUFFIX}",
            "rotorfault_version": _rfcore.__version__,
            "metadata": json.loads(json.dumps(dict(metadata or {}))),
            "complete": False,
        }
        out_path.mkdir(exist_ok=True)
        write_text(out_path / STREAM_MANIFEST, json.dumps(manifest, indent=2) + "\n")
        file_metadata = {"rotorfault": json.dumps({k: manifest[k] for k in ("kind", "arguments", "rotorfault_version", "total_rows", "chunk_rows")})}
    # Made one at a time: the plan of a huge job takes no memory.
    pending = (spec for spec in chunk_specs(total_rows, identity["chunk_rows"]) if spec.index not in done)
    pending_count = chunks - len(done)
    gathered: dict[int, Table] = {}

    def accept(spec: ChunkSpec, table: Any) -> None:
        table = _check_table(spec, table, schema)
        if out_path is None:
            gathered[spec.index] = table
        else:
            write_chunk(out_path, spec, table, file_metadata, compression)
        if on_chunk_written is not None:
            on_chunk_written(spec)

    already = sum(chunk_spec(k, total_rows, identity["chunk_rows"]).rows for k in done)
    with progress_bar(total_rows, description=description, show=progress, default_show=total_rows > 10_000_000, completed=already) as advance:
        if not pending_count:
            pass  # nothing left (a complete output resumed): no cluster is started
        elif backend == "local":
            run_local(task, pending, accept, advance)
        else:
            assert dask is not None
            with dask_client(dask) as client:
                run_dask(client, task, pending, accept, advance)
    if out_path is not None:
        manifest["complete"] = True
        write_text(out_path / STREAM_MANIFEST, json.dumps(manifest, indent=2) + "\n")
        table = None
    else:
        table = pa.concat_tables([gathered[k] for k in sorted(gathered)]) if gathered else schema.empty_table()
    return StreamResult(table, out_path, total_rows, chunks, pending_count, len(done), time.perf_counter() - started)


__all__ = ["Backend", "ChunkSpec", "ChunkTask", "StreamResult", "run_chunks"]

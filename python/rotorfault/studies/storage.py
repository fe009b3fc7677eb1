"""Storage of a study's rows: a Parquet dataset directory, one file per chunk, resumable.

A job is ``total`` rows cut into chunks of ``chunk_rows`` with deterministic ids (chunk ``k``
holds rows ``k * chunk_rows`` up to the next chunk)::

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
This is the one Parquet writer of the package (scans and campaigns alike).
"""

from __future__ import annotations

import errno
import json
import os
import shutil
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any, TypeAlias

from .._util.optional import require
from .._util.output import atomic_path, check_parent

#: ``pyarrow.Table`` / ``pyarrow.Schema`` (pyarrow has no type information: Any to the checker).
Table: TypeAlias = Any
Schema: TypeAlias = Any


def pyarrow_module() -> Any:
    """``pyarrow``, imported on first use (a dependency; the message names it if it is missing)."""
    return _import("pyarrow")


def parquet_module() -> Any:
    """``pyarrow.parquet``, imported on first use."""
    return _import("pyarrow.parquet")


def _import(name: str) -> Any:
    return require(name, feature="Parquet outputs of scans and campaigns")

#: Name of the manifest inside an output directory.
STREAM_MANIFEST = "_rotorfault.json"
#: Format version of the directory layout (a reader refuses other versions).
STREAM_FORMAT = 1
CHUNK_PREFIX = "chunk-"
CHUNK_SUFFIX = ".parquet"


@dataclass(frozen=True)
class ChunkSpec:
    """One chunk: its id (``index``) and its rows ``start <= row < stop`` of the whole job."""

    index: int
    start: int
    stop: int

    @property
    def rows(self) -> int:
        return self.stop - self.start


def chunk_count(total: int, chunk_rows: int) -> int:
    """How many chunks ``total`` rows make."""
    return -(-total // chunk_rows)


def chunk_spec(index: int, total: int, chunk_rows: int) -> ChunkSpec:
    """Chunk ``index`` of the deterministic chunking (:func:`chunk_specs`)."""
    start = index * chunk_rows
    return ChunkSpec(index, start, min(start + chunk_rows, total))


def chunk_specs(total: int, chunk_rows: int) -> Iterator[ChunkSpec]:
    """The deterministic chunking of ``total`` rows, one chunk at a time (a plan of 10^12 rows
    takes no memory): chunk ``k`` starts at ``k * chunk_rows``."""
    return (chunk_spec(k, total, chunk_rows) for k in range(chunk_count(total, chunk_rows)))


def chunk_file_name(index: int) -> str:
    return f"{CHUNK_PREFIX}{index:09d}{CHUNK_SUFFIX}"


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


def _describe_differences(old: Mapping[str, Any], new: Mapping[str, Any], prefix: str = "") -> str:
    """The fields that differ, by their dotted path (``arguments.certify_rule``), nested mappings
    followed down to the field so a long identity names what changed."""
    keys = sorted(set(old) | set(new))
    parts = []
    for key in keys:
        a_value, b_value = old.get(key), new.get(key)
        if a_value != b_value:
            if isinstance(a_value, Mapping) and isinstance(b_value, Mapping):
                parts.append(_describe_differences(a_value, b_value, f"{prefix}{key}."))
                continue
            a, b = json.dumps(a_value), json.dumps(b_value)
            a = a if len(a) <= 60 else a[:57] + "..."
            b = b if len(b) <= 60 else b[:57] + "..."
            parts.append(f"{prefix}{key} (written {a}, asked {b})")
    return "; ".join(parts)


def prepare_output(out: Path, identity: dict[str, Any], *, resume: bool, force: bool) -> set[int]:
    """Checks ``out`` before any work and returns the chunk ids already complete (resume)."""
    check_parent("out", out.absolute())
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
        # Recoverable at every step: the manifest is first marked incomplete (so a reader never
        # takes what is left for a whole output), the chunks go, the manifest last; an interrupted
        # --force leaves a manifest and some chunks, which --force and --resume both accept.
        if old.get("complete"):
            from .._util.output import write_text

            write_text(out / STREAM_MANIFEST, json.dumps({**old, "complete": False}, indent=2) + "\n")
        for entry in out.iterdir():
            if entry.name != STREAM_MANIFEST:
                entry.unlink() if not entry.is_dir() else shutil.rmtree(entry)
        (out / STREAM_MANIFEST).unlink()
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

    total, rows = identity["total_rows"], identity["chunk_rows"]
    count = chunk_count(total, rows)
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
            ok = (0 <= index < count and meta.num_rows == chunk_spec(index, total, rows).rows
                  and meta.schema.to_arrow_schema().remove_metadata().to_string() == identity["schema"])
        except (ValueError, OSError):
            ok = False
        if ok:
            done.add(index)
        else:
            # Not a chunk this job would write (should not happen: files are renamed into place
            # whole); recomputing it is the safe choice.
            entry.unlink()
    return done


def write_chunk(out: Path, spec: ChunkSpec, table: Table, file_metadata: Mapping[str, str], compression: str) -> None:
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
    "STREAM_MANIFEST",
    "ChunkSpec",
    "chunk_count",
    "chunk_spec",
    "Schema",
    "Table",
    "chunk_file_name",
    "chunk_specs",
    "iter_tables",
    "parquet_module",
    "pyarrow_module",
    "read_manifest",
]

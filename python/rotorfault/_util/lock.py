"""One writer per output: the lock every writer of an output (a scan's or a campaign's Parquet
directory, a report directory) holds for its whole run.

The lock is an operating-system file lock (``filelock``: ``flock`` on POSIX, ``LockFileEx`` on
Windows) on a hidden file beside the output, ``.<name>.rotorfault-lock``. The operating system
releases it when its process ends, however it ends (a ``SIGKILL`` too), so a lock is never left
behind by a killed run: whether an output is being written is known from the lock alone, never
guessed from a process id. Who holds it is a record the holder writes beside the lock once it has
it (``.<name>.rotorfault-lock.json``: process id, host, start time, command) and removes when it
lets go; a second writer (or ``--resume``, or ``--force``) is refused with a one-line
:class:`OutputInUse` error that names that process. A record found while the lock is free was
left by a process that died holding the lock: it is reported as :attr:`OutputLock.previous` and
replaced (the output itself is then recovered by its writer: see
:func:`rotorfault.studies.storage.prepare_output` and :func:`rotorfault._util.output.output_directory`).

The lock lives beside the output, not inside it, because a report directory is replaced as a
whole. Within one process the lock is re-entrant for the thread that holds it (the CLI takes it
before its checks, the library again around the writing); another thread is refused like another
process. A lock on a network file system is only as good as that file system's ``flock``.
"""

from __future__ import annotations

import contextlib
import json
import os
import socket
import sys
import threading
import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from .atomic import write_text

LOCK_SUFFIX = ".rotorfault-lock"


class OutputInUse(OSError):
    """The output is being written by another run (the message names it)."""


@dataclass
class OutputLock:
    """A held lock: the output, and the record of a previous holder that died holding it (None
    when the lock was left cleanly or never taken)."""

    out: Path
    previous: dict[str, Any] | None


def lock_file(out: str | os.PathLike[str]) -> Path:
    """The lock file of the output ``out`` (beside it)."""
    p = Path(out).absolute()
    return p.parent / f".{p.name}{LOCK_SUFFIX}"


def is_lock_file(name: str) -> bool:
    """Whether the file ``name`` is an output's lock or its holder record (they stay beside the
    output after a run: removing a lock file on release would let two writers lock different files)."""
    return name.startswith(".") and (name.endswith(LOCK_SUFFIX) or name.endswith(LOCK_SUFFIX + ".json"))


def _record_file(out: str | os.PathLike[str]) -> Path:
    lock = lock_file(out)
    return lock.with_name(lock.name + ".json")


def _read_record(path: Path) -> dict[str, Any] | None:
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError, RecursionError):
        return None
    return data if isinstance(data, dict) else None


def describe_holder(record: dict[str, Any] | None) -> str:
    """``process 123 on host since 2026-11-30 12:00:00 (rotorfault scan ...)``."""
    if record is None:
        return "another process (which has not written its details yet)"
    command = str(record.get("command", "?"))
    command = command if len(command) <= 120 else command[:117] + "..."
    return f"process {record.get('pid', '?')} on {record.get('host', '?')} since {record.get('started', '?')} ({command})"


# Held locks of this process: resolved lock path -> (the filelock, owning thread, depth).
_held: dict[Path, list[Any]] = {}
_held_guard = threading.Lock()


@contextlib.contextmanager
def output_lock(field: str, out: str | os.PathLike[str]) -> Iterator[OutputLock]:
    """Holds the lock of the output ``out`` for the block (module docs); raises
    :class:`OutputInUse` naming the holder when another run holds it. The directory ``out`` goes
    into must exist (its writers check it first)."""
    from filelock import FileLock, Timeout

    path = lock_file(out)
    key = path.resolve() if path.parent.exists() else path
    me = threading.get_ident()
    with _held_guard:
        entry = _held.get(key)
        if entry is not None:
            if entry[1] != me:
                raise OutputInUse(f"{field}: {str(out)!r} is being written by another thread of this process (pid {os.getpid()})")
            entry[2] += 1
    if entry is not None:
        try:
            yield OutputLock(Path(out), None)
        finally:
            with _held_guard:
                entry[2] -= 1
        return
    lock = FileLock(str(path))
    try:
        lock.acquire(timeout=0)
    except Timeout:
        raise OutputInUse(
            f"{field}: {str(out)!r} is being written by {describe_holder(_read_record(_record_file(out)))}; "
            "wait for it to finish or stop it (the lock goes with that process)"
        ) from None
    record_path = _record_file(out)
    previous = _read_record(record_path) if record_path.exists() else None
    try:
        record = {
            "pid": os.getpid(),
            "host": socket.gethostname(),
            "started": time.strftime("%Y-%m-%d %H:%M:%S %Z"),
            "command": " ".join([Path(sys.argv[0]).name, *sys.argv[1:]]) if sys.argv and sys.argv[0] else "python",
        }
        write_text(record_path, json.dumps(record) + "\n")
        with _held_guard:
            _held[key] = [lock, me, 1]
        try:
            yield OutputLock(Path(out), previous)
        finally:
            with _held_guard:
                _held.pop(key, None)
            record_path.unlink(missing_ok=True)
    finally:
        lock.release()


__all__ = ["LOCK_SUFFIX", "OutputInUse", "OutputLock", "describe_holder", "is_lock_file", "lock_file", "output_lock"]

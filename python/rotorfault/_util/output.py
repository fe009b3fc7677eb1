"""Files the package writes: checked before any computation, written under a temporary name in the
same directory and renamed into place only when complete, so an interrupted run never leaves a
truncated file under a final name. (Figures are drawn and saved by :mod:`rotorfault.plotting.style`,
through :func:`atomic_path`.)

This module depends on nothing else in the package but :mod:`rotorfault._util.atomic` (the
atomic write) and :mod:`rotorfault._util.lock` (one writer per output), so every room can use it.
"""

from __future__ import annotations

import contextlib
import os
import signal
import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from .atomic import _umask, atomic_path, write_text

#: File types a figure can be saved as (by extension).
FIGURE_SUFFIXES = (".png", ".pdf", ".svg")


def check_output_file(field: str, path: str | os.PathLike[str], *, suffixes: tuple[str, ...] = FIGURE_SUFFIXES, force: bool = False) -> Path:
    """Checks, before any work is done, that ``path`` can be written: a known extension, an
    existing writable directory, and no existing file unless ``force``."""
    if not isinstance(path, (str, os.PathLike)):
        raise TypeError(f"{field}: expected a file path, got {type(path).__name__}")
    p = Path(path)
    if p.suffix.lower() not in suffixes:
        raise ValueError(f"{field}: the file name must end in {', '.join(suffixes)}, got {str(p)!r}")
    if p.is_dir():
        raise ValueError(f"{field}: {str(p)!r} is a directory, expected a file name")
    check_parent(field, p)
    if p.exists() and not force:
        raise ValueError(f"{field}: {str(p)!r} exists; pass --force (force=True) to replace it")
    return p


def check_parent(field: str, p: Path) -> None:
    """The directory ``p`` goes into exists and is writable (``ValueError`` naming ``field``)."""
    parent = p.parent if str(p.parent) else Path(".")
    if not parent.is_dir():
        raise ValueError(f"{field}: directory {str(parent)!r} does not exist")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise ValueError(f"{field}: directory {str(parent)!r} is not writable")


#: The file that makes a directory a rotorfault output directory (lists its files).
MANIFEST = "manifest.json"


def check_output_directory(field: str, path: str | os.PathLike[str], *, force: bool = False) -> Path:
    """Checks, before any work is done, that the output directory ``path`` can be (re)placed: it
    does not exist, is empty, or (with ``force``) holds a previous output of this package (a
    manifest, and no file the manifest does not list). A directory with anything else in it is
    never replaced."""
    if not isinstance(path, (str, os.PathLike)):
        raise TypeError(f"{field}: expected a directory path, got {type(path).__name__}")
    p = Path(path)
    if p.exists() and not p.is_dir():
        raise ValueError(f"{field}: {str(p)!r} exists and is not a directory")
    check_parent(field, p.resolve())
    if p.is_dir() and any(p.iterdir()):
        manifest = p / MANIFEST
        if not manifest.is_file():
            raise ValueError(
                f"{field}: {str(p)!r} is not empty and holds no {MANIFEST} (not a rotorfault output); "
                "choose a new or empty directory"
            )
        import json

        try:
            listed = set(json.loads(manifest.read_text(encoding="utf-8"))["outputs"]) | {MANIFEST}
        except (ValueError, KeyError, TypeError, OSError):
            raise ValueError(f"{field}: {str(manifest)!r} is unreadable; choose a new or empty directory") from None
        foreign = sorted(entry.name for entry in p.iterdir() if entry.name not in listed)
        if foreign:
            raise ValueError(
                f"{field}: {str(p)!r} holds files its {MANIFEST} does not list ({', '.join(foreign[:5])}); "
                "choose a new or empty directory"
            )
        if not force:
            raise ValueError(f"{field}: {str(p)!r} holds a previous output; pass --force (force=True) to replace it")
    return p


def recover_output_directory(path: str | os.PathLike[str]) -> None:
    """Undoes what an interrupted writer of the output directory ``path`` left beside it (call
    with its lock held, :func:`rotorfault._util.lock.output_lock`, so every leftover is a dead
    writer's): a swap cut between its two renames is completed backwards (the previous directory
    back in place), temporary and replaced directories are removed."""
    import shutil

    final = Path(path)
    parent = final.parent if str(final.parent) else Path(".")
    if not parent.is_dir():
        return
    olds = sorted(parent.glob(f".{glob_escape(final.name)}.*.old"), key=lambda p: p.stat().st_mtime)
    if olds and not final.exists():
        os.replace(olds.pop(), final)
    for leftover in [*olds, *parent.glob(f".{glob_escape(final.name)}.*.part")]:
        shutil.rmtree(leftover, ignore_errors=True) if leftover.is_dir() else leftover.unlink(missing_ok=True)


def glob_escape(name: str) -> str:
    import glob

    return glob.escape(name)


@contextlib.contextmanager
def claim_output_directory(field: str, path: str | os.PathLike[str], *, force: bool = False) -> Iterator[Path]:
    """The one way a report command holds its output directory: the lock for the whole block (a
    second writer is refused, naming this one), what an interrupted run left recovered, then
    :func:`check_output_directory`; all before any work."""
    from .lock import output_lock

    if not isinstance(path, (str, os.PathLike)):
        raise TypeError(f"{field}: expected a directory path, got {type(path).__name__}")
    check_parent(field, Path(path).absolute())
    with output_lock(field, path):
        recover_output_directory(path)
        yield check_output_directory(field, path, force=force)


@contextlib.contextmanager
def output_directory(path: str | os.PathLike[str], manifest: dict[str, Any]) -> Iterator[Path]:
    """Yields a temporary sibling directory to fill; when the block completes, writes ``manifest``
    (plus ``outputs``: the files present) into it and swaps it in for ``path`` as one unit (the
    previous directory, if any, is removed only after the new one is in place). On any error or
    interrupt the temporary directory is removed and ``path`` is left as it was. The output's lock
    is held throughout (:func:`rotorfault._util.lock.output_lock`; re-entrant for a caller that
    holds it already). Call :func:`check_output_directory` (or :func:`claim_output_directory`) first."""
    from .lock import output_lock

    with output_lock("out", path):
        recover_output_directory(path)
        with _output_directory(path, manifest) as tmp:
            yield tmp


@contextlib.contextmanager
def _output_directory(path: str | os.PathLike[str], manifest: dict[str, Any]) -> Iterator[Path]:
    import json
    import shutil

    final = Path(path)
    tmp = Path(tempfile.mkdtemp(prefix=f".{final.name}.", suffix=".part", dir=final.parent if str(final.parent) else "."))
    os.chmod(tmp, 0o777 & ~_umask())
    old: Path | None = None
    try:
        yield tmp
        outputs = sorted(entry.name for entry in tmp.iterdir())
        write_text(tmp / MANIFEST, json.dumps({**manifest, "outputs": outputs}, indent=2) + "\n")
        with signals_deferred():
            if final.exists():
                old = final.parent / f".{final.name}.{os.getpid()}.old"
                os.replace(final, old)
            os.replace(tmp, final)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    if old is not None:
        shutil.rmtree(old, ignore_errors=True)


@contextlib.contextmanager
def signals_deferred() -> Iterator[None]:
    """Holds SIGINT and SIGTERM for the duration (a few renames), so a directory swap is not cut
    in half; they are delivered afterwards."""
    held = {signal.SIGINT, signal.SIGTERM}
    try:
        old = signal.pthread_sigmask(signal.SIG_BLOCK, held)
    except (AttributeError, ValueError, OSError):  # not the main thread, or no POSIX signals
        yield
        return
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, old)


__all__ = [
    "FIGURE_SUFFIXES",
    "MANIFEST",
    "atomic_path",
    "check_output_directory",
    "claim_output_directory",
    "check_output_file",
    "check_parent",
    "output_directory",
    "recover_output_directory",
    "signals_deferred",
    "write_text",
]

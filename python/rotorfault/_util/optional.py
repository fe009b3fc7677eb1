"""Optional dependencies: the one place that knows which extra installs which package, and the one
message when one is missing. A feature that needs an optional package asks for it *before* any
work or output (:func:`require_available`, a cheap look-up that imports nothing), then imports it
where it is used (:func:`require`); both raise an ``ImportError`` that names the feature and the
command that installs it::

    to_pandas() needs pandas, which is not installed: pip install "rotorfault[pandas]"

This module depends on nothing else in the package, so every room can use it.
"""

from __future__ import annotations

import importlib
import importlib.util
from types import ModuleType

#: The extra of ``pyproject.toml`` that installs each optional package (by import name).
EXTRAS: dict[str, str] = {
    "pandas": "pandas",
    "dask": "scale",
    "distributed": "scale",
    "rotorpy": "bench",
}


class MissingDependency(ImportError):
    """An optional package a feature needs is not installed (the message names the extra)."""


def install_hint(package: str) -> str:
    """``pip install "rotorfault[<extra>]"`` for ``package`` (its import name, e.g. ``"dask"``)."""
    top = package.split(".")[0]
    extra = EXTRAS.get(top)
    return f'pip install "rotorfault[{extra}]"' if extra else f"pip install {top}"


def _message(package: str, feature: str) -> str:
    return f"{feature} needs {package.split('.')[0]}, which is not installed: {install_hint(package)}"


def is_available(package: str) -> bool:
    """Whether ``package`` can be imported (found on the path; nothing is imported)."""
    try:
        return importlib.util.find_spec(package.split(".")[0]) is not None
    except (ImportError, ValueError):
        return False


def require_available(feature: str, *packages: str) -> None:
    """Raises :class:`MissingDependency` naming ``feature`` and the extra when any of ``packages``
    cannot be found: call it before any work or output."""
    for package in packages:
        if not is_available(package):
            raise MissingDependency(_message(package, feature))


def require(package: str, *, feature: str) -> ModuleType:
    """``package`` imported, or :class:`MissingDependency` naming ``feature`` and the extra."""
    try:
        return importlib.import_module(package)
    except ImportError as exc:
        if isinstance(exc, MissingDependency):
            raise
        missing = exc.name or package
        raise MissingDependency(_message(missing if missing.split(".")[0] in EXTRAS else package, feature)) from None


__all__ = ["EXTRAS", "MissingDependency", "install_hint", "is_available", "require", "require_available"]

"""Conversion of user input to the arrays the core reads.

Types are checked here (``TypeError`` naming the field); value rules (finite, ranges, matching
lengths) are checked once, in the Rust core, whose ``ValueError`` messages name the field too.
"""

from __future__ import annotations

import numbers
import sys
from collections.abc import Iterable
from typing import Any

import numpy as np
import numpy.typing as npt

FloatArray = npt.NDArray[np.float64]

_NUMERIC_KINDS = "iuf"


def float_array(field: str, value: Any, ndim: int) -> FloatArray:
    """``value`` as a C-contiguous float64 array with ``ndim`` dimensions.

    The user's object is never modified: the core only reads, and any conversion makes a copy.
    """
    if isinstance(value, (str, bytes)):
        raise TypeError(f"{field}: expected an array of numbers, got {type(value).__name__}")
    try:
        array = np.asarray(value)
    except (TypeError, ValueError) as exc:
        raise TypeError(f"{field}: expected an array of numbers ({exc})") from None
    if array.dtype.kind not in _NUMERIC_KINDS:
        raise TypeError(f"{field}: expected real numbers, got an array of dtype {array.dtype}")
    if array.ndim != ndim:
        raise ValueError(f"{field}: expected a {ndim}-D array, got shape {array.shape}")
    return np.ascontiguousarray(array, dtype=np.float64)


def frozen_array(field: str, value: Any, ndim: int) -> FloatArray:
    """A private read-only float64 copy of ``value``: later changes to the caller's array cannot
    desynchronise an object from what it reports."""
    array = np.array(float_array(field, value, ndim), dtype=np.float64, copy=True)
    array.setflags(write=False)
    return array


def real(field: str, value: Any) -> float:
    """``value`` as a float; booleans and non-numbers are a ``TypeError``."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise TypeError(f"{field}: expected a real number, got {type(value).__name__}")
    try:
        return float(value)
    except OverflowError:
        raise ValueError(f"{field}: must be finite, got a number too large for a float") from None


def flag(field: str, value: Any) -> bool:
    if not isinstance(value, (bool, np.bool_)):
        raise TypeError(f"{field}: expected True or False, got {type(value).__name__}")
    return bool(value)


def count(field: str, value: Any) -> int:
    """A non-negative integer (``ValueError`` if negative)."""
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise TypeError(f"{field}: expected an integer, got {type(value).__name__}")
    number = int(value)
    if number < 0:
        raise ValueError(f"{field}: must be >= 0, got {number}")
    if number > sys.maxsize:
        raise ValueError(f"{field}: must be at most {sys.maxsize}, got {number}")
    return number


def rotor_numbers(field: str, value: Any, rotor_count: int) -> tuple[int, ...]:
    """1-based rotor numbers, each in 1..rotor_count."""
    if isinstance(value, (str, bytes)) or not isinstance(value, Iterable):
        raise TypeError(f"{field}: expected a sequence of 1-based rotor numbers, got {type(value).__name__}")
    rotors = []
    for item in value:
        if isinstance(item, bool) or not isinstance(item, numbers.Integral):
            raise TypeError(f"{field}: expected 1-based rotor numbers, got {item!r}")
        rotor = int(item)
        if not 1 <= rotor <= rotor_count:
            raise ValueError(f"{field}: rotor numbers run from 1 to {rotor_count}, got {rotor}")
        rotors.append(rotor)
    return tuple(rotors)


_AXES = ("thrust-roll-pitch-yaw", "thrust-roll-pitch", "wrench")


def control_axes(give_up_yaw: Any, axes: Any) -> str:
    """The axes name from ``give_up_yaw`` (the short way) or ``axes`` (None: decided by the flag)."""
    drop_yaw = flag("give_up_yaw", give_up_yaw)
    if axes is None:
        return "thrust-roll-pitch" if drop_yaw else "thrust-roll-pitch-yaw"
    if not isinstance(axes, str):
        raise TypeError(f"axes: expected one of {', '.join(_AXES)}, got {type(axes).__name__}")
    if axes not in _AXES:
        raise ValueError(f"axes: must be one of {', '.join(_AXES)}, got {axes!r}")
    if drop_yaw and axes != "thrust-roll-pitch":
        raise ValueError(f"give_up_yaw: contradicts axes={axes!r} (give one of the two)")
    return axes


def read_toml(field: str, path: Any) -> dict[str, Any]:
    """The TOML file ``path`` as a dict; a missing, unreadable, non-UTF-8, malformed or too deeply
    nested file is a ``ValueError`` naming ``field`` and the file (never a ``RecursionError``)."""
    import os
    import tomllib
    from pathlib import Path

    if not isinstance(path, (str, os.PathLike)):
        raise TypeError(f"{field}: expected a file path, got {type(path).__name__}")
    p = Path(path)
    try:
        raw = p.read_bytes()
    except FileNotFoundError:
        raise ValueError(f"{field}: {str(p)!r} does not exist") from None
    except OSError as exc:
        raise ValueError(f"{field}: cannot read {str(p)!r}: {exc.strerror or exc}") from None
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise ValueError(f"{p}: not UTF-8 text ({exc.reason} at byte {exc.start}); expected TOML") from None
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ValueError(f"{p}: not valid TOML: {exc}") from None
    except RecursionError:
        raise ValueError(f"{p}: nested too deeply to read (arrays or tables within tables)") from None


"""Benchmark support (not part of the package): per-solve timings measured inside Rust, so no
Python call overhead is counted."""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from rotorfault import _rfcore
from rotorfault._util.convert import float_array
from rotorfault._typing import AllocationMethod
from rotorfault.allocation import METHODS, Allocator
from rotorfault.allocation.allocator import _positive_int


def time_per_solve(
    allocator: Allocator, virtual_controls: npt.ArrayLike, method: AllocationMethod = "active-set", *, repeats: int = 100
) -> npt.NDArray[np.float64]:
    """Mean seconds per cold-started solve, per row of ``virtual_controls``, measured in Rust on
    one thread (``repeats`` solves each)."""
    rows = float_array("virtual_controls", virtual_controls, 2)
    if method not in METHODS:
        raise ValueError(f"method: expected one of {', '.join(map(repr, METHODS))}, got {method!r}")
    times: npt.NDArray[np.float64] = _rfcore.time_allocations(allocator._core, rows, method, _positive_int("repeats", repeats))
    return times

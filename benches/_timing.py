"""Benchmark support for the allocation benches (not part of the package): per-solve timings
measured inside Rust, so no Python call overhead is counted, and the reference answer both benches
check against (Clarabel from Python on the same weighted problem)."""

from __future__ import annotations

import clarabel  # type: ignore[import-untyped]
import numpy as np
import numpy.typing as npt
from scipy import sparse  # type: ignore[import-untyped]

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


def python_clarabel(m: np.ndarray, w: np.ndarray, lower: np.ndarray, upper: np.ndarray, u_c: np.ndarray) -> np.ndarray:
    """``min (M T - u_c)^T W (M T - u_c)`` over ``lower <= T <= upper``, solved by Clarabel's
    Python package to 1e-10 (gap and feasibility), clipped to the bounds."""
    k = m.shape[1]
    h = sparse.csc_matrix(np.triu(m.T @ (w[:, None] * m)))
    q = -m.T @ (w * u_c)
    a = sparse.csc_matrix(np.vstack([np.eye(k), -np.eye(k)]))
    settings = clarabel.DefaultSettings()
    settings.verbose = False
    settings.tol_gap_abs = settings.tol_gap_rel = settings.tol_feas = 1e-10
    solution = clarabel.DefaultSolver(h, q, a, np.r_[upper, -lower], [clarabel.NonnegativeConeT(2 * k)], settings).solve()
    return np.clip(np.asarray(solution.x), lower, upper)

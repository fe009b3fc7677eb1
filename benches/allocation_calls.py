"""The cost of one allocation called from Python (issue 15 item 3), against clarabel's Python API.

Run:  pip install ".[bench]" && python benches/allocation_calls.py      (about 20 seconds)

Problem: Ke et al. eq. (33) on the ke-quadcopter preset with ``W = diag(1, 20, 20, 0.01)``, one
virtual control at a time (a hover wrench plus small torques, inside the attainable set, and one
beyond it so bounds are active). Timed with ``time.perf_counter`` over many calls, best of 7 runs
(the machine is shared), per call:

(a) ``Allocator.allocate(u)``: a prepared allocator, one virtual control (a list of floats);
(b) ``rf.allocate(airframe, u, weights=w)``: the one-line call, airframe given each time;
(c) ``rf.allocate(airframe, u)``: the same with the default weights;
(d) clarabel (Python): the same QP set up and solved through the clarabel PyPI package;
(e) the general path, ``Allocator.allocate([u])`` (a batch of one: conversion, shape checks, the
    batch binding and its arrays), what every call paid before the single-vector binding (which
    also rebuilt the solver per call: issue 15 measured 9 us and 25 us for (a) and (b) then).

The floor of the call (issue 32): ``AllocationProblem.allocate_one_floor(u)``, a core method that
takes the same argument and builds the same result object without the solve, so (floor) is what
any call of this shape costs from Python; (core) is ``allocate_one(u)`` called on the core object
directly (the floor plus the solve), and (a) - (core) is the Python wrapper (``Allocator.allocate``'s
checks and its ``Allocation``). The lowest ratio this call shape can reach is (floor + solve) / solve.

Also printed: the solve alone (``ActiveSetSolver::solve_unchecked`` with its certificate, timed
inside Rust: no Python call, best of 7 runs like the others), so the call overhead is (a) minus
it, and the ratios (a) / solve and (a') / solve, (a') being (a) with its commands read
(``Allocator.allocate(u).commands``: the fields are made when read). Targets: (a) <= 3 us, (b) <=
6 us (issue 15); (a) <= 3x the Rust solve (issue 32).
"""

from __future__ import annotations

import platform
import time
from collections.abc import Callable
from typing import Any

import clarabel  # type: ignore[import-untyped]
import numpy as np

import rotorfault as rf
from rotorfault.allocation import Allocator

from _timing import python_clarabel, time_per_solve

WEIGHTS = [1.0, 20.0, 20.0, 0.01]
TARGET_ALLOCATOR_S = 3e-6
TARGET_ONE_LINE_S = 6e-6
TARGET_OVER_RUST = 3.0


def per_call(fn: Callable[[], Any], calls: int, runs: int = 7) -> float:
    """Best over ``runs`` of the mean seconds per call of ``fn`` over ``calls`` calls."""
    best = float("inf")
    for _ in range(runs):
        start = time.perf_counter()
        for _ in range(calls):
            fn()
        best = min(best, (time.perf_counter() - start) / calls)
    return best


def main() -> None:
    print(f"rotorfault {rf.__version__}, clarabel (Python) {clarabel.__version__}, {platform.processor() or platform.machine()}")
    frame = rf.Airframe.preset("ke-quadcopter")
    allocator = Allocator(frame, weights=WEIGHTS)
    w = np.asarray(WEIGHTS)
    cases = {
        "inside": [frame.hover_thrust_n, 0.05, -0.08, 0.005],
        "beyond": [3.0 * frame.hover_thrust_n, 0.5, -0.8, 0.05],
    }
    print(f"\nper call, best of 7 runs (us); ke-quadcopter, W = diag({', '.join(map(str, WEIGHTS))})")
    header = (
        f"{'virtual control':<16} {'solve (Rust)':>12} {'Allocator':>10} {'+.commands':>11} {'rf.allocate':>12} "
        f"{'(default w)':>12} {'general path':>13} {'clarabel Py':>12} {'Allocator/Rust':>15} {'+.commands/Rust':>16} "
        f"{'Py/Allocator':>13}"
    )
    print(header)
    print("-" * len(header))
    ok = True
    floors: dict[str, tuple[float, float, float, float]] = {}
    for label, u in cases.items():
        exact = allocator.allocate(u)
        reference = python_clarabel(allocator.matrix, w, allocator.lower, allocator.upper, np.asarray(u))
        f_exact, _ = allocator.objective(u, exact.commands)
        f_ref, _ = allocator.objective(u, reference)
        assert exact.status == "optimal" and f_exact <= f_ref + 1e-12 * max(f_ref, 1.0), (label, f_exact, f_ref)
        # The Rust solve and the Python call, interleaved run by run (the machine is shared).
        solve = a = a_read = floor = core_call = float("inf")
        core = allocator._core
        for _ in range(7):
            solve = min(solve, float(time_per_solve(allocator, [u], repeats=20_000)[0]))
            a = min(a, per_call(lambda: allocator.allocate(u), 20_000, runs=1))
            a_read = min(a_read, per_call(lambda: allocator.allocate(u).commands, 20_000, runs=1))
            floor = min(floor, per_call(lambda: core.allocate_one_floor(u), 20_000, runs=1))
            core_call = min(core_call, per_call(lambda: core.allocate_one(u), 20_000, runs=1))
        floors[label] = (solve, floor, core_call, a)
        b = per_call(lambda: rf.allocate(frame, u, weights=WEIGHTS), 10_000)
        c = per_call(lambda: rf.allocate(frame, u), 10_000)
        e = per_call(lambda: allocator.allocate([u]), 10_000)
        d = per_call(lambda: python_clarabel(allocator.matrix, w, allocator.lower, allocator.upper, np.asarray(u)), 300)
        print(
            f"{label:<16} {solve * 1e6:>12.2f} {a * 1e6:>10.2f} {a_read * 1e6:>11.2f} {b * 1e6:>12.2f} {c * 1e6:>12.2f} "
            f"{e * 1e6:>13.2f} {d * 1e6:>12.1f} {a / solve:>14.2f}x {a_read / solve:>15.2f}x {d / a:>12.0f}x"
        )
        ok &= a <= TARGET_ALLOCATOR_S and b <= TARGET_ONE_LINE_S and a / solve <= TARGET_OVER_RUST
    print("\nwhere the time of (a) goes (us per call; the floor: the same argument in and result object out, no solve):")
    print(f"{'virtual control':<16} {'solve':>7} {'floor':>7} {'core call':>10} {'wrapper':>8} {'(a)':>7} {'(a)/solve':>10} {'best possible':>14}")
    for label, (solve, floor, core_call, a) in floors.items():
        print(f"{label:<16} {solve * 1e6:7.3f} {floor * 1e6:7.3f} {core_call * 1e6:10.3f} {(a - core_call) * 1e6:8.3f} "
              f"{a * 1e6:7.3f} {a / solve:9.2f}x {(floor + solve) / solve:13.2f}x")
    print(
        f"\ntargets: Allocator.allocate <= {TARGET_ALLOCATOR_S * 1e6:.0f} us and <= {TARGET_OVER_RUST:.0f}x the Rust solve, "
        f"rf.allocate(airframe) <= {TARGET_ONE_LINE_S * 1e6:.0f} us per call: " + ("met" if ok else "NOT met")
    )


if __name__ == "__main__":
    main()

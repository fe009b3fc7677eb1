"""Constrained control allocation: the active-set solver vs Clarabel (Rust and Python), one run.

Run:  pip install ".[bench]" && python benches/allocation_clarabel.py      (about a minute)

Problem (Ke et al. eq. (33)): ``min 1/2 (u_c - M T)^T W (u_c - M T)`` s.t. ``f_min <= T <= f_max``
with ``W = diag(1, 20, 20, 0.01)`` (Table IV's ordering w_p = w_q >> w_f >> w_r) on the presets
quad-x, hexa-pnpnpn and octo-x (4, 6, 8 rotors). Per airframe, 500 random virtual controls: half
attainable (``M T`` for a random T in the box), half beyond it (stretched and perturbed, so bounds
are active), the same set for every solver.

Timed, per problem, on one thread, cold-started, setup included:

(a) ``active-set``: rotorfault's exact solver (Rust), mean of 2,000 repeats per problem, timed
    inside Rust (``_timing.time_per_solve``) so no Python call overhead is counted;
(b) ``clarabel (Rust)``: the same problem through the clarabel crate (rotorfault's reference
    path), mean of 20 repeats per problem, timed inside Rust;
(c) ``clarabel (Python)``: the clarabel PyPI package building and solving the same QP from
    Python (scipy sparse matrices), mean of 5 repeats per problem, timed with perf_counter.

Reported: the median over problems (and the 90th percentile) of the per-problem times, and the
ratios of medians. Before timing, (a) is checked against (c) on every problem: objective within
1e-9 of the objective's scale and never worse than clarabel's by more than 1e-12.

Targets: active-set median <= 1 microsecond for 4 to 8 actuators (issue 4); >= 100x faster than
clarabel (Rust) on the same problems, with the certificate (issue 32; issue 4 asked 50x).
"""

from __future__ import annotations

import platform
import time

import clarabel  # type: ignore[import-untyped]
import numpy as np

import rotorfault as rf
from rotorfault.allocation import Allocator

from _timing import python_clarabel, time_per_solve

PRESETS = ("quad-x", "hexa-pnpnpn", "octo-x")
WEIGHTS = np.array([1.0, 20.0, 20.0, 0.01])
PROBLEMS = 500
TARGET_MEDIAN_S = 1e-6
TARGET_RATIO = 100.0


def virtual_controls(frame: rf.Airframe, rng: np.random.Generator) -> np.ndarray:
    m = frame.effectiveness_matrix()
    inside = rng.uniform(frame.min_thrust_n, frame.max_thrust_n, size=(PROBLEMS, frame.rotor_count)) @ m.T
    beyond = 2.0 * inside[: PROBLEMS // 2] + rng.normal(size=(PROBLEMS // 2, 4)) * [5.0, 0.5, 0.5, 0.05]
    return np.vstack([inside[PROBLEMS // 2 :], beyond])


def main() -> None:
    import argparse

    from _results import add_json_option, figure, write

    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    add_json_option(parser)
    json_path = parser.parse_args().json_path
    figures = []
    print(f"rotorfault {rf.__version__}, clarabel (Python) {clarabel.__version__}, {platform.processor() or platform.machine()}")
    rng = np.random.default_rng(2026)
    rows = []
    for name in PRESETS:
        frame = rf.Airframe.preset(name)
        allocator = Allocator(frame, weights=WEIGHTS)
        controls = virtual_controls(frame, rng)
        m, lower, upper = allocator.matrix, allocator.lower, allocator.upper

        exact = allocator.allocate(controls)
        for u_c, commands in zip(controls, exact.commands):
            reference = python_clarabel(m, WEIGHTS, lower, upper, u_c)
            f_exact, _ = allocator.objective(u_c, commands)
            f_ref, _ = allocator.objective(u_c, reference)
            scale = max(f_ref, 0.5 * float(u_c @ (WEIGHTS * u_c)))
            assert f_exact <= f_ref + 1e-12 * scale and f_ref - f_exact <= 1e-9 * scale, (name, f_exact, f_ref)

        active = time_per_solve(allocator, controls, "active-set", repeats=2000)
        rust_clarabel = time_per_solve(allocator, controls, "clarabel", repeats=20)
        py_clarabel = np.empty(PROBLEMS)
        for i, u_c in enumerate(controls):
            start = time.perf_counter()
            for _ in range(5):
                python_clarabel(m, WEIGHTS, lower, upper, u_c)
            py_clarabel[i] = (time.perf_counter() - start) / 5
        saturated = float(np.mean(~exact.attained))
        rows.append((name, frame.rotor_count, saturated, active, rust_clarabel, py_clarabel))

    print(f"\n{PROBLEMS} problems per airframe, per-solve times (median / p90), one thread, cold start")
    header = f"{'airframe':<12} {'m':>2} {'bounds hit':>10} {'active-set':>20} {'clarabel (Rust)':>22} {'clarabel (Python)':>22} {'Rust/AS':>8} {'Py/AS':>8}"
    print(header)
    print("-" * len(header))
    ok = True
    for name, m_count, saturated, a, b, c in rows:
        ma, mb, mc = (float(np.median(x)) for x in (a, b, c))
        pa, pb, pc = (float(np.percentile(x, 90)) for x in (a, b, c))
        print(
            f"{name:<12} {m_count:>2} {saturated:>10.0%} {ma * 1e9:>8.0f} / {pa * 1e9:>6.0f} ns "
            f"{mb * 1e6:>9.1f} / {pb * 1e6:>6.1f} us {mc * 1e6:>9.1f} / {pc * 1e6:>6.1f} us "
            f"{mb / ma:>7.0f}x {mc / ma:>7.0f}x"
        )
        ok &= ma <= TARGET_MEDIAN_S and mb / ma >= TARGET_RATIO
        figures.append(figure(f"active-set allocation, {name} ({m_count} rotors), median per solve", ma * 1e9, "ns",
                              baseline="the clarabel crate (Rust), same problems", baseline_value=mb * 1e9, ratio=mb / ma,
                              target=f"<= {TARGET_MEDIAN_S * 1e9:.0f} ns and >= {TARGET_RATIO:.0f}x"))
        figures.append(figure(f"active-set allocation, {name}, against clarabel from PyPI", ma * 1e9, "ns",
                              baseline="clarabel (PyPI), same problems", baseline_value=mc * 1e9, ratio=mc / ma))
    print(
        f"\ntargets: active-set median <= {TARGET_MEDIAN_S * 1e6:.0f} us and >= {TARGET_RATIO:.0f}x clarabel (Rust): "
        + ("met" if ok else "NOT met")
    )
    write(json_path, "allocation_clarabel",
          f"Ke eq. (33) allocation, {PROBLEMS} random virtual controls per airframe, one thread, cold start", figures)


if __name__ == "__main__":
    main()

"""ACAI throughput on Du et al.'s Fig. 4 grid: rotorfault (Rust) vs two NumPy implementations.

Run:  python benches/acai_grid.py [--json PATH]     (about 20 s on a 2-core machine; --json also
      writes the figures, the machine and the date as JSON, read by ``rotorfault reproduce``)

Grid: PNPNPN hexacopter (preset ``hexa-pnpnpn``), eta1, eta2, eta5 in {0, 0.04, ..., 1}, the other
rotors at 1: 26^3 = 17,576 efficiency vectors (Du, Quan, Yang, Cai, JGCD 2015, Fig. 4).

Variants (all compute Du's Theorem 3 / eq. (13) with the box [0, K] and G = [m g, 0, 0, 0]):

(a) ``rotorfault.acai_batch``: the Rust core. Facet normals xi_j are computed once per call from the
    nominal matrix (generalised cross products), then each row is ~20 x 6 multiply-adds, run in
    parallel with rayon on every available core. The timing is end to end from Python: argument
    conversion, building the analysis, validating every row, the batch, the returned array.
(b) NumPy, per point, as the paper describes it: build B_f(eta) for every point (N x 4 x 6); for each
    of the 20 column groups a batched ``np.linalg.svd`` of the N x 4 x 3 stacks gives xi_j (last left
    singular vector) and the rank test (singular values); rank B_f from a batched SVD of B_f; then
    d_j and eq. (13). Vectorised across N (no Python loop over points); a loop over the 20 groups.
(c) NumPy with the Rust core's algorithmic shortcut: scaling column k by eta_k > 0 only scales the
    null vector, so xi_j does not depend on eta. xi_j and the projections xi_j . bbar_k are computed
    once (20 small SVDs), then all N points are two (N x 6) @ (6 x 20) matrix products plus masks.
    Same algorithm as (a), so (a)/(c) is roughly "language + threads", (c)/(b) is "algorithm".

Both NumPy variants are checked against the Rust values on the grid (1e-9 absolute where finite,
identical -inf pattern) before anything is timed.

Threads: (a) uses every core rayon sees, and on x86-64 with AVX2 evaluates 8 points per pass in 4-wide
registers (`analysis::facet_lanes`, the same values bit for bit as the scalar path); NumPy's batched SVD is a single-threaded loop over
matrices, and the matmuls in (c) are too small to gain much from BLAS threads. Environment
variables such as OPENBLAS_CORETYPE / OPENBLAS_L2_SIZE / OPENBLAS_NUM_THREADS are deliberately left
as the environment sets them (this script neither sets nor clears them): the figures in
benches/README.md were measured as-is, and the variables are printed with the results.
"""

from __future__ import annotations

import itertools
import os
import platform
import statistics
import time
from collections.abc import Callable

import numpy as np

import rotorfault as rf

PRESET = "hexa-pnpnpn"
LEVELS = np.linspace(0.0, 1.0, 26)  # {0, 0.04, ..., 1}, endpoints exact
GRID_ROTORS = (0, 1, 4)  # eta1, eta2, eta5 (0-based)
ATOL = 1e-9
# NumPy rank decisions: a singular value counts when above RTOL x the largest (like the core's
# RANK_RTOL; on this grid the smallest nonzero singular values are O(1e-2), far from any threshold).
RTOL = rf.RANK_RTOL
TARGET_RUST_EVALS_PER_S = 2_000_000
TARGET_RATIO_VS_B = 50.0
TARGET_RATIO_VS_C = 15.0  # issue 32: the facet evaluation in SIMD lanes over points
LARGE_N = 1_000_000
ROUNDS = 8


# -- problem data ---------------------------------------------------------------------------------


def fig4_grid() -> np.ndarray:
    """17,576 x 6 efficiencies, eta1 slowest, eta5 fastest, other rotors at 1."""
    e1, e2, e5 = np.meshgrid(LEVELS, LEVELS, LEVELS, indexing="ij")
    etas = np.ones((e1.size, 6))
    for k, values in zip(GRID_ROTORS, (e1, e2, e5)):
        etas[:, k] = values.ravel()
    return etas


def problem(airframe: rf.Airframe) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Nominal B (4 x 6, healthy efficiencies), K (6,), G (4,)."""
    bbar = np.asarray(airframe.with_efficiency(np.ones(airframe.rotor_count)).effectiveness_matrix())
    k_max = np.asarray(airframe.max_thrust_n, dtype=float)
    if np.any(np.asarray(airframe.min_thrust_n) != 0.0):
        raise ValueError("this benchmark assumes Du's box [0, K]")
    g = np.array([airframe.hover_thrust_n, 0.0, 0.0, 0.0])
    return bbar, k_max, g


GROUPS = list(itertools.combinations(range(6), 3))  # 20 column groups of 3


def eq13(d: np.ndarray, valid: np.ndarray, full_rank: np.ndarray) -> np.ndarray:
    """Du eq. (13) over the valid groups: sign(min d_j) min |d_j|; -inf where rank B_f < 4."""
    inf = np.inf
    min_d = np.where(valid, d, inf).min(axis=1)
    min_abs = np.where(valid, np.abs(d), inf).min(axis=1)
    rho = np.where(min_d >= 0.0, min_d, -min_abs)
    return np.where(full_rank, rho, -inf)


# -- (b) NumPy, per-point SVD ---------------------------------------------------------------------


def acai_numpy_per_point(etas: np.ndarray, bbar: np.ndarray, k_max: np.ndarray, g: np.ndarray) -> np.ndarray:
    n_pts = etas.shape[0]
    b_f = bbar[None, :, :] * etas[:, None, :]  # N x 4 x 6, columns b_k = eta_k bbar_k
    f_c = 0.5 * k_max
    offset = b_f @ f_c - g  # N x 4: B_f f_c - G
    # Du Step 2: rank B_f = 4.
    s_full = np.linalg.svd(b_f, compute_uv=False)  # N x 4
    full_rank = s_full[:, 3] > RTOL * s_full[:, 0]
    d = np.empty((n_pts, len(GROUPS)))
    valid = np.empty((n_pts, len(GROUPS)), dtype=bool)
    for j, group in enumerate(GROUPS):
        cols = list(group)
        rest = [k for k in range(6) if k not in group]
        u, s, _ = np.linalg.svd(b_f[:, :, cols], full_matrices=True)  # U: N x 4 x 4, s: N x 3
        xi = u[:, :, 3]  # unit null vector of B_{1,j}^T
        valid[:, j] = s[:, 2] > RTOL * s[:, 0]  # rank B_{1,j} = 3, else skip (Du Step 6)
        proj = np.einsum("nr,nrk->nk", xi, b_f[:, :, rest])  # xi_j . b_k, k not in j
        half = 0.5 * (np.abs(proj) @ k_max[rest])
        d[:, j] = half - np.abs(np.einsum("nr,nr->n", xi, offset))
    return eq13(d, valid, full_rank)


# -- (c) NumPy, eta-independent facet normals (the Rust core's algorithm) --------------------------


def acai_numpy_precomputed(etas: np.ndarray, bbar: np.ndarray, k_max: np.ndarray, g: np.ndarray) -> np.ndarray:
    # Once per geometry: xi_j of the nominal columns and P[j, k] = xi_j . bbar_k (0 on the group).
    normals = np.empty((len(GROUPS), 4))
    member = np.zeros((len(GROUPS), 6), dtype=bool)
    for j, group in enumerate(GROUPS):
        u, s, _ = np.linalg.svd(bbar[:, list(group)], full_matrices=True)
        if not s[2] > RTOL * s[0]:
            raise ValueError(f"nominal group {group} is rank deficient; not handled here")
        normals[j] = u[:, 3]
        member[j, list(group)] = True
    proj = normals @ bbar  # 20 x 6
    proj[member] = 0.0
    proj[np.abs(proj) <= RTOL * np.linalg.norm(bbar, axis=0)] = 0.0
    g_along = normals @ g  # 20
    # Per point: two (N x 6) @ (6 x 20) products (eta, K >= 0, so |P_jk eta_k| K_k = eta_k K_k |P_jk|).
    w = etas * k_max  # N x 6
    half = 0.5 * (w @ np.abs(proj).T)  # N x 20
    centre = 0.5 * (w @ proj.T)  # xi_j . B_f f_c
    d = half - np.abs(centre - g_along)
    # A group spans a facet iff none of its rotors has eta = 0 (a positive scaling keeps rank 3).
    failed = (etas == 0.0).astype(float)
    valid = (failed @ member.T.astype(float)) == 0.0
    # rank B_f = 4 iff some valid group has a working column off its hyperplane.
    working = (etas != 0.0).astype(float)
    leaves = (working @ (proj != 0.0).T.astype(float)) > 0.0
    full_rank = np.any(valid & leaves, axis=1)
    return eq13(d, valid, full_rank)


# -- harness --------------------------------------------------------------------------------------


def time_once(fn: Callable[[], object]) -> float:
    t0 = time.perf_counter()
    fn()
    return time.perf_counter() - t0


def interleaved_times(
    fns: dict[str, Callable[[], object]], rounds: int, budget_per_round_s: float
) -> dict[str, list[float]]:
    """Times every function in ``rounds`` interleaved rounds (a, b, c, a, b, c, ...), so that
    background load, turbo or thermal drift hit all variants alike. In each round a function runs
    as many times as fit in its share of ``budget_per_round_s`` (at least once). One warm-up call
    each first."""
    per_call = {key: time_once(fn) for key, fn in fns.items()}  # warm-up + calibration
    calls = {key: max(1, int(budget_per_round_s / len(fns) / max(t, 1e-9))) for key, t in per_call.items()}
    samples: dict[str, list[float]] = {key: [] for key in fns}
    for _ in range(rounds):
        for key, fn in fns.items():
            samples[key].extend(time_once(fn) for _ in range(calls[key]))
    return samples


def check(name: str, got: np.ndarray, ref: np.ndarray) -> float:
    if got.shape != ref.shape:
        raise AssertionError(f"{name}: shape {got.shape} vs {ref.shape}")
    inf_got, inf_ref = np.isneginf(got), np.isneginf(ref)
    if not np.array_equal(inf_got, inf_ref):
        raise AssertionError(
            f"{name}: -inf pattern differs at {np.flatnonzero(inf_got != inf_ref)[:10]} (first 10)"
        )
    if np.isnan(got).any() or np.isposinf(got).any():
        raise AssertionError(f"{name}: NaN or +inf in the result")
    finite = ~inf_ref
    err = np.abs(got[finite] - ref[finite])
    worst = float(err.max()) if err.size else 0.0
    if worst > ATOL:
        i = np.flatnonzero(finite)[int(err.argmax())]
        raise AssertionError(f"{name}: |diff| = {worst:.3e} > {ATOL:g} at row {i}: {got[i]!r} vs {ref[i]!r}")
    return worst


def avx2() -> str:
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as handle:
            flags = next((line for line in handle if line.startswith("flags")), "")
    except OSError:
        return "unknown"
    return "yes" if " avx2" in flags else "no (the portable form runs)"


def verdict(ok: bool) -> str:
    return "PASS" if ok else "MISS"


def main() -> None:
    import argparse

    from _results import add_json_option, figure, write

    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    add_json_option(parser)
    json_path = parser.parse_args().json_path
    airframe = rf.Airframe.preset(PRESET)
    bbar, k_max, g = problem(airframe)
    etas = fig4_grid()
    n = etas.shape[0]

    # -- validate before timing -------------------------------------------------------------------
    rust = rf.acai_batch(airframe, etas)
    healthy = rf.acai(airframe, np.ones(6))
    assert abs(healthy - 1.4861) < 5e-4, healthy  # Du Table II
    worst_b = check("(b) NumPy per-point SVD", acai_numpy_per_point(etas, bbar, k_max, g), rust)
    worst_c = check("(c) NumPy precomputed xi_j", acai_numpy_precomputed(etas, bbar, k_max, g), rust)

    cores_os = os.cpu_count() or 1
    cores_avail = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else cores_os
    env = {k: os.environ[k] for k in sorted(os.environ) if k.startswith(("OPENBLAS", "OMP_", "RAYON", "MKL_"))}
    print(f"machine: {platform.machine()} {platform.processor() or ''}".rstrip()
          + f", os.cpu_count() = {cores_os}, usable cores = {cores_avail}")
    print(f"python {platform.python_version()}, numpy {np.__version__}, rotorfault {rf.__version__}")
    print(f"thread/BLAS env (left as-is): {env or 'none set'}")
    print(f"CPU has AVX2 (the Rust facet kernel's 4-lane form, chosen at run time): {avx2()}")
    load_before = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    print()
    controllable = np.count_nonzero(rust > 0.0)
    print(
        f"grid: {PRESET}, eta1, eta2, eta5 in {{0, 0.04, ..., 1}}: N = {n:,} points; "
        f"controllable (ACAI > 0): {controllable:,} ({controllable / n:.1%}); "
        f"ACAI = 0: {np.count_nonzero(rust == 0.0):,}; -inf: {np.count_nonzero(np.isneginf(rust)):,}; "
        f"healthy ACAI = {healthy:.4f} (Du Table II: 1.4861)"
    )
    print(f"validation vs Rust: (b) max |diff| = {worst_b:.2e}, (c) max |diff| = {worst_c:.2e} "
          f"(limit {ATOL:g}; -inf patterns identical)")
    print()

    # -- timing ---------------------------------------------------------------------------------
    labels = {
        "a": "(a) rotorfault.acai_batch (Rust, rayon)",
        "b": "(b) NumPy, per-point batched SVD (paper)",
        "c": "(c) NumPy, xi_j precomputed (Rust's alg.)",
    }
    samples = interleaved_times(
        {
            "a": lambda: rf.acai_batch(airframe, etas),
            "b": lambda: acai_numpy_per_point(etas, bbar, k_max, g),
            "c": lambda: acai_numpy_precomputed(etas, bbar, k_max, g),
        },
        rounds=ROUNDS,
        budget_per_round_s=1.5,
    )
    median = {key: statistics.median(ts) for key, ts in samples.items()}
    t_rust = median["a"]
    print(f"timing: {ROUNDS} interleaved rounds, time.perf_counter; evals/s and ratios from the median")
    print(f"{'variant':44s} {'median':>11s} {'min':>11s} {'evals/s':>12s} {'Rust/variant':>13s} {'runs':>5s}")
    for key, label in labels.items():
        t, ts = median[key], samples[key]
        print(f"{label:44s} {t * 1e3:8.3f} ms {min(ts) * 1e3:8.3f} ms {n / t:12,.0f} {t / t_rust:12.1f}x {len(ts):5d}")
    print()
    rust_rate = n / t_rust
    ratio_b = median["b"] / t_rust
    ratio_c = median["c"] / t_rust
    print(f"target: Rust >= {TARGET_RUST_EVALS_PER_S:,} evals/s: {rust_rate:,.0f} -> {verdict(rust_rate >= TARGET_RUST_EVALS_PER_S)}")
    print(f"target: Rust >= {TARGET_RATIO_VS_B:g}x NumPy (b): {ratio_b:.1f}x -> {verdict(ratio_b >= TARGET_RATIO_VS_B)}")
    print(f"target: Rust >= {TARGET_RATIO_VS_C:g}x NumPy (c), the same algorithm: {ratio_c:.1f}x -> "
          f"{verdict(ratio_c >= TARGET_RATIO_VS_C)} (from the minima: {min(samples['c']) / min(samples['a']):.1f}x)")
    print(f"split:  algorithm (b)/(c) = {median['b'] / median['c']:.1f}x, "
          f"language + {cores_avail} threads (c)/(a) = {ratio_c:.1f}x")
    print()

    # -- the Rust path at scale -------------------------------------------------------------------
    rng = np.random.default_rng(20150101)
    big = rng.random((LARGE_N, 6))
    failed_rows = np.flatnonzero(rng.random(LARGE_N) < 0.1)  # some failed rotors too
    big[failed_rows, rng.integers(0, 6, failed_rows.size)] = 0.0
    big_rust = rf.acai_batch(airframe, big)
    check("(c) on the random batch", acai_numpy_precomputed(big[:50_000], bbar, k_max, g), big_rust[:50_000])
    big_times = interleaved_times({"big": lambda: rf.acai_batch(airframe, big)}, rounds=1, budget_per_round_s=3.0)
    t_big, reps = statistics.median(big_times["big"]), len(big_times["big"])
    print(f"Rust at scale: {LARGE_N:,} random efficiency vectors (10% with one failed rotor): "
          f"median {t_big * 1e3:.1f} ms over {reps} runs = {LARGE_N / t_big:,.0f} evals/s "
          f"({t_big / LARGE_N * 1e9 * cores_avail:.0f} ns per evaluation per core)")
    load_after = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    print()
    print(f"1-min load average: {load_before:.2f} before timing, {load_after:.2f} after "
          f"(this script alone keeps 1 to {cores_avail} cores busy; a load well above {cores_avail} means "
          f"other work shared the CPUs and the figures are pessimistic)")
    write(json_path, "acai_grid", f"ACAI on Du Fig. 4's grid ({n:,} points, {PRESET}), end to end from Python", [
        figure("rotorfault.acai_batch, Fig. 4 grid", rust_rate, "evaluations/s", baseline="NumPy, the paper's per-point procedure (batched SVD)",
               baseline_value=n / median["b"], ratio=ratio_b, target=f">= {TARGET_RUST_EVALS_PER_S:,.0f}/s and >= {TARGET_RATIO_VS_B:g}x"),
        figure("rotorfault.acai_batch, Fig. 4 grid, time", t_rust * 1e3, "ms", baseline="NumPy with rotorfault's algorithm (normals once per geometry)",
               baseline_value=median["c"] * 1e3, ratio=ratio_c, target=f">= {TARGET_RATIO_VS_C:g}x"),
        figure(f"rotorfault.acai_batch, {LARGE_N:,} random efficiency vectors", LARGE_N / t_big, "evaluations/s"),
    ])


if __name__ == "__main__":
    main()

"""``rotorfault.control.norms``: the H-infinity norm against analytic values across poles from
1e-9 to 1e9 rad/s, against dense frequency sweeps (continuous and discrete), and refusals.

Tolerances: analytic cases 1e-9 relative (the bracket ``rtol``); sweeps: the norm is never below
the sweep's largest gain (1e-12) and at most 1e-6 above it (the sweep is refined around its
peak, so it misses the true peak by less than that)."""

from __future__ import annotations

import math

import control as ct
import numpy as np
import pytest

from rotorfault.control import norms
from rotorfault.control.realisation import frequency_response, state_space

DECADES = [10.0**k for k in range(-9, 10)]


@pytest.mark.parametrize("pole", DECADES)
def test_first_order_across_eighteen_decades(pole: float) -> None:
    # k / (s + p): the peak k / p at 0 rad/s; gains from 1e-9 to 1e9 too.
    for gain in (1e-9, 1.0, 1e9):
        g = state_space([[-pole]], [[gain]], [[1.0]], [[0.0]])
        peak = norms.peak_gain(g)
        assert peak.gain == pytest.approx(gain / pole, rel=1e-12)
        assert peak.frequency_rad_s == 0.0
        # ... and with a feedthrough: (s + 2p) / (s + p) peaks at 2 at 0 rad/s, 1 at infinity.
        h = state_space([[-pole]], [[pole]], [[1.0]], [[1.0]])
        assert norms.hinf_norm(h) == pytest.approx(2.0, rel=1e-12)


@pytest.mark.parametrize("natural", DECADES[::2])
@pytest.mark.parametrize("damping", [0.5, 0.1, 1e-3])
def test_resonance_across_eighteen_decades(natural: float, damping: float) -> None:
    # wn^2 / (s^2 + 2 z wn s + wn^2): peak 1 / (2 z sqrt(1 - z^2)) at wn sqrt(1 - 2 z^2).
    g = state_space([[0, natural], [-natural, -2 * damping * natural]], [[0], [natural]], [[1, 0]], [[0]])
    peak = norms.peak_gain(g)
    assert peak.gain == pytest.approx(1 / (2 * damping * math.sqrt(1 - damping**2)), rel=1e-9)
    # The resonance is flat for z = 0.5 (the gain is within 1e-9 over 1e-4 of frequency).
    assert peak.frequency_rad_s == pytest.approx(natural * math.sqrt(1 - 2 * damping**2), rel=1e-3 if damping == 0.5 else 1e-6)


def _sweep_peak(system: ct.StateSpace, lo: float, hi: float, *, discrete: bool = False) -> float:
    """Largest gain on 0 and a dense log grid (continuous) or a uniform grid of the half circle
    (discrete), refined by a finer grid around the best point twice."""
    if discrete:
        w = np.linspace(0.0, math.pi, 20001)
    else:
        w = np.concatenate([[0.0], np.logspace(math.log10(lo), math.log10(hi), 20000)])
    for _ in range(3):
        sv = np.linalg.svd(frequency_response(system, w), compute_uv=False)[:, 0]
        k = int(np.argmax(sv))
        a, b = w[max(k - 1, 0)], w[min(k + 1, w.size - 1)]
        best = float(sv[k])
        w = np.linspace(a, b, 2001)
    return max(best, float(np.max(np.linalg.svd(frequency_response(system, w), compute_uv=False)[:, 0])))


def _random_wide_system(rng: np.random.Generator, n: int, p: int, m: int) -> ct.StateSpace:
    """Poles spread log-uniformly over 1e-9..1e9 rad/s (some complex, lightly damped) in a
    block upper-triangular A (each coupling of the size of the slower of the two modes), with
    states rescaled by factors up to 1e6; random B, C (each mode contributing a gain of order
    one) and D. (A dense orthogonal mixing of such modes would not be a well-posed system in
    double precision: its small poles would be lost to rounding, and with them its response.)"""
    blocks: list[np.ndarray] = []
    mags: list[float] = []
    while len(mags) < n:
        mag = 10 ** rng.uniform(-9, 9)
        if rng.random() < 0.5 and len(mags) <= n - 2:
            z = 10 ** rng.uniform(-2, -0.1)
            w = mag * math.sqrt(1 - z * z)
            blocks.append(np.array([[-z * mag, w], [-w, -z * mag]]))
            mags += [mag, mag]
        else:
            blocks.append(np.array([[-mag]]))
            mags.append(mag)
    a = np.zeros((n, n))
    k = 0
    for blk in blocks:
        a[k:k + blk.shape[0], k:k + blk.shape[0]] = blk
        k += blk.shape[0]
    size = np.array(mags)
    for i in range(n):
        for j in range(n):
            if a[i, j] == 0 and j > i:
                a[i, j] = 0.3 * rng.normal() * min(size[i], size[j])
    scale = np.sqrt(size)
    b = rng.normal(size=(n, m)) * scale[:, None]
    c = rng.normal(size=(p, n)) * scale[None, :]
    t = 10 ** rng.uniform(0, 6, n)
    return state_space(a * t[None, :] / t[:, None], b / t[:, None], c * t[None, :], rng.normal(size=(p, m)) * 0.1)


@pytest.mark.parametrize("seed", range(8))
def test_wide_random_systems_against_a_dense_sweep(seed: int) -> None:
    rng = np.random.default_rng(seed)
    g = _random_wide_system(rng, int(rng.integers(3, 8)), int(rng.integers(1, 4)), int(rng.integers(1, 4)))
    poles = np.abs(np.diag(np.asarray(g.A)))
    swept = _sweep_peak(g, poles.min() / 1e3, poles.max() * 1e3)
    value = norms.hinf_norm(g)
    # The norm lies in [value, value (1 + 2e-9)]; the sweep is a lower bound of it.
    assert swept <= value * (1 + 2e-9)
    assert value <= swept * (1 + 1e-6)


@pytest.mark.parametrize("pole", [-0.999999, -0.9, -0.3, 0.0, 0.5, 0.99, 1 - 1e-9])
def test_discrete_first_order(pole: float) -> None:
    # k / (z - a) on the unit circle peaks at z = 1 (a > 0) or z = -1 (a < 0): k / (1 - |a|).
    g = state_space([[pole]], [[2.0]], [[1.0]], [[0.0]], dt=0.01)
    peak = norms.peak_gain(g)
    assert peak.gain == pytest.approx(2.0 / (1 - abs(pole)), rel=1e-9)
    if pole != 0.0:  # 2 / z has the same gain at every frequency
        assert peak.frequency_rad_s == pytest.approx(0.0 if pole > 0 else math.pi / 0.01, abs=1e-6)


@pytest.mark.parametrize("seed", range(4))
def test_discrete_random_systems_against_a_dense_sweep(seed: int) -> None:
    rng = np.random.default_rng(100 + seed)
    n, p, m = 4, 2, 2
    a = rng.normal(size=(n, n))
    a *= 0.97 / max(abs(np.linalg.eigvals(a)))
    g = state_space(a, rng.normal(size=(n, m)), rng.normal(size=(p, n)), rng.normal(size=(p, m)), dt=True)
    swept = _sweep_peak(g, 0, 0, discrete=True)
    value = norms.hinf_norm(g)
    assert swept * (1 - 1e-12) <= value <= swept * (1 + 1e-6)


def test_agrees_with_slycot_ab13dd_where_installed() -> None:
    # A cross-check only (python-control's norm uses slycot's ab13dd, tolerance 1e-6).
    pytest.importorskip("slycot")
    rng = np.random.default_rng(5)
    for _ in range(5):
        a = rng.normal(size=(5, 5))
        a -= (max(np.linalg.eigvals(a).real) + rng.uniform(0.1, 1.0)) * np.eye(5)
        g = ct.ss(a, rng.normal(size=(5, 3)), rng.normal(size=(2, 5)), rng.normal(size=(2, 3)))
        assert norms.hinf_norm(g) == pytest.approx(float(ct.norm(g, "inf", tol=1e-10)), rel=1e-6)


def test_unstable_static_and_transfer_functions() -> None:
    assert norms.hinf_norm(state_space([[1e-9]], [[1.0]], [[1.0]], [[0.0]])) == math.inf
    assert norms.hinf_norm(state_space([[0.0]], [[1.0]], [[1.0]], [[0.0]])) == math.inf  # a pole at 0
    assert norms.hinf_norm(state_space([[1.5]], [[1.0]], [[1.0]], [[0.0]], dt=0.1)) == math.inf
    # A static gain's norm is its largest singular value, at every frequency.
    assert norms.hinf_norm(np.array([[3.0, 4.0]])) == pytest.approx(5.0, rel=1e-15)
    tf = ct.tf([1e9], [1, 1e9])
    assert norms.hinf_norm(tf) == pytest.approx(1.0, rel=1e-12)
    assert norms.hinf_norm_below(tf, 1.0 + 1e-6) and not norms.hinf_norm_below(tf, 1.0 - 1e-6)


def test_refusals_name_the_field() -> None:
    with pytest.raises(ValueError, match="system: the matrix A must be finite"):
        norms.hinf_norm(ct.ss([[np.nan]], [[1.0]], [[1.0]], [[0.0]]))
    with pytest.raises(ValueError, match="system: an empty system"):
        norms.hinf_norm(np.zeros((0, 2)))
    with pytest.raises(TypeError, match="system: expected a python-control StateSpace"):
        norms.hinf_norm("G")
    with pytest.raises(ValueError, match="rtol: must be a number in"):
        norms.peak_gain(ct.ss([[-1.0]], [[1.0]], [[1.0]], [[0.0]]), rtol=0.0)
    with pytest.raises(ValueError, match="level: must be a finite number > 0"):
        norms.hinf_norm_below(ct.ss([[-1.0]], [[1.0]], [[1.0]], [[0.0]]), math.inf)

"""The H-infinity norm, our own (python-control's ``norm`` calls slycot's ``ab13dd`` when it is
installed and a fixed-grid bisection otherwise; neither is right for every scale).

:func:`peak_gain` is the Bruinsma-Steinbuch level-set iteration (Bruinsma and Steinbuch, "A fast
algorithm to compute the H-infinity-norm of a transfer function matrix", Systems & Control
Letters 14, 1990), with three things for badly scaled systems:

- the states are balanced first (:func:`~rotorfault.control.realisation.balance_states`) and the
  system is divided by the level, so the Hamiltonian's entries are of the system's own size;
- the lower bound starts from the gain at 0, at infinity, at every pole's modulus and imaginary
  part and on a log-spaced grid spanning all the poles (20 points per decade): no fixed frequency
  range, so poles from 1e-9 to 1e9 rad/s are all seen;
- the Hamiltonian's near-imaginary eigenvalues are accepted generously (relative real part below
  1e-5) and every candidate frequency and every midpoint (arithmetic and geometric) between
  neighbours is evaluated: a spurious candidate costs an evaluation, a missed crossing would cost
  the answer, and the bound only ever rises to a gain actually attained.

The result lies in ``[gain, gain (1 + 2 rtol)]``. An unstable system has an infinite norm.
Discrete systems are mapped to continuous ones by the bilinear map ``z = (1 + s) / (1 - s)``,
which takes the unit circle onto the imaginary axis and keeps the norm; the peak frequency is
mapped back. A static system's norm is its gain's largest singular value.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from .._util.convert import FloatArray
from .realisation import as_state_space, balance_states, frequency_response, sampling_period, state_space

#: Relative real part below which a Hamiltonian eigenvalue is a candidate crossing.
_CANDIDATE_RTOL = 1e-5
_MAX_ITERATIONS = 60


@dataclass(frozen=True)
class PeakGain:
    """The H-infinity norm ``gain`` (largest singular value over frequency; ``inf`` when the
    system is unstable) and a frequency where it is attained (rad/s; ``inf`` for the direct
    feedthrough at infinite frequency, ``nan`` when unstable), within relative ``rtol``."""

    gain: float
    frequency_rad_s: float
    rtol: float


def _largest_sv(system: Any, omega: FloatArray) -> FloatArray:
    resp = frequency_response(system, omega)
    with np.errstate(all="ignore"):
        if not np.all(np.isfinite(resp)):
            out = np.full(omega.size, np.inf)
            ok = np.all(np.isfinite(resp), axis=(1, 2))
            if np.any(ok):
                out[ok] = np.linalg.svd(resp[ok], compute_uv=False)[:, 0]
            return out
        return np.asarray(np.linalg.svd(resp, compute_uv=False)[:, 0], dtype=np.float64)


def _to_continuous(a: FloatArray, b: FloatArray, c: FloatArray, d: FloatArray) -> tuple[FloatArray, ...]:
    """The bilinear map z = (1 + s) / (1 - s): G_c(s) = G_d(z)."""
    n = a.shape[0]
    m = np.linalg.inv(a + np.eye(n))
    return ((a - np.eye(n)) @ m, math.sqrt(2.0) * m @ b, math.sqrt(2.0) * c @ m, d - c @ m @ b)


def _is_stable(a: FloatArray, discrete: bool) -> bool:
    if a.shape[0] == 0:
        return True
    eig = np.linalg.eigvals(a)
    if discrete:
        return bool(np.max(np.abs(eig)) < 1.0)
    return bool(np.max(eig.real) < 0.0)


def _hamiltonian_eigs(a: FloatArray, b: FloatArray, c: FloatArray, d: FloatArray, level: float) -> FloatArray:
    """Eigenvalues of the bounded-real Hamiltonian of ``G / level`` at level 1."""
    root = math.sqrt(level)
    b1, c1, d1 = b / root, c / root, d / level
    r = np.eye(d.shape[1]) - d1.T @ d1
    ri = np.linalg.inv(r)
    a1 = a + b1 @ ri @ d1.T @ c1
    s_inv = np.eye(d.shape[0]) + d1 @ ri @ d1.T
    h = np.block([[a1, b1 @ ri @ b1.T], [-c1.T @ s_inv @ c1, -a1.T]])
    return np.asarray(np.linalg.eigvals(h))


def _inverted(a: FloatArray, b: FloatArray, c: FloatArray, d: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray] | None:
    """A balanced realisation of ``G(1/s)`` (poles ``1/lambda``; its gain at ``j nu`` is ``G``'s
    at ``j / nu``), or ``None`` when ``A`` is singular."""
    try:
        ai = np.linalg.inv(a)
    except np.linalg.LinAlgError:
        return None
    if not np.all(np.isfinite(ai)):
        return None
    inv, _ = balance_states(state_space(ai, ai @ b, -c @ ai, d - c @ ai @ b))
    return (np.asarray(inv.A, dtype=np.float64), np.asarray(inv.B, dtype=np.float64),
            np.asarray(inv.C, dtype=np.float64), np.asarray(inv.D, dtype=np.float64))


def _start_frequencies(poles: npt.NDArray[np.complex128]) -> FloatArray:
    mags = np.abs(poles)
    nz = mags[mags > 0]
    pts = [0.0]
    if nz.size:
        lo, hi = math.log10(float(nz.min())) - 2, math.log10(float(nz.max())) + 2
        pts += list(np.logspace(lo, hi, max(int(20 * (hi - lo)) + 1, 2)))
        pts += list(nz) + list(np.abs(poles.imag[poles.imag != 0]))
    return np.unique(np.asarray(pts, dtype=np.float64))


def peak_gain(system: Any, *, rtol: float = 1e-9, field: str = "system") -> PeakGain:
    """The H-infinity norm of ``system`` (a python-control ``StateSpace`` or ``TransferFunction``,
    continuous or discrete) and where it peaks; see the module notes. ``rtol``: the relative
    width of the bracket returned (the true norm is in ``[gain, gain (1 + 2 rtol)]``); ``field``:
    the name refusals give the system (its entries are checked by
    :func:`~rotorfault.control.realisation.as_state_space`)."""
    if not (isinstance(rtol, float | int) and 1e-15 <= float(rtol) <= 1e-1):
        raise ValueError(f"rtol: must be a number in [1e-15, 0.1], got {rtol!r}")
    sys_ = as_state_space(field, system)
    dt = sampling_period(sys_)
    balanced, _ = balance_states(sys_)
    a, b, c, d = (np.asarray(m, dtype=np.float64) for m in (balanced.A, balanced.B, balanced.C, balanced.D))
    if a.shape[0] == 0:
        return PeakGain(float(np.linalg.norm(d, 2)), 0.0 if dt else math.inf, float(rtol))
    if not _is_stable(a, bool(dt)):
        return PeakGain(math.inf, math.nan, float(rtol))
    if dt:
        a, b, c, d = _to_continuous(a, b, c, d)
        cont, _ = balance_states(state_space(a, b, c, d))
        a, b, c, d = (np.asarray(m, dtype=np.float64) for m in (cont.A, cont.B, cont.C, cont.D))
    else:
        cont = balanced
    d_gain = float(np.linalg.norm(d, 2))  # the gain at infinite frequency (discrete: at z = -1)
    omega = _start_frequencies(np.asarray(np.linalg.eigvals(a), dtype=np.complex128))
    gains = _largest_sv(cont, omega)
    k = int(np.argmax(gains))
    best, where = float(gains[k]), float(omega[k])
    if d_gain >= best:
        best, where = d_gain, math.inf
    if best == 0.0:
        return PeakGain(0.0, 0.0, float(rtol))
    views: list[tuple[FloatArray, FloatArray, FloatArray, FloatArray, bool]] = [(a, b, c, d, False)]
    inverted = _inverted(a, b, c, d)
    if inverted is not None:
        views.append((inverted[0], inverted[1], inverted[2], inverted[3], True))
    for _ in range(_MAX_ITERATIONS):
        level = best * (1.0 + 2.0 * rtol)
        found = [np.zeros(0)]
        for va, vb, vc, vd, inv in views:
            eig = _hamiltonian_eigs(va, vb, vc, vd, level)
            near = eig[np.abs(eig.real) <= _CANDIDATE_RTOL * np.maximum(np.abs(eig), 1e-300)]
            nu = np.abs(near.imag)
            found.append(1.0 / nu[nu > 0] if inv else nu)
        freqs = np.unique(np.concatenate(found))
        if freqs.size == 0:
            break
        mids = [freqs]
        if freqs.size > 1:
            lo, hi = freqs[:-1], freqs[1:]
            mids += [(lo + hi) / 2, np.sqrt(lo * hi)]
        trial = np.unique(np.concatenate(mids))
        trial_gains = _largest_sv(cont, trial)
        k = int(np.argmax(trial_gains))
        if not trial_gains[k] > level:
            break
        best, where = float(trial_gains[k]), float(trial[k])
    if dt and math.isfinite(where):
        where = 2.0 * math.atan(where) / dt
    elif dt:
        where = math.pi / dt
    return PeakGain(best, where, float(rtol))


def hinf_norm(system: Any, *, rtol: float = 1e-9) -> float:
    """The H-infinity norm (``inf`` for an unstable system): :func:`peak_gain`'s ``gain``."""
    return peak_gain(system, rtol=rtol).gain


def hinf_norm_below(system: Any, level: float) -> bool:
    """``True`` when ``system`` is stable and its H-infinity norm is below ``level``."""
    if not (isinstance(level, float | int) and level > 0 and math.isfinite(level)):
        raise ValueError(f"level: must be a finite number > 0, got {level!r}")
    return peak_gain(system).gain * (1.0 + 2e-9) < level


__all__ = ["PeakGain", "hinf_norm", "hinf_norm_below", "peak_gain"]

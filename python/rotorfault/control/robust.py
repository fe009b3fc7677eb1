"""H-infinity loop shaping (McFarlane and Glover): normalised-coprime-factor robust stabilisation
from two Riccati equations, our own implementation (python-control has no Glover-McFarlane
synthesis and slycot does not wrap SLICOT's sb10id/sb10kd).

- :func:`ncfsyn`: the central controller of the shaped plant ``Gs = W2 G W1`` for
  ``gamma = factor * gamma_min``, returned as ``K = W1 Ks W2`` (a python-control ``StateSpace``);
- :func:`loop_shape_weight`: a pre-compensator ``W1`` that gives a square plant of full relative
  degree (what robust feedback linearisation produces) a target loop shape ``G W1 = diag(L_i)``,
  with :func:`target_loop_shape` the scalar ``L`` (Lanzon's shape: a low-frequency gain, -20
  dB/decade through the crossover, -40 dB/decade above);
- :func:`plot_singular_values`: the singular values of a plant and of its shaped plant.

Sign convention: the returned controllers are for **negative feedback**, ``u = -K y``
(python-control's ``feedback(G * K)``), i.e. ``u = K (r - y)``.

Formulas (Skogestad and Postlethwaite, *Multivariable Feedback Control*, 2nd ed., eqs.
(9.64)-(9.82)), with ``S = I + D^T D``, ``R = I + D D^T``, ``A_r = A - B S^-1 D^T C``::

    A_r^T X + X A_r - X B S^-1 B^T X + C^T R^-1 C = 0          (control ARE)
    A_r Z + Z A_r^T - Z C^T R^-1 C Z + B S^-1 B^T = 0          (filter ARE)
    gamma_min = sqrt(1 + rho(X Z)) = (1 - ||[N M]||_H^2)^(-1/2)
    F = -S^-1 (D^T C + B^T X),  L = (1 - gamma^2) I + X Z
    Ks (positive feedback) = [A + B F + gamma^2 L^-T Z C^T (C + D F) | gamma^2 L^-T Z C^T ]
                             [B^T X                                   | -D^T                ]
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import control as ct  # type: ignore[import-untyped]
import numpy as np
import numpy.typing as npt
import scipy.linalg as sla  # type: ignore[import-untyped]

from .._util.convert import FloatArray, real
from ..plotting.frequency import plot_singular_values


@dataclass(frozen=True)
class NcfsynResult:
    """The outcome of :func:`ncfsyn`.

    ``controller`` is ``K = W1 Ks W2`` for the plant (negative feedback), ``shaped_controller`` is
    ``Ks`` for the shaped plant ``Gs = W2 G W1`` (negative feedback), ``gamma_min`` the optimal
    and ``gamma`` the achieved robust-stabilisation level (``gamma = factor * gamma_min``: the
    four-block norm ``||[I; Ks] (I + Gs Ks)^-1 [I, Gs]||_inf`` is at most ``gamma``),
    ``stability_margin = 1 / gamma`` (the normalised-coprime-factor uncertainty tolerated).
    ``x`` and ``z`` are the two Riccati solutions."""

    controller: ct.StateSpace
    shaped_controller: ct.StateSpace
    shaped_plant: ct.StateSpace
    gamma_min: float
    gamma: float
    x: FloatArray
    z: FloatArray

    @property
    def stability_margin(self) -> float:
        """``1 / gamma``: the size of normalised-coprime-factor perturbation tolerated."""
        return 1.0 / self.gamma


def _as_ss(field: str, system: Any) -> ct.StateSpace:
    if isinstance(system, ct.StateSpace):
        return system
    if isinstance(system, (ct.TransferFunction,)):
        return ct.ss(system)
    if isinstance(system, (int, float, np.ndarray, list, tuple)):
        try:
            d = np.atleast_2d(np.asarray(system, dtype=np.float64))
        except (TypeError, ValueError):
            raise TypeError(f"{field}: expected a static gain of numbers or a python-control system, got {system!r:.60}") from None
        if d.ndim != 2:
            raise ValueError(f"{field}: expected a static gain matrix (2-D), got shape {d.shape}")
        return ct.ss(np.zeros((0, 0)), np.zeros((0, d.shape[1])), np.zeros((d.shape[0], 0)), d)
    raise TypeError(f"{field}: expected a python-control StateSpace or TransferFunction, got {type(system).__name__}")


def _matrices(system: ct.StateSpace) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    return (np.asarray(system.A, dtype=float), np.asarray(system.B, dtype=float),
            np.asarray(system.C, dtype=float), np.asarray(system.D, dtype=float))


def riccati_solutions(plant: ct.StateSpace) -> tuple[FloatArray, FloatArray]:
    """``(X, Z)``: the stabilising solutions of the control and filter AREs of the normalised
    coprime factorisation of ``plant`` (module docs). ``ValueError`` if the plant is not
    stabilisable and detectable (no stabilising solution)."""
    a, b, c, d = _matrices(plant)
    s = np.eye(b.shape[1]) + d.T @ d
    r = np.eye(c.shape[0]) + d @ d.T
    ar = a - b @ np.linalg.solve(s, d.T @ c)
    try:
        x = sla.solve_continuous_are(ar, b, c.T @ np.linalg.solve(r, c), s)
        z = sla.solve_continuous_are(ar.T, c.T, b @ np.linalg.solve(s, b.T), r)
    except (np.linalg.LinAlgError, ValueError) as exc:
        raise ValueError(f"plant: no stabilising Riccati solution (is the shaped plant stabilisable and detectable?): {exc}") from None
    return (x + x.T) / 2, (z + z.T) / 2


def ncf_gamma_min(plant: ct.StateSpace) -> float:
    """``gamma_min = sqrt(1 + rho(X Z))`` of a (shaped) plant."""
    x, z = riccati_solutions(plant)
    return float(np.sqrt(1.0 + max(np.max(np.linalg.eigvals(x @ z).real), 0.0)))


def _krylov_basis(a: FloatArray, b: FloatArray, rtol: float) -> FloatArray:
    """Orthonormal basis of the controllable subspace of ``(A, B)`` by block Arnoldi (each new
    direction orthogonalised twice against the basis; a direction counts when its norm exceeds
    ``rtol`` times that of ``A`` applied to the basis)."""
    n = a.shape[0]
    scale = max(1.0, float(np.linalg.norm(a, 2)))
    u, sv, _ = np.linalg.svd(b, full_matrices=False)
    basis = u[:, sv > rtol * max(1.0, float(sv[0]) if sv.size else 1.0)]
    new = basis
    while new.shape[1] and basis.shape[1] < n:
        w = a @ new
        for _ in range(2):
            w = w - basis @ (basis.T @ w)
        u, sv, _ = np.linalg.svd(w, full_matrices=False)
        keep = sv > rtol * scale
        new = u[:, keep]
        if new.shape[1]:
            for _ in range(2):
                new = new - basis @ (basis.T @ new)
            new, _ = np.linalg.qr(new)
            basis = np.hstack([basis, new])
    return basis


def _require_stabilisable_detectable(system: ct.StateSpace) -> None:
    """PBH eigenvector test at every eigenvalue with a real part >= 0: no left eigenvector
    orthogonal to ``B``, no right eigenvector in the kernel of ``C`` (relative to their norms, so
    that large weight gains do not hide a cancellation)."""
    a, b, c, _ = _matrices(system)
    n = a.shape[0]
    if n == 0:
        return
    scale = max(1.0, float(np.linalg.norm(a, 2)))
    lams, right = np.linalg.eig(a)
    _, left = np.linalg.eig(a.T)
    lams_left = np.linalg.eigvals(a.T)
    for k, lam in enumerate(lams):
        if lam.real < -1e-9 * scale:
            continue
        vr = right[:, k] / np.linalg.norm(right[:, k])
        j = int(np.argmin(np.abs(lams_left - lam)))
        vl = left[:, j] / np.linalg.norm(left[:, j])
        b_norm = max(float(np.linalg.norm(b, 2)), 1e-300)
        c_norm = max(float(np.linalg.norm(c, 2)), 1e-300)
        for name, value in (("stabilisable", float(np.linalg.norm(vl @ b)) / b_norm),
                            ("detectable", float(np.linalg.norm(c @ vr)) / c_norm)):
            if value <= 1e-9:
                raise ValueError(
                    f"plant: the shaped plant W2 G W1 is not {name}: the mode at {lam:.6g} cannot be "
                    "stabilised (no stabilising Riccati solution; a weight may cancel it)"
                )


def minimal_realisation(system: ct.StateSpace, *, rtol: float = 1e-9) -> ct.StateSpace:
    """A minimal realisation (controllable, then observable part) by orthogonal projection onto
    Krylov subspaces; needs no slycot. Removes the modes a weight cancels in ``G W1``."""
    a, b, c, d = _matrices(system)
    if a.shape[0] == 0:
        return system
    t = _krylov_basis(a, b, rtol)
    a, b, c = t.T @ a @ t, t.T @ b, c @ t
    if a.shape[0]:
        t = _krylov_basis(a.T, c.T, rtol)
        a, b, c = t.T @ a @ t, t.T @ b, c @ t
    return ct.ss(a, b, c, d)


def ncfsyn(
    plant: Any,
    w1: Any,
    w2: Any = None,
    factor: float = 1.1,
) -> NcfsynResult:
    """Glover-McFarlane loop-shaping synthesis: the central controller robustly stabilising the
    shaped plant ``Gs = W2 G W1`` at ``gamma = factor * gamma_min`` (``factor > 1``), and the
    plant's controller ``K = W1 Ks W2`` (negative feedback). ``w2`` defaults to the identity."""
    g = _as_ss("plant", plant)
    if g.ninputs == 0 or g.noutputs == 0:  # LAPACK's own error otherwise (dgges: lwork=0)
        raise ValueError(f"plant: expected at least one input and one output, got {g.noutputs}x{g.ninputs}")
    w1s = _as_ss("w1", w1)
    factor = real("factor", factor)
    if not np.isfinite(factor) or factor <= 1.0:
        raise ValueError(f"factor: must be > 1 (gamma = factor * gamma_min; at 1 the central controller does not exist), got {factor}")
    if w1s.noutputs != g.ninputs:
        raise ValueError(f"w1: expected {g.ninputs} outputs (the plant's inputs), got {w1s.noutputs}")
    w2s = _as_ss("w2", np.eye(g.noutputs) if w2 is None else w2)
    if w2s.ninputs != g.noutputs:
        raise ValueError(f"w2: expected {g.noutputs} inputs (the plant's outputs), got {w2s.ninputs}")
    for field, system in (("plant", g), ("w1", w1s), ("w2", w2s)):
        if not all(np.all(np.isfinite(m)) for m in _matrices(system)):
            raise ValueError(f"{field}: matrices must be finite")
    # The weights may cancel stable plant modes (an inverting W1 does): synthesise on a minimal
    # realisation, after checking that no mode it drops is on or right of the imaginary axis
    # (such a cancellation leaves the closed loop unstable or undamped whatever Ks does).
    full = ct.series(w1s, g, w2s)
    _require_stabilisable_detectable(full)
    gs = minimal_realisation(full)
    a, b, c, d = _matrices(gs)
    x, z = riccati_solutions(gs)
    gamma_min = float(np.sqrt(1.0 + max(np.max(np.linalg.eigvals(x @ z).real), 0.0)))
    gamma = factor * gamma_min
    s = np.eye(b.shape[1]) + d.T @ d
    f = -np.linalg.solve(s, d.T @ c + b.T @ x)
    n = a.shape[0]
    lt = ((1.0 - gamma**2) * np.eye(n) + x @ z).T
    gain = gamma**2 * np.linalg.solve(lt, z @ c.T)
    ak = a + b @ f + gain @ (c + d @ f)
    # Negative-feedback form of the positive-feedback central controller: C_K, D_K change sign.
    ks = ct.ss(ak, gain, -b.T @ x, d.T)
    k = ct.series(w2s, ks, w1s)
    return NcfsynResult(controller=k, shaped_controller=ks, shaped_plant=gs,
                        gamma_min=gamma_min, gamma=gamma, x=x, z=z)


def hankel_gamma_min(plant: ct.StateSpace) -> float:
    """``(1 - ||[N M]||_H^2)^(-1/2)`` from the Hankel singular values of the normalised left
    coprime factors (gramians from two Lyapunov equations): an independent route to ``gamma_min``."""
    a, b, c, d = _matrices(plant)
    _, z = riccati_solutions(plant)
    r = np.eye(c.shape[0]) + d @ d.T
    h = -(b @ d.T + z @ c.T) @ np.linalg.inv(r)
    ah = a + h @ c
    bnm = np.hstack([b + h @ d, h])
    p = sla.solve_continuous_lyapunov(ah, -bnm @ bnm.T)
    q = sla.solve_continuous_lyapunov(ah.T, -c.T @ np.linalg.solve(r, c))
    hankel = float(np.sqrt(np.max(np.linalg.eigvals(p @ q).real)))
    return float(1.0 / np.sqrt(1.0 - hankel**2))


def four_block(plant: ct.StateSpace, controller: ct.StateSpace) -> ct.StateSpace:
    """``[I; K] (I + G K)^-1 [I, G]`` for a negative-feedback ``K`` (inputs: output and input
    disturbances; outputs: plant output and controller output), as a state-space system."""
    g = _as_ss("plant", plant)
    k = _as_ss("controller", controller)
    ag, bg, cg, dg = _matrices(g)
    ak, bk, ck, dk = _matrices(k)
    ny, nu = dg.shape
    # Loop: y = G (u + w2) + w1, u = -K y.  Solve the algebraic loop y = cg xg + dg(-ck xk - dk y + w2) + w1.
    e = np.linalg.inv(np.eye(ny) + dg @ dk)
    # y = e (cg xg - dg ck xk + dg w2 + w1)
    cy = e @ np.hstack([cg, -dg @ ck])
    dy = e @ np.hstack([np.eye(ny), dg])
    cu = -np.hstack([np.zeros((nu, ag.shape[0])), ck]) - dk @ cy
    du = -dk @ dy
    ng, nk = ag.shape[0], ak.shape[0]
    a = np.zeros((ng + nk, ng + nk))
    a[:ng, :ng] = ag
    a[ng:, ng:] = ak
    a[:ng, :] += bg @ cu
    a[ng:, :] += bk @ cy
    bw = np.vstack([bg @ (du + np.hstack([np.zeros((nu, ny)), np.eye(nu)])), bk @ dy])
    return ct.ss(a, bw, np.vstack([cy, cu]), np.vstack([dy, du]))


def hinf_norm_below(system: ct.StateSpace, level: float) -> bool:
    """``True`` when ``system`` is stable and its H-infinity norm is below ``level`` (the
    Hamiltonian of the bounded-real lemma has no imaginary-axis eigenvalue; Boyd-Balakrishnan)."""
    a, b, c, d = _matrices(system)
    if a.size and np.max(np.linalg.eigvals(a).real) >= 0:
        return False
    if np.linalg.norm(d, 2) >= level:
        return False
    r = level**2 * np.eye(d.shape[1]) - d.T @ d
    ri = np.linalg.inv(r)
    a1 = a + b @ ri @ d.T @ c
    h = np.block([[a1, b @ ri @ b.T], [-c.T @ (np.eye(d.shape[0]) + d @ ri @ d.T) @ c, -a1.T]])
    eig = np.linalg.eigvals(h)
    scale = max(1.0, float(np.max(np.abs(eig))))
    return bool(np.all(np.abs(eig.real) > 1e-9 * scale))


def hinf_norm(system: ct.StateSpace, *, rtol: float = 1e-6) -> float:
    """The H-infinity norm of a stable system by bisection on :func:`hinf_norm_below`."""
    _, b, c, d = _matrices(system)
    lo = float(np.linalg.norm(d, 2))
    w = np.logspace(-3, 5, 400)
    resp = system(1j * w)
    resp = np.asarray(resp).reshape(system.noutputs, system.ninputs, -1)
    lo = max(lo, float(max(np.linalg.svd(resp[:, :, i], compute_uv=False)[0] for i in range(len(w)))))
    hi = max(2.0 * lo, 1e-12)
    while not hinf_norm_below(system, hi):
        hi *= 2.0
        if hi > 1e12:
            return float("inf")
    while hi - lo > rtol * hi:
        mid = 0.5 * (lo + hi)
        if hinf_norm_below(system, mid):
            hi = mid
        else:
            lo = mid
    return hi


def target_loop_shape(
    crossover_rad_s: float,
    *,
    low_gain_db: float = 60.0,
    rolloff_factor: float = 10.0,
) -> ct.TransferFunction:
    """Lanzon's target loop shape as a scalar transfer function: ``low_gain_db`` at low frequency,
    -20 dB/decade through ``crossover_rad_s``, -40 dB/decade above ``rolloff_factor *
    crossover_rad_s``: ``L(s) = wc / (s + wc / 10^(low_gain_db/20)) * wh / (s + wh)``
    (relative degree 2, ``|L(j wc)|`` about 1)."""
    wc = real("crossover_rad_s", crossover_rad_s)
    gain_db = real("low_gain_db", low_gain_db)
    factor = real("rolloff_factor", rolloff_factor)
    if not np.isfinite(wc) or wc <= 0:
        raise ValueError(f"crossover_rad_s: must be > 0, got {wc}")
    if not np.isfinite(gain_db) or gain_db <= 0:
        raise ValueError(f"low_gain_db: must be > 0 (a loop gain above 1 at low frequency), got {gain_db}")
    if not np.isfinite(factor) or factor <= 1:
        raise ValueError(f"rolloff_factor: must be > 1 (the -40 dB/decade corner above the crossover), got {factor}")
    wl = wc / 10 ** (gain_db / 20)
    wh = factor * wc
    return ct.tf([wc * wh], np.polymul([1, wl], [1, wh]))


def relative_degrees(plant: ct.StateSpace) -> tuple[list[int], FloatArray]:
    """Relative degree of each output of a strictly proper plant, and the decoupling matrix
    (row i: ``C_i A^(r_i - 1) B``)."""
    a, b, c, d = _matrices(plant)
    n = a.shape[0]
    if np.any(d != 0):
        raise ValueError("plant: must be strictly proper (D = 0) for a relative-degree weight")
    degrees, rows = [], []
    for i in range(c.shape[0]):
        ci = c[i]
        for k in range(1, n + 1):
            row = ci @ np.linalg.matrix_power(a, k - 1) @ b
            if np.max(np.abs(row)) > 1e-12 * max(1.0, np.max(np.abs(ci)) * np.max(np.abs(b))):
                degrees.append(k)
                rows.append(row)
                break
        else:
            raise ValueError(f"plant: output {i} is not affected by the inputs (infinite relative degree)")
    return degrees, np.array(rows)


def loop_shape_weight(
    plant: Any,
    loop_shape: Any,
    *,
    channel_gain: npt.ArrayLike | None = None,
    margin_rad_s: float = 1.0,
) -> ct.StateSpace:
    """A pre-compensator ``W1 = G_e(s)^-1 diag(channel_gain_i * L(s))`` for a square
    plant of full vector relative degree (``sum r_i = n``: no zero dynamics, the case of a robust
    feedback linearised plant). ``loop_shape`` is a scalar transfer function of relative degree at
    least ``max r_i`` (e.g. :func:`target_loop_shape`); ``channel_gain`` (default 1) de-weights or
    emphasises output channels.

    ``G_e(s) = G(s + e)`` is the plant with its poles shifted left by ``e = max(0, margin_rad_s +
    max Re(poles))``, so that the weight's zeros lie at least ``margin_rad_s`` left of the
    imaginary axis: an exact inverse would cancel the plant's undamped or unstable modes (Lanzon's
    plant has an undamped pair at the spin rate), leaving them in every closed loop. Hence
    ``G W1 = G(s) G(s + e)^-1 diag(L)``: ``diag(L)`` well above the plant's poles, the plant's
    own modes left for the synthesis to stabilise below.

    Construction: with full relative degree, ``x = T^-1 [y_i, y_i', ..., y_i^(r_i - 1)]`` and
    ``u = Dm^-1 (y^(r) - C_r x)`` (``C_r`` rows ``C_i A^r_i``): ``W1`` runs ``L`` per channel and
    feeds its output and derivatives (realised exactly from ``L``'s state) through that inverse."""
    g = _as_ss("plant", plant)
    a, _, c, _ = _matrices(g)
    margin = real("margin_rad_s", margin_rad_s)
    if not (margin >= 0 and np.isfinite(margin)):
        raise ValueError(f"margin_rad_s: must be finite and >= 0, got {margin}")
    shift = max(0.0, margin + float(np.max(np.linalg.eigvals(a).real))) if a.size else 0.0
    a = a - shift * np.eye(a.shape[0])
    if g.ninputs != g.noutputs:
        raise ValueError(f"plant: must be square, got {g.noutputs} outputs x {g.ninputs} inputs")
    degrees, dm = relative_degrees(g)
    n = a.shape[0]
    if sum(degrees) != n:
        raise ValueError(f"plant: relative degrees {degrees} sum to {sum(degrees)}, not the {n} states (zero dynamics)")
    if abs(np.linalg.det(dm)) < 1e-12 * max(1.0, np.max(np.abs(dm))) ** len(degrees):
        raise ValueError("plant: the decoupling matrix is singular")
    m = len(degrees)
    gains = np.ones(m) if channel_gain is None else np.asarray(channel_gain, dtype=float)
    if gains.shape != (m,) or not np.all(np.isfinite(gains)) or np.any(gains <= 0):
        raise ValueError(f"channel_gain: expected {m} finite positive numbers, got {gains}")
    ls = ct.ss(loop_shape) if not isinstance(loop_shape, ct.StateSpace) else loop_shape
    if ls.ninputs != 1 or ls.noutputs != 1:
        raise ValueError("loop_shape: must be a scalar (SISO) transfer function")
    al, bl, cl, dl = _matrices(ls)
    if np.any(dl != 0):
        raise ValueError("loop_shape: must be strictly proper")
    nl = al.shape[0]
    # Derivative k of L's output: C A^k xi + [k == rel deg] C A^(k-1) B v.
    t_rows = np.vstack([c[i] @ np.linalg.matrix_power(a, k) for i in range(m) for k in range(degrees[i])])
    cr = np.vstack([c[i] @ np.linalg.matrix_power(a, degrees[i]) for i in range(m)])
    tinv = np.linalg.inv(t_rows)
    # Stacked signals of channel i as linear maps of (xi_all, v): rows of [y_i, ..., y_i^(r_i - 1)] and y_i^(r_i).
    state_rows, state_d = [], []
    top_rows, top_d = [], []
    for i in range(m):
        for k in range(degrees[i] + 1):
            row = np.zeros(m * nl)
            row[i * nl:(i + 1) * nl] = gains[i] * cl @ np.linalg.matrix_power(al, k)
            dv = np.zeros(m)
            if k >= 1:
                dv[i] = gains[i] * float((cl @ np.linalg.matrix_power(al, k - 1) @ bl).item())
            if k < degrees[i]:
                state_rows.append(row)
                state_d.append(dv)
            else:
                top_rows.append(row)
                top_d.append(dv)
    if np.any(np.abs(np.array(state_d)) > 0):
        raise ValueError(f"loop_shape: relative degree must be at least {max(degrees)} (the plant's largest relative degree)")
    dmi = np.linalg.inv(dm)
    s_rows, top_r, top_dv = np.array(state_rows), np.array(top_rows), np.array(top_d)
    cw = dmi @ (top_r - cr @ tinv @ s_rows)
    dw = dmi @ top_dv
    aw = np.kron(np.eye(m), al)
    bw = np.kron(np.eye(m), bl)
    return ct.ss(aw, bw, cw, dw)


def singular_values(system: ct.StateSpace, omega: npt.ArrayLike) -> FloatArray:
    """Singular values (columns, descending) of ``system(j omega)`` at each frequency (rows)."""
    w = np.asarray(omega, dtype=float)
    resp = np.asarray(system(1j * w)).reshape(system.noutputs, system.ninputs, -1)
    return np.array([np.linalg.svd(resp[:, :, i], compute_uv=False) for i in range(len(w))])


__all__ = [
    "NcfsynResult",
    "four_block",
    "hankel_gamma_min",
    "hinf_norm",
    "hinf_norm_below",
    "loop_shape_weight",
    "minimal_realisation",
    "ncf_gamma_min",
    "ncfsyn",
    "plot_singular_values",
    "relative_degrees",
    "riccati_solutions",
    "singular_values",
    "target_loop_shape",
]

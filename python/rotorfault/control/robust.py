"""H-infinity loop shaping (McFarlane and Glover): normalised-coprime-factor robust stabilisation
from two Riccati equations, our own implementation (python-control has no Glover-McFarlane
synthesis and slycot does not wrap SLICOT's sb10id/sb10kd).

- :func:`ncfsyn`: the central controller of the shaped plant ``Gs = W2 G W1`` for
  ``gamma = factor * gamma_min``, returned as ``K = W1 Ks W2`` (a python-control ``StateSpace``)
  with the evidence checked before it is returned (:class:`NcfsynEvidence`,
  :func:`check_synthesis`): ``gamma_min`` two ways, the achieved four-block norm on the full,
  unreduced shaped plant, the closed-loop poles with the original plant and weights;
- :func:`loop_shape_weight`: a pre-compensator ``W1`` that gives a square plant of full relative
  degree (what robust feedback linearisation produces) a target loop shape ``G W1 = diag(L_i)``,
  with :func:`target_loop_shape` the scalar ``L`` (Lanzon's shape: a low-frequency gain, -20
  dB/decade through the crossover, -40 dB/decade above);
- :func:`plot_singular_values`: the singular values of a plant and of its shaped plant.

One answer on every install: the weights and the shaped plant are built in state space here
(:mod:`~rotorfault.control.realisation`; a ``TransferFunction`` argument is realised by our own
code, never by python-control's slycot-or-scipy conversion), minimal realisations and norms
(:mod:`~rotorfault.control.norms`) are ours, and the Riccati and Lyapunov equations are
scipy.linalg's. ``tests/cross/test_robust_install.py`` runs the designs with slycot hidden and
compares.

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

import math
import warnings
from dataclasses import dataclass
from typing import Any

import control as ct  # type: ignore[import-untyped]
import numpy as np
import numpy.typing as npt
import scipy.linalg as sla  # type: ignore[import-untyped]

from .._util.convert import FloatArray, float_array, real
from .._util.numeric import scaled_norm
from .norms import hinf_norm, hinf_norm_below, peak_gain
from .realisation import (
    as_state_space,
    balance_states,
    frequency_response,
    minimal_realisation,
    series,
    signal_names,
    stacked_state_names,
    state_space,
    system_matrices,
    with_signals,
)

#: The synthesis checks' tolerances (stated once; tests break each check against them):
#: the achieved four-block norm on the full shaped plant may exceed gamma by this fraction
#: (the norm itself is computed to 1e-9);
ACHIEVED_NORM_RTOL = 1e-6
#: gamma_min by the Riccati solutions and by the Hankel formula agree to this, times
#: gamma_min^2 (the Hankel formula's condition number: d gamma / gamma = gamma^2 h^2 dh / h),
#: and never worse than GAMMA_MIN_RTOL_CAP (beyond it the Hankel route cannot confirm
#: gamma_min and the design is refused). Measured on random badly scaled families: at most
#: 5e-10 gamma_min^2 (poles from 1e-6 to 1e3 rad/s in one plant);
GAMMA_MIN_RTOL = 1e-8
GAMMA_MIN_RTOL_CAP = 1e-3
#: the largest gamma_min the Hankel route can confirm on every install: 1 - h^2 = 1/gamma_min^2
#: is found by cancellation from gramians whose rounding (about 1e-12 gamma_min^2 relative on
#: the random badly scaled families, whatever the realisation: unbalanced, state-balanced,
#: square-root Cholesky factors) depends on the state units and on LAPACK's last bits. Measured
#: (seeds 1 and 3, both twins): at most 7.5e-6 at gamma_min <= 6.9e3, 3e-4..0.9 from 1.68e4 up
#: (1e-2 at 9.99e4 on one twin, 4e-4 on the other). Between, the decision against
#: GAMMA_MIN_RTOL_CAP would hinge on rounding, so beyond this value the design is refused by the
#: Riccati gamma_min alone (the same on every install and for every state scaling: twins agree
#: to 1e-7 at 1.05e4, measured) - a stability margin below 1e-4 is not a usable design anyway.
GAMMA_MIN_CONFIRMABLE_MAX = 1e4
#: a Riccati solution's residual relative to the size of its terms (measured: below 1e-12 for
#: gamma_min < 100, at most 4e-8 at gamma_min ~ 1e5 in the random families); a larger one is
#: not a solution;
RICCATI_RESIDUAL_RTOL = 1e-6
#: a mode at or right of the imaginary axis whose PBH measure (left eigenvector against the
#: unit-normalised input columns, right eigenvector against the unit-normalised output rows, on
#: the state-balanced realisation) is below this cannot be moved by any controller.
PBH_RTOL = 1e-9


@dataclass(frozen=True)
class NcfsynEvidence:
    """What :func:`ncfsyn` measured before returning, each checked:

    - ``gamma_min_riccati`` (``sqrt(1 + rho(X Z))``) and ``gamma_min_hankel`` (``(1 -
      ||[N M]||_H^2)^(-1/2)``) agree to ``GAMMA_MIN_RTOL gamma_min^2``;
    - ``riccati_residual_x``, ``riccati_residual_z``: residuals relative to the size of the
      equation's terms, below ``RICCATI_RESIDUAL_RTOL``;
    - ``achieved_norm``: ``||[I; Ks] (I + Gs Ks)^-1 [I, Gs]||_inf`` on the **full, unreduced**
      shaped plant ``W2 G W1`` (``full_states`` states; the synthesis used ``synthesis_states``),
      at most ``gamma (1 + ACHIEVED_NORM_RTOL)``;
    - ``closed_loop_poles``: the loop of the original plant with ``K = W1 Ks W2`` (every state of
      plant, weights and ``Ks``), all in the open left half-plane (``closed_loop_max_real < 0``).
    """

    gamma_min_riccati: float
    gamma_min_hankel: float
    riccati_residual_x: float
    riccati_residual_z: float
    achieved_norm: float
    full_states: int
    synthesis_states: int
    closed_loop_poles: npt.NDArray[np.complex128]

    @property
    def closed_loop_max_real(self) -> float:
        return float(np.max(self.closed_loop_poles.real)) if self.closed_loop_poles.size else -math.inf


@dataclass(frozen=True)
class NcfsynResult:
    """The outcome of :func:`ncfsyn`.

    ``controller`` is ``K = W1 Ks W2`` for the plant (negative feedback), ``shaped_controller`` is
    ``Ks`` for the shaped plant ``Gs = W2 G W1`` (negative feedback), ``shaped_plant`` the full,
    unreduced ``W2 G W1`` and ``synthesis_plant`` the minimal realisation the Riccati equations
    were solved on; ``gamma_min`` the optimal and ``gamma`` the achieved robust-stabilisation
    level (``gamma = factor * gamma_min``: the four-block norm ``||[I; Ks] (I + Gs Ks)^-1 [I,
    Gs]||_inf`` is at most ``gamma``), ``stability_margin = 1 / gamma`` (the
    normalised-coprime-factor uncertainty tolerated). ``x`` and ``z`` are the two Riccati
    solutions; ``evidence`` what was checked before returning (:class:`NcfsynEvidence`).

    Signal names: the shaped plant's inputs are W1's, its outputs W2's (the plant's when ``w2`` is
    the identity); ``controller`` reads the plant's outputs and drives its inputs,
    ``shaped_controller`` the shaped plant's; states keep their systems' names (prefixed by
    ``w1.``, ``plant.``, ``w2.`` when two collide), numbered ``ks_i`` and ``gs_i`` for the
    central controller and the minimal realisation, whose states stand for no single quantity.

    Examples:

        >>> import control as ct
        >>> from rotorfault.control import ncfsyn
        >>> result = ncfsyn(ct.ss([[-1.0]], [[1.0]], [[1.0]], [[0.0]]), ct.ss([[-0.1]], [[1.0]], [[1.0]], [[0.0]]))
        >>> round(result.gamma, 4), result.evidence.closed_loop_max_real < 0, result.shaped_plant.nstates
        (1.7898, True, 2)
    """

    controller: ct.StateSpace
    shaped_controller: ct.StateSpace
    shaped_plant: ct.StateSpace
    synthesis_plant: ct.StateSpace
    gamma_min: float
    gamma: float
    x: FloatArray
    z: FloatArray
    evidence: NcfsynEvidence

    @property
    def stability_margin(self) -> float:
        """``1 / gamma``: the size of normalised-coprime-factor perturbation tolerated."""
        return 1.0 / self.gamma


def _matrices(system: ct.StateSpace) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    return (np.asarray(system.A, dtype=float), np.asarray(system.B, dtype=float),
            np.asarray(system.C, dtype=float), np.asarray(system.D, dtype=float))


def _care(a: FloatArray, b: FloatArray, q: FloatArray, r: FloatArray, name: str) -> tuple[FloatArray, float]:
    """The stabilising solution of ``A^T X + X A - X B R^-1 B^T X + Q = 0`` with its relative
    residual; ``ValueError`` naming ``name`` when scipy finds none, the residual is above
    ``RICCATI_RESIDUAL_RTOL`` or ``A - B R^-1 B^T X`` is not stable."""
    try:
        # scipy's balancing casts a NaN scale to an index on extreme entries (a RuntimeWarning);
        # the residual and closed-loop checks below judge whatever comes back.
        with np.errstate(invalid="ignore", over="ignore"):
            x = sla.solve_continuous_are(a, b, q, r)
        if not np.all(np.isfinite(x)):
            raise np.linalg.LinAlgError("the solution is not finite")
    except (np.linalg.LinAlgError, ValueError) as exc:
        raise ValueError(f"{name}: no stabilising Riccati solution (scipy: {exc}); the shaped plant W2 G W1 "
                         "has a mode on the imaginary axis that no input moves or no output sees") from None
    x = (x + x.T) / 2
    g = b @ np.linalg.solve(r, b.T)
    terms = scaled_norm(q) + 2 * scaled_norm(a) * scaled_norm(x) + scaled_norm(x @ g @ x)
    residual = scaled_norm(a.T @ x + x @ a - x @ g @ x + q) / max(terms, 1e-300)
    if not residual <= RICCATI_RESIDUAL_RTOL:
        raise ValueError(f"{name}: the Riccati solution's residual is {residual:.3g} of its terms (above "
                         f"{RICCATI_RESIDUAL_RTOL:g}): the shaped plant is too ill-conditioned for this synthesis")
    closed = np.linalg.eigvals(a - g @ x)
    if closed.size and not np.max(closed.real) < 0:
        raise ValueError(f"{name}: the Riccati solution is not stabilising (closed-loop eigenvalue with real part "
                         f"{np.max(closed.real):.3g}): the shaped plant is not stabilisable and detectable")
    return x, residual


def _riccati(plant: ct.StateSpace) -> tuple[FloatArray, FloatArray, float, float]:
    a, b, c, d = _matrices(plant)
    s = np.eye(b.shape[1]) + d.T @ d
    r = np.eye(c.shape[0]) + d @ d.T
    ar = a - b @ np.linalg.solve(s, d.T @ c)
    x, rx = _care(ar, b, c.T @ np.linalg.solve(r, c), s, "control Riccati equation (X)")
    z, rz = _care(ar.T, c.T, b @ np.linalg.solve(s, b.T), r, "filter Riccati equation (Z)")
    return x, z, rx, rz


def riccati_solutions(plant: Any) -> tuple[FloatArray, FloatArray]:
    """``(X, Z)``: the stabilising solutions of the control and filter AREs of the normalised
    coprime factorisation of ``plant`` (module docs), each checked (residual, stabilising).
    ``ValueError`` if the plant is not stabilisable and detectable (no stabilising solution)."""
    x, z, _, _ = _riccati(as_state_space("plant", plant, static=False, discrete=False))
    return x, z


def _gamma_from_xz(x: FloatArray, z: FloatArray) -> float:
    return float(np.sqrt(1.0 + max(float(np.max(np.linalg.eigvals(x @ z).real)), 0.0)))


def ncf_gamma_min(plant: Any) -> float:
    """``gamma_min = sqrt(1 + rho(X Z))`` of a (shaped) plant, on its minimal realisation."""
    gs = minimal_realisation(as_state_space("plant", plant, static=False, discrete=False), field="plant")
    x, z = riccati_solutions(gs)
    return _gamma_from_xz(x, z)


def hankel_gamma_min(plant: Any, *, field: str = "plant") -> float:
    """``(1 - ||[N M]||_H^2)^(-1/2)`` from the Hankel singular values of the normalised left
    coprime factors (gramians from two Lyapunov equations): an independent route to ``gamma_min``
    (it uses ``Z`` for the factorisation but not ``X``). ``field``: the name refusals give it."""
    gs = minimal_realisation(as_state_space(field, plant, static=False, discrete=False), field=field)
    a, b, c, d = _matrices(gs)
    _, z = riccati_solutions(gs)
    r = np.eye(c.shape[0]) + d @ d.T
    h = -(b @ d.T + z @ c.T) @ np.linalg.inv(r)
    ah = a + h @ c
    bnm = np.hstack([b + h @ d, h])
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error", sla.LinAlgWarning)
            warnings.simplefilter("error", RuntimeWarning)
            p = sla.solve_continuous_lyapunov(ah, -bnm @ bnm.T)
            q = sla.solve_continuous_lyapunov(ah.T, -c.T @ np.linalg.solve(r, c))
    except (np.linalg.LinAlgError, ValueError, sla.LinAlgWarning, RuntimeWarning) as exc:
        raise ValueError(f"plant: the gramians of the coprime factors have no solution (scipy: {exc})") from None
    hankel_sq = float(np.max(np.linalg.eigvals(p @ q).real))
    if not 0.0 <= hankel_sq < 1.0:
        raise ValueError(f"plant: the Hankel norm of the normalised coprime factors is {math.sqrt(max(hankel_sq, 0)):.6g}, "
                         "not in [0, 1): the factorisation is wrong (ill-conditioned shaped plant)")
    return float(1.0 / np.sqrt(1.0 - hankel_sq))


def _pbh_measures(system: ct.StateSpace) -> list[tuple[complex, float, float]]:
    """``(eigenvalue, input measure, output measure)`` for each mode with real part >= 0 of the
    state-balanced realisation: the norm of the unit left eigenvector against the unit input
    columns, of the unit right eigenvector against the unit output rows (0: the mode is hidden)."""
    balanced, _ = balance_states(system)
    a, b, c, _ = _matrices(balanced)
    if a.shape[0] == 0:
        return []
    bn = b / np.maximum(scaled_norm(b, axis=0), 1e-300)[None, :]
    cn = c / np.maximum(scaled_norm(c, axis=1), 1e-300)[:, None]
    try:
        lams, left, right = sla.eig(a, left=True, right=True)
    except (np.linalg.LinAlgError, ValueError) as exc:
        raise ValueError(f"plant: the eigenvalues of the shaped plant could not be computed (scipy: {exc})") from None
    scale = max(float(np.max(np.abs(lams))), 1e-300)
    out = []
    for k, lam in enumerate(lams):
        if lam.real < -PBH_RTOL * max(abs(lam), scale * _EPS_SCALE):
            continue
        vl = left[:, k] / scaled_norm(left[:, k])
        vr = right[:, k] / scaled_norm(right[:, k])
        out.append((complex(lam), scaled_norm(vl.conj() @ bn), scaled_norm(cn @ vr)))
    return out


_EPS_SCALE = float(np.finfo(float).eps)


def _require_stabilisable_detectable(system: ct.StateSpace) -> None:
    """PBH eigenvector test (scale-free: :func:`_pbh_measures`) at every eigenvalue with a real
    part >= 0: ``ValueError`` naming the mode when no input moves it or no output sees it."""
    for lam, to_inputs, to_outputs in _pbh_measures(system):
        for name, value in (("stabilisable", to_inputs), ("detectable", to_outputs)):
            if value <= PBH_RTOL:
                raise ValueError(
                    f"plant: the shaped plant W2 G W1 is not {name}: the mode at {lam:.6g} cannot be "
                    f"stabilised (PBH measure {value:.2g}; no stabilising Riccati solution; a weight may cancel it)"
                )


def four_block(plant: Any, controller: Any) -> ct.StateSpace:
    """``[I; K] (I + G K)^-1 [I, G]`` for a negative-feedback ``K`` (inputs: output and input
    disturbances; outputs: plant output and controller output), as a state-space system (states:
    the plant's, then the controller's)."""
    g = as_state_space("plant", plant)
    k = as_state_space("controller", controller)
    ag, bg, cg, dg = _matrices(g)
    ak, bk, ck, dk = _matrices(k)
    ny, nu = dg.shape
    if dk.shape != (nu, ny):
        raise ValueError(f"controller: expected {nu} outputs x {ny} inputs (the plant's inputs x outputs), got {dk.shape[0]} x {dk.shape[1]}")
    # Loop: y = G (u + w2) + w1, u = -K y.  Solve the algebraic loop y = cg xg + dg(-ck xk - dk y + w2) + w1.
    try:
        e = np.linalg.inv(np.eye(ny) + dg @ dk)
    except np.linalg.LinAlgError:
        raise ValueError("controller: the loop is not well posed (I + D_G D_K is singular)") from None
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
    loop = state_space(a, bw, np.vstack([cy, cu]), np.vstack([dy, du]), g.dt)
    return with_signals(loop, states=stacked_state_names(("plant", g), ("controller", k)),
                        inputs=[f"disturbance_{label}" for label in (*g.output_labels, *g.input_labels)],
                        outputs=[*g.output_labels, *g.input_labels], name="four-block")


#: Largest ``gamma`` the central controller is built at: ``gamma^2`` (1e300) stays a float beside
#: ``X Z``. Far above any useful design: the tolerated perturbation ``1 / gamma`` is then 1e-150.
MAX_GAMMA = 1e150


def _central_controller(gs: ct.StateSpace, factor: float) -> tuple[ct.StateSpace, float, float, FloatArray, FloatArray, float, float]:
    a, b, c, d = _matrices(gs)
    x, z, rx, rz = _riccati(gs)
    gamma_min = _gamma_from_xz(x, z)
    # The plant's own gamma_min first: above the confirmable limit no factor helps, so the refusal
    # names it, not factor (a factor of 1e140 on such a plant blamed the factor).
    _require_confirmable(gamma_min)
    gamma = factor * gamma_min
    if not gamma <= MAX_GAMMA:  # gamma^2 below must stay a float (a factor of 1e300 overflowed it)
        raise ValueError(f"factor: gamma = factor * gamma_min = {factor:g} * {gamma_min:.6g} must be at most {MAX_GAMMA:g} "
                         "(the central controller needs gamma^2 as a float; a factor of 1.05-1.5 is the usual choice)")
    s = np.eye(b.shape[1]) + d.T @ d
    f = -np.linalg.solve(s, d.T @ c + b.T @ x)
    n = a.shape[0]
    lt = ((1.0 - gamma**2) * np.eye(n) + x @ z).T
    try:
        gain = gamma**2 * np.linalg.solve(lt, z @ c.T)
    except np.linalg.LinAlgError:
        raise ValueError(f"factor: {factor} is too close to 1 (the central controller's (1 - gamma^2) I + X Z is singular)") from None
    ak = a + b @ f + gain @ (c + d @ f)
    # Negative-feedback form of the positive-feedback central controller: C_K, D_K change sign.
    ks = state_space(ak, gain, -b.T @ x, d.T)
    return ks, gamma_min, gamma, x, z, rx, rz


def _require_confirmable(gamma_min: float) -> None:
    """The ``gamma_min check``'s first rule: the shaped plant's optimal gamma at most
    ``GAMMA_MIN_CONFIRMABLE_MAX`` (a property of the plant and the weights, whatever the factor)."""
    if not gamma_min <= GAMMA_MIN_CONFIRMABLE_MAX:
        raise ValueError(
            f"gamma_min check: the Riccati value {gamma_min:.12g} is above {GAMMA_MIN_CONFIRMABLE_MAX:g}, where the "
            "Hankel formula's rounding reaches the tolerance and cannot confirm it on every install (a gamma_min this "
            "large means the shaped plant W2 G W1 is close to having a mode no input moves or no output sees: "
            f"stability margin 1/gamma_min = {1 / gamma_min:.3g})")


def check_synthesis(
    plant: ct.StateSpace,
    w1: ct.StateSpace,
    w2: ct.StateSpace,
    shaped_controller: ct.StateSpace,
    gamma_min: float,
    gamma: float,
    *,
    synthesis_plant: ct.StateSpace | None = None,
    residuals: tuple[float, float] = (0.0, 0.0),
) -> NcfsynEvidence:
    """The checks :func:`ncfsyn` runs before it returns, on the original ``plant`` and weights, in
    this order: ``gamma_min`` at most ``GAMMA_MIN_CONFIRMABLE_MAX`` and against the Hankel formula
    (``gamma_min check``), the stability of
    the loop of ``plant`` with ``K = W1 Ks W2``, every state of plant, weights and controller
    (``internal-stability check``), the four-block norm of ``shaped_controller`` on the full
    shaped plant ``W2 G W1`` against ``gamma`` (``achieved-norm check``). ``ValueError`` naming
    the failed check and its cause; the evidence otherwise. ``synthesis_plant``: the realisation
    the Riccati equations were solved on (default: the full shaped plant)."""
    full = series(w1, plant, w2)
    used = full if synthesis_plant is None else synthesis_plant
    reduced = used.nstates < full.nstates
    _require_confirmable(gamma_min)
    hankel = hankel_gamma_min(used, field="the synthesis plant (a minimal realisation of W2 G W1)")
    tol = min(GAMMA_MIN_RTOL * gamma_min**2, GAMMA_MIN_RTOL_CAP)
    if not abs(hankel - gamma_min) <= tol * gamma_min:
        raise ValueError(
            f"gamma_min check: the Riccati value {gamma_min:.12g} and the Hankel formula's {hankel:.12g} differ by "
            f"{abs(hankel - gamma_min) / gamma_min:.3g} (relative; tolerance {tol:.3g}): at this gamma_min the Riccati "
            "solutions cannot be confirmed (a gamma_min this large means the shaped plant W2 G W1 is close to having "
            "a mode no input moves or no output sees: stability margin 1/gamma_min = "
            f"{1 / gamma_min:.3g})" if gamma_min > 1e2 else
            f"gamma_min check: the Riccati value {gamma_min:.12g} and the Hankel formula's {hankel:.12g} differ by "
            f"{abs(hankel - gamma_min) / gamma_min:.3g} (relative; tolerance {tol:.3g}): the Riccati solutions of the "
            "shaped plant are inaccurate (ill-conditioned W2 G W1)")
    controller = series(w2, shaped_controller, w1)
    loop = four_block(plant, controller)
    try:
        poles = np.asarray(np.linalg.eigvals(np.asarray(loop.A, dtype=float)), dtype=np.complex128)
    except np.linalg.LinAlgError as exc:
        raise ValueError(f"internal-stability check: the closed-loop eigenvalues could not be computed ({exc})") from None
    if poles.size and not np.max(poles.real) < 0:
        worst = poles[int(np.argmax(poles.real))]
        raise ValueError(f"internal-stability check: the loop of the plant with K = W1 Ks W2 has a pole at {worst:.6g} "
                         "(real part >= 0): the weights cancel an unstable or undamped mode of the plant, or the "
                         "controller does not stabilise it")
    achieved = peak_gain(four_block(full, shaped_controller), field="the four-block loop of Ks with W2 G W1")
    bound = gamma * (1.0 + ACHIEVED_NORM_RTOL)
    if not achieved.gain <= bound:
        cause = (f"the realisation the synthesis used ({used.nstates} of the {full.nstates} states) does not "
                 "represent the full shaped plant" if reduced else
                 "the central controller's formula lost accuracy (ill-conditioned Riccati solutions)")
        raise ValueError(f"achieved-norm check: the four-block norm of the controller on the full shaped plant W2 G W1 "
                         f"is {achieved.gain:.9g} (peak at {achieved.frequency_rad_s:.6g} rad/s), above gamma "
                         f"(1 + {ACHIEVED_NORM_RTOL:g}) = {bound:.9g}: {cause}")
    return NcfsynEvidence(gamma_min_riccati=gamma_min, gamma_min_hankel=hankel, riccati_residual_x=residuals[0],
                          riccati_residual_z=residuals[1], achieved_norm=achieved.gain, full_states=full.nstates,
                          synthesis_states=used.nstates, closed_loop_poles=poles)


def ncfsyn(
    plant: Any,
    w1: Any,
    w2: Any = None,
    factor: float = 1.1,
) -> NcfsynResult:
    """Glover-McFarlane loop-shaping synthesis: the central controller robustly stabilising the
    shaped plant ``Gs = W2 G W1`` at ``gamma = factor * gamma_min`` (``factor > 1``), and the
    plant's controller ``K = W1 Ks W2`` (negative feedback). ``w2`` defaults to the identity.

    Continuous time only (a discrete plant is refused: design in continuous time and
    discretise). The shaped plant is built in state space here and synthesised on its
    :func:`~rotorfault.control.realisation.minimal_realisation` (which removes only what is
    hidden relative to its own scale), after a scale-free PBH check that no hidden mode is on or
    right of the imaginary axis. Before returning, :func:`check_synthesis` runs on the original
    plant and weights; the result carries its :class:`NcfsynEvidence`.

    Examples:

        >>> import control as ct
        >>> import rotorfault as rf
        >>> plant = ct.ss([[-1.0]], [[1.0]], [[1.0]], [[0.0]])
        >>> weight = ct.ss([[-0.1]], [[1.0]], [[1.0]], [[0.0]])
        >>> result = rf.ncfsyn(plant, weight)
        >>> round(result.gamma_min, 4), round(result.stability_margin, 4), result.controller.nstates
        (1.6271, 0.5587, 3)
    """
    g = as_state_space("plant", plant, discrete=False)
    w1s = as_state_space("w1", w1, discrete=False)
    factor = real("factor", factor)
    if not np.isfinite(factor) or factor <= 1.0:
        raise ValueError(f"factor: must be finite and > 1 (gamma = factor * gamma_min; at 1 the central controller does not exist), got {factor}")
    if w1s.noutputs != g.ninputs:
        raise ValueError(f"w1: expected {g.ninputs} outputs (the plant's inputs), got {w1s.noutputs}")
    w2s = as_state_space("w2", np.eye(g.noutputs) if w2 is None else w2, discrete=False)
    if w2s.ninputs != g.noutputs:
        raise ValueError(f"w2: expected {g.noutputs} inputs (the plant's outputs), got {w2s.ninputs}")
    if w2 is None:
        w2s = with_signals(w2s, inputs=g.output_labels, outputs=g.output_labels, name="w2")
    full = with_signals(series(w1s, g, w2s), states=stacked_state_names(("w1", w1s), ("plant", g), ("w2", w2s)),
                        inputs=w1s.input_labels, outputs=w2s.output_labels, name="shaped-plant")
    if full.nstates == 0:
        raise ValueError("plant: the shaped plant W2 G W1 is static (no states): there is no loop shape to synthesise")
    # The weights may cancel stable plant modes (an inverting W1 does): synthesise on a minimal
    # realisation, after checking that no hidden mode is on or right of the imaginary axis
    # (such a cancellation leaves the closed loop unstable or undamped whatever Ks does).
    _require_stabilisable_detectable(full)
    gs = minimal_realisation(full, field="the shaped plant W2 G W1")
    if gs.nstates == 0:
        # Every state hidden (B = 0, C = 0 or a zero weight): scipy's Riccati solver failed on the
        # empty Hamiltonian with LAPACK's bare "dgges: lwork=0".
        raise ValueError("plant: the shaped plant W2 G W1 has no state its inputs move and its outputs see (its minimal "
                         "realisation is static: a zero weight, or B = 0 or C = 0): there is no loop shape to synthesise")
    # The minimal realisation's states are combinations of the shaped plant's: numbered, not named.
    gs = with_signals(gs, states=signal_names("gs", gs.nstates), inputs=full.input_labels, outputs=full.output_labels,
                      name="synthesis-plant")
    ks, gamma_min, gamma, x, z, rx, rz = _central_controller(gs, factor)
    # Negative feedback: the controllers read the (shaped) plant's outputs and drive its inputs.
    ks = with_signals(ks, states=signal_names("ks", ks.nstates), inputs=full.output_labels, outputs=full.input_labels,
                      name="shaped-controller")
    evidence = check_synthesis(g, w1s, w2s, ks, gamma_min, gamma, synthesis_plant=gs, residuals=(rx, rz))
    controller = with_signals(series(w2s, ks, w1s), states=stacked_state_names(("w2", w2s), ("ks", ks), ("w1", w1s)),
                              inputs=g.output_labels, outputs=g.input_labels, name="controller")
    return NcfsynResult(controller=controller, shaped_controller=ks, shaped_plant=full, synthesis_plant=gs,
                        gamma_min=gamma_min, gamma=gamma, x=x, z=z, evidence=evidence)


def target_loop_shape(
    crossover_rad_s: float,
    *,
    low_gain_db: float = 60.0,
    rolloff_factor: float = 10.0,
) -> ct.StateSpace:
    """Lanzon's target loop shape as a scalar system: ``low_gain_db`` at low frequency, -20
    dB/decade through ``crossover_rad_s``, -40 dB/decade above ``rolloff_factor *
    crossover_rad_s``: ``L(s) = wc / (s + wc / 10^(low_gain_db/20)) * wh / (s + wh)`` (relative
    degree 2, ``|L(j wc)|`` about 1), built in state space here (no transfer-function conversion,
    whose result differs by install) with the output and its scaled derivative as the states,
    ``x = [y, y' / wn]``, ``wn = sqrt(wl wh)``: :func:`loop_shape_weight` feeds ``y``, ``y'`` and
    ``y''`` through the plant's inverse, and as states (not as differences of large states) they
    carry no cancellation."""
    wc = real("crossover_rad_s", crossover_rad_s)
    gain_db = real("low_gain_db", low_gain_db)
    factor = real("rolloff_factor", rolloff_factor)
    if not np.isfinite(wc) or wc <= 0:
        raise ValueError(f"crossover_rad_s: must be finite and > 0, got {wc}")
    if not np.isfinite(gain_db) or gain_db <= 0:
        raise ValueError(f"low_gain_db: must be finite and > 0 (a loop gain above 1 at low frequency), got {gain_db}")
    if not np.isfinite(factor) or factor <= 1:
        raise ValueError(f"rolloff_factor: must be finite and > 1 (the -40 dB/decade corner above the crossover), got {factor}")
    wl = wc / 10 ** (gain_db / 20)
    wh = factor * wc
    wn = math.sqrt(wl * wh)
    shape = state_space([[0.0, wn], [-wl * wh / wn, -(wl + wh)]], [[0.0], [wc * wh / wn]], [[1.0, 0.0]], [[0.0]])
    return with_signals(shape, states=["y", "dy_per_wn"], inputs=["v"], outputs=["y"], name="loop-shape")


def relative_degrees(plant: ct.StateSpace) -> tuple[list[int], FloatArray]:
    """Relative degree of each output of a strictly proper plant, and the decoupling matrix
    (row i: ``C_i A^(r_i - 1) B``)."""
    a, b, c, d = system_matrices("plant", plant, static=False, discrete=False)
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
    g = as_state_space("plant", plant, static=False, discrete=False)
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
    ls = as_state_space("loop_shape", loop_shape, static=False, discrete=False)
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
    # W1 drives the plant's inputs from the shaped plant's (one loop shape L per channel).
    return with_signals(state_space(aw, bw, cw, dw), states=signal_names("w1", aw.shape[0]),
                        inputs=[f"shaped_{label}" for label in g.input_labels], outputs=g.input_labels, name="w1")


def singular_values(system: ct.StateSpace, omega: npt.ArrayLike) -> FloatArray:
    """Singular values (columns, descending) of ``system(j omega)`` at each frequency (rows)."""
    resp = frequency_response(as_state_space("system", system), omega)
    return np.asarray(np.linalg.svd(resp, compute_uv=False), dtype=np.float64)


def plot_singular_values(
    plant: ct.StateSpace,
    shaped: ct.StateSpace,
    path: str | None = None,
    *,
    omega: npt.ArrayLike | None = None,
    title: str = "",
    crossover_rad_s: float | None = None,
) -> Any:
    """Singular values (dB) of ``plant`` and of the shaped plant ``G W1`` against frequency
    ``omega`` (rad/s; default 1e-2..1e4), Lanzon's Fig. 4: computed here
    (:func:`singular_values`), drawn by :mod:`rotorfault.plotting.frequency`. Saved to ``path``
    if given."""
    from ..plotting.frequency import plot_singular_values_db

    w = np.logspace(-2, 4, 400) if omega is None else float_array("omega", omega, 1)
    curves = [(singular_values(plant, w), "G", "--", "0.5"), (singular_values(shaped, w), "G W1", "-", "black")]
    return plot_singular_values_db(w, curves, path, title=title or "open-loop singular values", crossover_rad_s=crossover_rad_s)


__all__ = [
    "ACHIEVED_NORM_RTOL",
    "GAMMA_MIN_RTOL",
    "GAMMA_MIN_RTOL_CAP",
    "GAMMA_MIN_CONFIRMABLE_MAX",
    "PBH_RTOL",
    "RICCATI_RESIDUAL_RTOL",
    "NcfsynEvidence",
    "NcfsynResult",
    "check_synthesis",
    "four_block",
    "hankel_gamma_min",
    "hinf_norm",
    "hinf_norm_below",
    "loop_shape_weight",
    "minimal_realisation",
    "ncf_gamma_min",
    "ncfsyn",
    "peak_gain",
    "plot_singular_values",
    "relative_degrees",
    "riccati_solutions",
    "singular_values",
    "target_loop_shape",
]

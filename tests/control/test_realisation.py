"""``rotorfault.control.realisation``: realisations built here, the same on every install.

Each against an independent computation: transfer functions evaluated as polynomials,
python-control's series connection, known minimal orders of systems built with hidden modes,
the gramians of the balanced realisation; and the case that broke the Lanzon design (issue 25):
the shaped plant from scipy's controller-canonical form, where an absolute threshold kept 6 of 11
states, keeps all 11 here. Frequency responses agree to 1e-9 relative unless stated."""

from __future__ import annotations

import control as ct
import numpy as np
import pytest
import scipy.signal

from rotorfault.control import realisation as R
from rotorfault.control import robust
from rotorfault.control.lanzon import LanzonVehicle

W = np.logspace(-3, 4, 60)


def _close(g1: ct.StateSpace, g2: ct.StateSpace, rtol: float = 1e-9, omega: np.ndarray = W) -> None:
    r1, r2 = R.frequency_response(g1, omega), R.frequency_response(g2, omega)
    for k in range(omega.size):
        scale = max(np.linalg.norm(r1[k], 2), np.linalg.norm(r2[k], 2), 1e-300)
        assert np.linalg.norm(r1[k] - r2[k], 2) <= rtol * scale, (omega[k], r1[k], r2[k])


def _polynomial_response(tf: ct.TransferFunction, omega: np.ndarray) -> np.ndarray:
    out = np.zeros((omega.size, tf.noutputs, tf.ninputs), dtype=complex)
    for i in range(tf.noutputs):
        for j in range(tf.ninputs):
            num, den = tf.num_list[i][j], tf.den_list[i][j]
            out[:, i, j] = np.polyval(num, 1j * omega) / np.polyval(den, 1j * omega)
    return out


def test_transfer_functions_realised_minimally() -> None:
    # A 2x2 with a shared denominator in each column and a direct term.
    tf = ct.tf([[[1, 2], [3]], [[1, 0, 5], [1]]], [[[1, 3, 2], [1, 4]], [[1, 3, 2], [1, 4]]])
    g = R.realise_transfer_function(tf)
    got, want = R.frequency_response(g, W), _polynomial_response(tf, W)
    np.testing.assert_allclose(got, want, rtol=1e-10, atol=1e-12)
    # McMillan degree: column 1 shares (s + 1)(s + 2), column 2 shares (s + 4): 3 states.
    assert g.nstates == 3
    # Badly scaled coefficients (poles at 1e-4 and 1e4): realised and evaluated to 1e-9.
    tf = ct.tf([1e4, 1], np.polymul([1, 1e-4], [1, 1e4]))
    np.testing.assert_allclose(R.frequency_response(R.realise_transfer_function(tf), W)[:, 0, 0],
                               _polynomial_response(tf, W)[:, 0, 0], rtol=1e-9)
    with pytest.raises(ValueError, match="g: an improper entry"):
        R.realise_transfer_function(ct.tf([1, 0, 0], [1, 1]), field="g")


def test_series_matches_python_control() -> None:
    rng = np.random.default_rng(1)
    g1 = ct.ss(rng.normal(size=(3, 3)), rng.normal(size=(3, 2)), rng.normal(size=(2, 3)), rng.normal(size=(2, 2)))
    g2 = ct.ss(rng.normal(size=(2, 2)), rng.normal(size=(2, 2)), rng.normal(size=(1, 2)), rng.normal(size=(1, 2)))
    ours = R.series(g1, g2)
    theirs = ct.series(g1, g2)
    np.testing.assert_allclose(R.frequency_response(ours, W), R.frequency_response(theirs, W), rtol=1e-12, atol=1e-12)
    with pytest.raises(ValueError, match=r"systems\[1\]: expected 1 inputs \(the outputs of systems\[0\]\), got 2"):
        R.series(g2, g1)


def test_balancing_undoes_state_units() -> None:
    rng = np.random.default_rng(2)
    a, b, c = rng.normal(size=(5, 5)), rng.normal(size=(5, 2)), rng.normal(size=(2, 5))
    t = 10 ** rng.uniform(-6, 6, 5)
    scaled = R.state_space(a * t[None, :] / t[:, None], b / t[:, None], c * t[None, :], np.zeros((2, 2)))
    balanced, s = R.balance_states(scaled)
    assert np.all(np.log2(s) == np.round(np.log2(s)))  # powers of two: an exact change of units
    np.testing.assert_array_equal(np.asarray(balanced.A), np.asarray(scaled.A) * s[None, :] / s[:, None])
    # The balanced entries are of the unscaled system's size (within the powers of two).
    assert np.max(np.abs(np.asarray(balanced.A))) < 8 * np.max(np.abs(a))
    _close(balanced, scaled, rtol=1e-10)


def _hidden(rng: np.random.Generator, scale_decades: float) -> tuple[ct.StateSpace, int]:
    """A system with a known minimal order: a controllable-and-observable part (poles from 1e-4
    to 1e4 rad/s), a stable uncontrollable mode and a stable unobservable mode, mixed by a
    random orthogonal change of basis and then state units spanning ``scale_decades``."""
    nm = int(rng.integers(2, 5))
    poles = -(10 ** rng.uniform(-4, 4, nm))
    am = np.diag(poles) + np.triu(rng.normal(size=(nm, nm)), 1) * 0.1 * np.sqrt(np.outer(-poles, -poles))
    bm = rng.normal(size=(nm, 2)) * np.sqrt(-poles)[:, None]
    cm = rng.normal(size=(2, nm)) * np.sqrt(-poles)[None, :]
    n = nm + 2
    a = np.zeros((n, n))
    a[:nm, :nm] = am
    a[nm, nm] = -0.5  # uncontrollable (zero row of B), observable
    a[nm + 1, nm + 1] = -2.0  # controllable, unobservable (zero column of C)
    b = np.zeros((n, 2))
    b[:nm] = bm
    b[nm + 1] = rng.normal(size=2)
    c = np.zeros((2, n))
    c[:, :nm] = cm
    c[:, nm] = rng.normal(size=2)
    t = 10 ** rng.uniform(0, scale_decades, n)
    return R.state_space(a * t[None, :] / t[:, None], b / t[:, None], c * t[None, :], np.zeros((2, 2))), nm


def test_minimal_realisation_removes_hidden_modes_and_nothing_else() -> None:
    # 100 systems with one uncontrollable and one unobservable mode, in units spanning 1e6:
    # never below the known order, the response unchanged (1e-8 relative; measured at most
    # 1.7e-11), and the hidden modes removed in all 100. The staircases alone left a mode in 3
    # (the tuning install) or 6 (numpy 2.4.6, scipy 1.17.1): removing it by the floor pass
    # disturbed the kept modes by 1e-11..6.5e-10 (rounding, install-dependent), above
    # HIDDEN_MODE_RTOL. The modal pass decides on the mode's own coupling instead: measured
    # 8e-19..2e-13 for those modes against at least 2.1e-2 for every genuine mode, and removing
    # it changes the response by 6e-15..2e-13.
    exact = 0
    for seed in range(100):
        g, order = _hidden(np.random.default_rng(seed), 6.0)
        reduced = R.minimal_realisation(g)
        assert order <= reduced.nstates <= order + 2
        exact += reduced.nstates == order
        _close(reduced, g, rtol=1e-8, omega=np.logspace(-6, 6, 40))
    assert exact == 100


@pytest.mark.parametrize("units", [1.0, 1e5])
def test_minimal_realisation_drops_a_mode_by_its_coupling_against_hidden_mode_rtol(units: float) -> None:
    # 1/(s + 1) + k/(s + 3): the second mode's share of the response is k/3 relative at s = 0
    # (measured 0.996 k). Kept at k = 1e-10 (above HIDDEN_MODE_RTOL = 1e-11), dropped at k =
    # 1e-12, whatever the state units.
    for k, states in ((1e-10, 2), (1e-12, 1)):
        g = R.state_space([[-1.0, 0.0], [0.0, -3.0]], [[1.0], [k / units]], [[1.0, units]], [[0.0]])
        reduced = R.minimal_realisation(g)
        assert reduced.nstates == states
        _close(reduced, g, rtol=1e-11 if states == 1 else 1e-13, omega=np.logspace(-3, 3, 13))


def _wide(seed: int) -> ct.StateSpace:
    """Six real poles log-uniform in 1e-9..1e9 rad/s, each with a gain of order one, in state
    units spanning 1e6: minimal."""
    rng = np.random.default_rng(seed)
    p = -(10 ** rng.uniform(-9, 9, 6))
    b = rng.normal(size=(6, 2)) * np.sqrt(-p)[:, None]
    c = rng.normal(size=(2, 6)) * np.sqrt(-p)[None, :]
    t = 10 ** rng.uniform(0, 6, 6)
    return R.state_space(np.diag(p), b / t[:, None], c * t[None, :], np.zeros((2, 2)))


def test_minimal_realisation_keeps_every_state_across_eighteen_decades() -> None:
    # The old absolute threshold (below) drops states of these minimal systems; ours keeps all.
    dropped_before = 0
    for seed in range(100):
        g = _wide(seed)
        assert R.minimal_realisation(g).nstates == 6
        dropped_before += _absolute_threshold(g).nstates < 6
    assert dropped_before >= 50  # measured: 84 of 100


def _absolute_threshold(system: ct.StateSpace, rtol: float = 1e-9) -> ct.StateSpace:
    """The reduction this package used before issue 25: Krylov directions kept when their norm
    exceeds ``rtol`` times ``||A||`` (an absolute threshold on the unbalanced realisation)."""
    a, b, c, d = (np.asarray(m, dtype=float) for m in (system.A, system.B, system.C, system.D))

    def basis(a: np.ndarray, b: np.ndarray) -> np.ndarray:
        n = a.shape[0]
        scale = max(1.0, float(np.linalg.norm(a, 2)))
        u, sv, _ = np.linalg.svd(b, full_matrices=False)
        q = u[:, sv > rtol * max(1.0, float(sv[0]))]
        new = q
        while new.shape[1] and q.shape[1] < n:
            w = a @ new
            for _ in range(2):
                w = w - q @ (q.T @ w)
            u, sv, _ = np.linalg.svd(w, full_matrices=False)
            new = u[:, sv > rtol * scale]
            if new.shape[1]:
                for _ in range(2):
                    new = new - q @ (q.T @ new)
                new, _ = np.linalg.qr(new)
                q = np.hstack([q, new])
        return q

    t = basis(a, b)
    a, b, c = t.T @ a @ t, t.T @ b, c @ t
    t = basis(a.T, c.T)
    return R.state_space(t.T @ a @ t, t.T @ b, c @ t, d)


def lanzon_shaped_plant_from_scipy(crossover_rad_s: float = 30.0) -> ct.StateSpace:
    """Lanzon's shaped plant ``G W1`` (printed I_zz) with the loop shape realised the way
    python-control does without slycot: scipy's controller-canonical form of the transfer
    function. The weight is then built from it exactly as ``design`` does."""
    wc = crossover_rad_s
    wl, wh = wc / 1e3, 10 * wc
    a, b, c, d = scipy.signal.tf2ss([wc * wh], np.polymul([1, wl], [1, wh]))
    shape = R.state_space(a, b, c, d)
    plant = LanzonVehicle().plant()
    return R.series(robust.loop_shape_weight(plant, shape), plant)


def test_lanzon_shaped_plant_keeps_all_eleven_states() -> None:
    gs = lanzon_shaped_plant_from_scipy()
    assert gs.nstates == 11
    # The old absolute threshold dropped 5 of them (issue 25) ...
    assert _absolute_threshold(gs).nstates == 6
    # ... ours keeps all, and the response is the same to 1e-9.
    reduced = R.minimal_realisation(gs)
    assert reduced.nstates == 11
    _close(reduced, gs, rtol=1e-9, omega=np.logspace(-4, 5, 90))


def test_balanced_realisation_has_equal_diagonal_gramians() -> None:
    rng = np.random.default_rng(4)
    a = rng.normal(size=(4, 4))
    a -= (max(np.linalg.eigvals(a).real) + 0.5) * np.eye(4)
    g = R.state_space(a, rng.normal(size=(4, 2)), rng.normal(size=(3, 4)), np.zeros((3, 2)))
    bal, hsv = R.balanced_realisation(g)
    ab, bb, cb = (np.asarray(m) for m in (bal.A, bal.B, bal.C))
    import scipy.linalg as sla

    p = sla.solve_continuous_lyapunov(ab, -bb @ bb.T)
    q = sla.solve_continuous_lyapunov(ab.T, -cb.T @ cb)
    np.testing.assert_allclose(p, np.diag(hsv), atol=1e-10 * hsv[0])
    np.testing.assert_allclose(q, np.diag(hsv), atol=1e-10 * hsv[0])
    assert np.all(np.diff(hsv) <= 0)
    _close(bal, g, rtol=1e-10)
    with pytest.raises(ValueError, match="system: a balanced realisation needs a stable system"):
        R.balanced_realisation(R.state_space([[1.0]], [[1.0]], [[1.0]], [[0.0]]))
    with pytest.raises(ValueError, match="system: a discrete-time system"):
        R.balanced_realisation(R.state_space([[0.5]], [[1.0]], [[1.0]], [[0.0]], dt=0.1))


def test_system_arguments_are_checked() -> None:
    with pytest.raises(ValueError, match="w1: the matrix B must be finite"):
        R.as_state_space("w1", ct.ss([[-1.0]], [[np.inf]], [[1.0]], [[0.0]]))
    with pytest.raises(ValueError, match="plant: a static system"):
        R.as_state_space("plant", np.eye(2), static=False)
    with pytest.raises(ValueError, match="plant: an empty system"):
        R.as_state_space("plant", np.zeros((0, 3)))
    with pytest.raises(TypeError, match="plant: expected a python-control StateSpace"):
        R.as_state_space("plant", "G")
    with pytest.raises(TypeError, match="plant: expected a python-control StateSpace"):
        R.as_state_space("plant", True)


@pytest.mark.parametrize("entry", [1e300, 1e51, 1e-51, 1e-300, 5e-324])
def test_absurd_and_subnormal_scales_are_refused_before_any_work(entry: float) -> None:
    # Before: OverflowError from the balancing, LAPACK's "DGGES parameter 7 had an illegal
    # value" from scipy's Riccati solver, or a pole at 5e-324 read as 0 (norm inf).
    a = [[-1.0, entry], [0.0, -2.0]] if entry > 1 else [[-entry, entry], [0.0, -entry]]
    g = R.state_space(a, [[1.0], [1.0]], [[1.0, 1.0]], [[0.0]])
    rule = r"the matrix A's largest entry must be 0 or lie in \[1e-50, 1e\+50\] in magnitude"
    from rotorfault.control import norms

    for call, field in ((norms.hinf_norm, "system"), (R.minimal_realisation, "system"),
                        (lambda s: robust.ncfsyn(s, np.eye(1)), "plant")):
        with pytest.raises(ValueError, match=rf"^{field}: {rule}"):
            call(g)
    # Zeros, and small entries beside a normal largest one (rounding where a zero was), are fine.
    assert R.as_state_space("g", R.state_space([[-1.0, 1e-77], [0.0, -2.0]], [[1.0], [0.0]], [[1.0, 5e-324]], [[0.0]])).nstates == 2


@pytest.mark.parametrize("case", ["large A", "large B and C", "small A and B", "both ends", "large D"])
def test_entries_at_the_accepted_limits_give_an_answer_or_a_named_refusal(case: str) -> None:
    # At 1e+-50 every entry point either answers or raises ValueError naming its check; no raw
    # LAPACK error, OverflowError or warning (warnings are errors in the test run).
    big, small = R.MAX_ENTRY, R.MIN_ENTRY
    g = {
        "large A": R.state_space([[-big, big], [0, -big]], [[1], [1]], [[1, 1]], [[0]]),
        "large B and C": R.state_space([[-1.0]], [[big]], [[big]], [[0]]),
        "small A and B": R.state_space([[-small]], [[small]], [[1]], [[0]]),
        "both ends": R.state_space([[-big, 0], [0, -small]], [[1], [1]], [[1, 1]], [[small]]),
        "large D": R.state_space([[-1.0]], [[1]], [[1]], [[big]]),
    }[case]
    from rotorfault.control import norms

    # The norms are exact here: G(0) = C (-A)^-1 B + D dominates, the gain at infinity is |D|.
    a, b, c, d = (np.asarray(m, dtype=float) for m in (g.A, g.B, g.C, g.D))
    at_zero = float(abs((c @ np.linalg.solve(-a, b) + d).item()))
    assert norms.hinf_norm(g) == pytest.approx(max(at_zero, abs(d.item())), rel=1e-9)
    if case == "large A":
        # (2 s + 3 a) / (s + a)^2, a = 1e50: the staircase, comparing the coupling with ||A||,
        # takes the Jordan block's second state for hidden; the response check catches it (0.667).
        with pytest.raises(ValueError, match=r"^system: minimal-realisation check: removing the 1 state\(s\) .* by 0\.667"):
            R.minimal_realisation(g)
    else:
        assert R.minimal_realisation(g).nstates == g.nstates
    for call in (R.balanced_realisation, robust.ncf_gamma_min, robust.hankel_gamma_min, lambda s: robust.ncfsyn(s, np.eye(1))):
        try:
            call(g)
        except ValueError as exc:
            assert str(exc).split(":")[0] in ("system", "plant", "controller", "the shaped plant W2 G W1",
                                              "control Riccati equation (X)",
                                              "filter Riccati equation (Z)", "gamma_min check", "achieved-norm check",
                                              "internal-stability check"), str(exc)

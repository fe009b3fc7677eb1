"""The one LQR (rotorfault.control.riccati.design_lqr) and its checks (issue 25): every check
refuses a case built to make it fail, the gains agree with python-control's lqr/dlqr on
well-posed cases, and plants in other units (state scalings up to 1e6) or nearly uncontrollable
give the same verdicts as their twins. The PBH tests of rotorfault.control.stabilisability are
checked against the core's rank rule and closed forms."""

from __future__ import annotations

import math
from typing import Any

import control as ct
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import rotorfault as rf
from rotorfault import vpp
from rotorfault.control import riccati
from rotorfault.control.riccati import RESIDUAL_RTOL, design_lqr, sampled_spectral_radius
from rotorfault.control.stabilisability import detectability, left_null_space, stabilisability

SETTINGS = settings(derandomize=True, max_examples=150, deadline=None)


def double_integrator() -> tuple[np.ndarray, np.ndarray]:
    return np.array([[0.0, 1.0], [0.0, 0.0]]), np.array([[0.0], [1.0]])


# -- agreement with python-control (a second implementation) ------------------------------------


def _relative(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.max(np.abs(a - b)) / np.max(np.abs(b)))


def test_double_integrator_has_the_closed_form() -> None:
    """q = diag(1, 0), r = 1: K = [1, sqrt(2)], X = [[sqrt 2, 1], [1, sqrt 2]] (analytic)."""
    d = design_lqr(double_integrator(), np.diag([1.0, 0.0]), [[1.0]])
    np.testing.assert_allclose(d.gain, [[1.0, math.sqrt(2)]], rtol=1e-13)
    np.testing.assert_allclose(d.riccati, [[math.sqrt(2), 1.0], [1.0, math.sqrt(2)]], rtol=1e-13)
    assert d.residual_rtol < 1e-15 and not d.discrete and d.sampled_spectral_radius is None
    np.testing.assert_allclose(sorted(d.closed_loop_eigenvalues.imag), [-math.sqrt(0.5), math.sqrt(0.5)], rtol=1e-13)


@pytest.mark.parametrize("seed", range(12))
def test_continuous_and_discrete_agree_with_python_control(seed: int) -> None:
    """Random stabilisable plants with random positive weights: K and X equal python-control's
    lqr and dlqr (whichever path it takes on this install) to 1e-9 relative."""
    rng = np.random.default_rng(seed)
    n, m = int(rng.integers(2, 8)), int(rng.integers(1, 4))
    a, b = rng.standard_normal((n, n)), rng.standard_normal((n, m))
    g = rng.standard_normal((n, n))
    q = g @ g.T + 0.1 * np.eye(n)
    h = rng.standard_normal((m, m))
    r = h @ h.T + 0.1 * np.eye(m)
    d = design_lqr((a, b), q, r)
    k, x, _ = ct.lqr(a, b, q, r)
    assert _relative(d.gain, np.asarray(k)) < 1e-9 and _relative(d.riccati, np.asarray(x)) < 1e-9
    ad = a / (1.1 * np.max(np.abs(np.linalg.eigvals(a)))) * 1.2  # some eigenvalues outside the unit circle
    dd = design_lqr(ct.ss(ad, b, np.eye(n), np.zeros((n, m)), 0.01), q, r)
    kd, xd, _ = ct.dlqr(ad, b, q, r)
    assert dd.discrete and dd.dt_s == 0.01
    assert _relative(dd.gain, np.asarray(kd)) < 1e-9 and _relative(dd.riccati, np.asarray(xd)) < 1e-9
    assert dd.sampled_spectral_radius == pytest.approx(np.max(np.abs(np.linalg.eigvals(ad - b @ dd.gain))), rel=1e-12)


def test_hover_and_vpp_designs_agree_with_python_control() -> None:
    """The designs the simulator flies: lqr_hover on quad-x and Wang's VPP with propeller 1
    failed. Measured residuals: 1.4e-15 and 1.6e-13 of the terms."""
    sim = rf.Simulator(rf.Airframe.preset("quad-x"))
    trim = rf.hover_trim(sim, position=(0, 0, -10))
    model = rf.linearize(sim, trim)
    a, b = model.A, model.B
    fb = rf.lqr_hover(sim, position=(0, 0, -10))
    q = np.diag(1.0 / np.array([1.0] * 6 + [0.1] * 3 + [1.0] * 3) ** 2)
    r = np.eye(4) / (0.1 * sim.airframe.hover_thrust_n / 4) ** 2
    assert _relative(fb.gain, np.asarray(ct.lqr(a, b, q, r)[0])) < 1e-9
    assert fb.design is not None and fb.design.residual_rtol < 1e-13 and fb.design.dt_s == sim.dt_s
    wang = vpp.preset()
    at = vpp.trim(wang, failed=(1,), speeds={3: 9000.0})
    model = vpp.linearize(wang, at)
    feedback = vpp.lqr(wang, at, dt_s=1e-3)
    assert feedback.design is not None and feedback.design.residual_rtol < 1e-11
    r_in = np.diag([1.0 / (1000.0**2 if s.startswith("omega") else 0.05**2) for s in model.input_labels])
    k = np.asarray(ct.lqr(model.A, model.B, np.diag(1.0 / vpp.STATE_SCALE**2), r_in)[0])
    assert _relative(feedback.gain[2:], k) < 1e-9


# -- each check refuses a case built to fail it -------------------------------------------------


def test_stabilisability_refuses_and_names_the_mode_not_the_weights() -> None:
    """An integrator no input reaches (and an unstable oscillation no input reaches), whatever
    the weights: the message names the check, the model and the mode, and says no weights help."""
    a = np.diag([0.0, -1.0])
    b = np.array([[0.0], [1.0]])
    for r in ([[1.0]], [[1e-9]]):
        with pytest.raises(ValueError, match=r"^stabilisability: the model is not stabilisable, so no weights q, r give "
                           r"a stabilising gain: at eigenvalue 0 no input moves x1 \(PBH rank 1 of 2\)$"):
            design_lqr((a, b), np.eye(2), r)
    osc = np.array([[0.1, 2.0, 0.0], [-2.0, 0.1, 0.0], [0.0, 0.0, -1.0]])
    with pytest.raises(ValueError, match=r"at eigenvalue 0\.1 \+- 2j no input moves any combination of position; speed \(PBH rank 2 of 3\)$"):
        design_lqr((osc, [[0.0], [0.0], [1.0]]), np.eye(3), [[1.0]], state_names=["position", "speed", "z"])


def test_detectability_refuses_an_unstable_mode_the_weights_ignore() -> None:
    """An unstable state q does not weigh: the optimal gain would leave it (python-control
    returns K = 0 for the decoupled case); here the weights are the cause and the message says so."""
    a = np.diag([1.0, -1.0])
    b = np.eye(2)
    with pytest.raises(ValueError, match=r"^detectability: q does not weigh a mode of the model that is not stable.*"
                       r"at eigenvalue 1 the weight does not see the state along x1 .*weigh it in q$"):
        design_lqr((a, b), np.diag([0.0, 1.0]), np.eye(2))
    # An integrator's position unweighted in the hover model: named as a state.
    sim = rf.Simulator(rf.Airframe.preset("quad-x"))
    q = np.diag([0.0] + [1.0] * 11)
    with pytest.raises(ValueError, match=r"detectability: .*the weight does not see the state along north position x"):
        rf.lqr_hover(sim, q=q)
    with pytest.raises(ValueError, match=r"detectability: .*north position x"):
        rf.lqr_hover_allocated(sim, rf.Allocator(sim.airframe), q=q)
    wang = vpp.preset()
    with pytest.raises(ValueError, match=r"detectability: .*the weight does not see the state along yaw psi"):
        vpp.lqr(wang, vpp.trim(wang, failed=(1,), speeds={3: 9000.0}), q=np.diag([1.0] * 8 + [0.0] + [1.0] * 3))


def test_the_sampled_loop_at_a_long_control_period_is_refused() -> None:
    """A continuous gain whose zero-order-hold loop is unstable at the controller's period: the
    double integrator with a 10 rad/s loop at dt = 0.5 s; the hover LQR of quad-x at 5 Hz (its
    fastest pole 5.95 rad/s); the VPP LQR at 2 Hz. The same designs pass at 400 Hz / 1 kHz."""
    a, b = double_integrator()
    fast = design_lqr((a, b), np.diag([1e4, 1.0]), [[1.0]], dt_s=0.001)
    assert fast.sampled_spectral_radius is not None and fast.sampled_spectral_radius < 1.0
    with pytest.raises(ValueError, match=r"^sampled loop: the gain for the model held over the control period dt_s = 0\.5 s"):
        design_lqr((a, b), np.diag([1e4, 1.0]), [[1.0]], dt_s=0.5)
    with pytest.raises(ValueError, match=r"^sampled loop: .*quad-x.*dt_s = 0\.2 s.*spectral radius 1\.2"):
        rf.lqr_hover(rf.Simulator(rf.Airframe.preset("quad-x"), dt_s=0.2))
    sim = rf.Simulator(rf.Airframe.preset("quad-x"), dt_s=0.2)
    with pytest.raises(ValueError, match=r"^sampled loop: .*virtual control"):
        rf.lqr_hover_allocated(sim, rf.Allocator(sim.airframe))
    wang = vpp.preset()
    with pytest.raises(ValueError, match=r"^sampled loop: .*VPP hover model of wang.*dt_s = 0\.5 s"):
        vpp.lqr(wang, vpp.trim(wang, failed=(1,), speeds={3: 9000.0}), dt_s=0.5)


def test_the_residual_is_judged_against_the_equations_terms() -> None:
    """Why the check reads the residual relative to the Riccati equation's terms, not to ||Q||:
    x1' = x2, x2' = u, x3' = 0.5 x3 + e u with e = 1e-4 (an unstable mode barely reached) has
    ||X|| = 4e9 ||Q||. Our solution leaves 4.3e-15 of the terms (python-control's slycot path
    leaves 1.4e-6, 1.2e4 ||Q||), which is 3.5e-5 ||Q||: a check against ||Q|| would refuse a
    correct solution."""
    a = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.5]])
    d = design_lqr((a, [[0.0], [1.0], [1e-4]]), np.eye(3), [[1.0]])
    assert d.residual_rtol < 1e-13 and d.residual_q > 1e-6
    assert np.linalg.norm(d.riccati) / math.sqrt(3) > 1e9
    assert np.max(d.closed_loop_eigenvalues.real) < 0


def test_sampled_spectral_radius_is_the_zero_order_hold_loop() -> None:
    """Scalar plant x' = a x + b u, u = -k x held over h: x+ = (e^(ah) - (e^(ah) - 1) b k / a) x."""
    a, b, k, h = 0.7, 2.0, 3.0, 0.4
    expected = abs(math.exp(a * h) - (math.exp(a * h) - 1.0) * b * k / a)
    assert sampled_spectral_radius([[a]], [[b]], [[k]], h) == pytest.approx(expected, rel=1e-13)


def test_a_wrong_riccati_solution_is_refused(monkeypatch: pytest.MonkeyPatch) -> None:
    """Break the solver and watch each check fire: a perturbed solution fails the residual, the
    anti-stabilising solution of x' = x + u (X = 1 - sqrt 2: residual 0, closed loop +sqrt 2) fails
    the closed loop, in continuous and discrete time."""
    from scipy import linalg

    real_care = linalg.solve_continuous_are
    monkeypatch.setattr(linalg, "solve_continuous_are", lambda *args, **kw: real_care(*args, **kw) * (1 + 1e-5))
    monkeypatch.setattr(riccati, "NEWTON_STEPS", 0)
    with pytest.raises(ValueError, match=r"^riccati residual: .*leaves a residual of [0-9.e-]+ of its terms"):
        design_lqr(double_integrator(), np.eye(2), [[1.0]])
    monkeypatch.setattr(linalg, "solve_continuous_are", lambda *args, **kw: np.array([[1.0 - math.sqrt(2.0)]]))
    with pytest.raises(ValueError, match=r"^closed loop: .*Re = 1\.41421"):
        design_lqr(([[1.0]], [[1.0]]), [[1.0]], [[1.0]])
    # discrete x+ = 2 x + u, q = r = 1: X^2 - 4 X - 1 = 0; the other root 2 - sqrt 5 gives |A - BK| > 1.
    monkeypatch.setattr(linalg, "solve_discrete_are", lambda *args, **kw: np.array([[2.0 - math.sqrt(5.0)]]))
    with pytest.raises(ValueError, match=r"^closed loop: .*\|lambda\| = "):
        design_lqr(([[2.0]], [[1.0]]), [[1.0]], [[1.0]], discrete=True)


def test_a_failing_solver_is_reported_as_such(monkeypatch: pytest.MonkeyPatch) -> None:
    from scipy import linalg

    def fail(*args: Any, **kw: Any) -> None:
        raise np.linalg.LinAlgError("Failed to find a finite solution.")

    monkeypatch.setattr(linalg, "solve_continuous_are", fail)
    with pytest.raises(ValueError, match=r"^riccati: scipy.linalg.solve_continuous_are found no stabilising solution"):
        design_lqr(double_integrator(), np.eye(2), [[1.0]])


@pytest.mark.parametrize(
    ("plant", "message"),
    [
        ((np.zeros((0, 0)), np.zeros((0, 1))), r"^plant: a static system \(no states\)"),
        ((np.zeros((2, 2)), np.zeros((2, 0))), r"^plant B: no inputs"),
        ((np.array([[0.0, math.nan], [0.0, 0.0]]), np.ones((2, 1))), r"^plant A\[0, 1\]: must be finite, got nan"),
        ((np.zeros((2, 2)), np.array([[math.inf], [0.0]])), r"^plant B\[0, 0\]: must be finite, got inf"),
        ((np.zeros((2, 3)), np.ones((2, 1))), r"^plant A: expected a square matrix"),
        ((np.zeros((2, 2)), np.ones((3, 1))), r"^plant B: expected 2 rows"),
    ],
)
def test_empty_static_and_non_finite_plants_are_refused(plant: tuple[np.ndarray, np.ndarray], message: str) -> None:
    with pytest.raises(ValueError, match=message):
        design_lqr(plant, np.eye(plant[0].shape[0]) if plant[0].shape[0] else np.zeros((0, 0)), np.eye(max(plant[1].shape[1], 1)))


def test_python_control_systems_and_their_timebase() -> None:
    """dt = 0: continuous; dt > 0 or True: discrete (the discrete Riccati equation, not the
    continuous one python-control's lqr would use); dt = None and contradictions are refused; a
    static system is refused."""
    a, b = double_integrator()
    cont = design_lqr(ct.ss(a, b, np.eye(2), np.zeros((2, 1))), np.eye(2), [[1.0]])
    assert not cont.discrete
    held = ct.c2d(ct.ss(a, b, np.eye(2), np.zeros((2, 1))), 0.1)
    disc = design_lqr(held, np.eye(2), [[1.0]])
    assert disc.discrete and disc.dt_s == 0.1
    assert _relative(disc.gain, np.asarray(ct.dlqr(held.A, held.B, np.eye(2), [[1.0]])[0])) < 1e-9
    unspecified_period = design_lqr(ct.ss(held.A, held.B, np.eye(2), np.zeros((2, 1)), True), np.eye(2), [[1.0]])
    assert unspecified_period.discrete and unspecified_period.dt_s is None
    np.testing.assert_allclose(unspecified_period.gain, disc.gain, rtol=1e-14)
    with pytest.raises(ValueError, match=r"^discrete: False contradicts plant.dt = 0.1"):
        design_lqr(held, np.eye(2), [[1.0]], discrete=False)
    with pytest.raises(ValueError, match=r"^dt_s: 0.2 contradicts plant.dt = 0.1"):
        design_lqr(held, np.eye(2), [[1.0]], dt_s=0.2)
    with pytest.raises(ValueError, match=r"^plant.dt: None"):
        design_lqr(ct.ss(a, b, np.eye(2), np.zeros((2, 1)), None), np.eye(2), [[1.0]])
    with pytest.raises(ValueError, match=r"^plant: a static system"):
        design_lqr(ct.ss([], [], [], [[1.0]]), np.zeros((0, 0)), [[1.0]])
    with pytest.raises(TypeError, match=r"^plant: expected \(A, B\) or a python-control StateSpace"):
        design_lqr(ct.tf([1], [1, 1]), np.eye(1), [[1.0]])
    with pytest.raises(TypeError, match=r"^discrete:"):
        design_lqr((a, b), np.eye(2), [[1.0]], discrete="yes")  # type: ignore[arg-type]
    # The discrete Riccati equation on a discrete plant is not the continuous one: the gains differ.
    assert _relative(disc.gain, np.asarray(ct.lqr(held.A, held.B, np.eye(2), [[1.0]])[0])) > 1e-2


@pytest.mark.parametrize(
    ("q", "r", "message"),
    [
        (np.zeros((2, 2)), [[1.0]], r"^q: all zero on the diagonal: the cost must weigh some state"),
        ([[1.0, 2.0], [0.0, 1.0]], [[1.0]], r"^q: must be symmetric"),
        ([[1.0, 2.0], [2.0, 1.0]], [[1.0]], r"^q: must be positive semi-definite"),
        (np.diag([1.0, -1.0]), [[1.0]], r"^q\[1, 1\]: must be >= 0"),
        (np.eye(2), [[0.0]], r"^r: all zero on the diagonal"),
        (np.eye(3), [[1.0]], r"^q: expected a 2x2 matrix, got shape \(3, 3\)"),
        (np.eye(2), [[math.nan]], r"^r\[0, 0\]: must be finite, got nan"),
        (np.eye(2), np.ones((2, 2)), r"^r: expected a 1x1 matrix"),
        # Found by the long hostile run: a subnormal R overflowed the gain into a NaN warning.
        (np.eye(2), [[1e-310]], r"^r\[0, 0\]: 1e-310 is subnormal \(nonzero and below 2.23e-308"),
        (np.diag([1.0, 5e-324]), [[1.0]], r"^q\[1, 1\]: 4.94e-324 is subnormal"),
    ],
)
def test_weights_are_checked(q: Any, r: Any, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        design_lqr(double_integrator(), q, r)
    with pytest.raises(ValueError, match=r"^r: must be positive definite"):
        design_lqr((np.zeros((1, 1)), np.ones((1, 2))), [[1.0]], [[1.0, 1.0], [1.0, 1.0]])
    with pytest.raises(ValueError, match=r"^dt_s: must be > 0 and finite"):
        design_lqr(double_integrator(), np.eye(2), [[1.0]], dt_s=math.inf)


# -- scale-free verdicts --------------------------------------------------------------------------


@st.composite
def twins(draw: Any) -> tuple[str, np.ndarray, np.ndarray, np.ndarray]:
    """A random plant of one kind and a state scaling D (10^-6 .. 10^6 per state):
    ``generic``; ``uncontrollable`` (a block no input reaches, any stability); ``weak`` (the last
    state reached with a gain 1e-4 to 1e-2 of the others: stabilisable, with large gains)."""
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    kind = draw(st.sampled_from(["generic", "uncontrollable", "weak"]))
    n, m = int(rng.integers(2, 7)), int(rng.integers(1, 3))
    a, b = rng.standard_normal((n, n)), rng.standard_normal((n, m))
    if kind == "uncontrollable":
        k = int(rng.integers(1, n))
        a[k:, :k] = 0.0
        b[k:, :] = 0.0
    elif kind == "weak":
        coupling = 10.0 ** rng.uniform(-4, -2)
        b[-1, :] *= coupling
        a[-1, :-1] *= coupling
    return kind, a, b, 10.0 ** rng.uniform(-6, 6, size=n)


def _verdict(a: np.ndarray, b: np.ndarray, q: np.ndarray) -> tuple[str, Any]:
    try:
        return "designed", design_lqr((a, b), q, np.eye(b.shape[1]))
    except ValueError as error:
        return str(error).split(":")[0], str(error)


@SETTINGS
@given(twins())
def test_scaled_and_nearly_uncontrollable_twins_give_the_same_verdict(case: tuple[str, np.ndarray, np.ndarray, np.ndarray]) -> None:
    """x_s = D x: A_s = D A D^-1, B_s = D B, Q_s = D^-1 Q D^-1. The verdict (designed or which
    check refused) is the same, the named modes are the same, and K_s = K D^-1 to 1e-6 (measured
    over 1500 pairs: 1.4e-7 at worst, a coupling of 2e-4 with ||X|| = 4e13 ||Q||, 1e-9 typical;
    residuals at most 4.6e-11 of the terms)."""
    kind, a, b, d = case
    n = a.shape[0]
    q = np.eye(n)
    first, detail = _verdict(a, b, q)
    second, detail_s = _verdict(d[:, None] * a / d[None, :], d[:, None] * b, q / d[:, None] / d[None, :])
    assert first == second
    if kind == "weak" or kind == "generic":
        assert first == "designed"
    if first == "designed":
        assert detail.residual_rtol <= RESIDUAL_RTOL and detail_s.residual_rtol <= RESIDUAL_RTOL
        assert _relative(detail_s.gain * d[None, :], detail.gain) < 1e-6
        assert np.max(detail.closed_loop_eigenvalues.real) < 0
    elif first == "stabilisability":
        # The same modes (eigenvalues, ranks, number of directions), and every direction either
        # twin names, taken to the unscaled units (w = D w_s), is one no input moves: w^T B = 0,
        # w^T A B = 0 and w^T p(A) = 0 with p the mode's real factor of the characteristic
        # polynomial. (The bases may differ: they are chosen in each twin's balanced units.)
        plain = stabilisability(a, b).failing
        scaled = stabilisability(d[:, None] * a / d[None, :], d[:, None] * b).failing
        assert [(m.rank, len(m.directions)) for m in plain] == [(m.rank, len(m.directions)) for m in scaled]
        for mode, twin in zip(plain, scaled):
            assert abs(mode.eigenvalue - twin.eigenvalue) <= 1e-6 * max(1.0, abs(mode.eigenvalue))
            lam = mode.eigenvalue
            factor = a - lam.real * np.eye(n) if lam.imag == 0 else (a - lam.real * np.eye(n)) @ (a - lam.real * np.eye(n)) + lam.imag**2 * np.eye(n)
            for w in [dd.coefficients for dd in mode.directions] + [d * dd.coefficients for dd in twin.directions]:
                w = w / np.linalg.norm(w)
                for image, size in ((w @ b, np.linalg.norm(b)), (w @ a @ b, np.linalg.norm(a @ b)), (w @ factor, np.linalg.norm(factor))):
                    assert np.linalg.norm(image) <= 1e-6 * size


def test_pbh_rank_is_the_cores_rank_rule() -> None:
    """The PBH rank at every tested eigenvalue equals rotorfault's scale-free rank
    (_rfcore.scale_free_rank) of the same pencil; a column 1e-12 of the others still counts."""
    fixed = vpp.fixed_pitch(vpp.preset())
    for failed in ((), (1,)):
        model = vpp.linearize(fixed, vpp.fixed_pitch_trim(fixed, failed=failed), pitch_fixed=True)
        test = stabilisability(model.A, model.B)
        for mode in test.modes:
            pencil = np.hstack([model.A - mode.eigenvalue.real * np.eye(12), model.B])
            assert mode.rank == rf._rfcore.scale_free_rank(pencil) == left_null_space(pencil)[0]
    tiny = stabilisability(np.zeros((2, 2)), np.diag([1.0, 1e-12]))
    assert tiny.holds and tiny.modes[0].rank == 2


def test_detectability_names_state_directions() -> None:
    """(A, C) with C blind to x1 + x2 at eigenvalue 0: the direction is named, in C's null space."""
    a = np.zeros((2, 2))
    c = np.array([[1.0, -1.0]])
    test = detectability(a, c, state_names=["x", "y"])
    assert not test.holds
    (direction,) = test.failing[0].directions
    assert direction.text == "x together with y: x + y"
    np.testing.assert_allclose(c @ direction.coefficients, 0.0, atol=1e-15)


def test_detectability_of_a_pair_balancing_would_overflow() -> None:
    """A with an entry of 1e300 is balanced by scales down to 2^-1000, which divide C^T's rows
    past the float range; B's columns are shifted by a power of two instead (rank and left null
    space unchanged). Analytic answer: O = [C; CA] = [[0, 1e300], [1e600, 1e300]] has rank 2,
    so the pair is observable, hence detectable; no warning on the way."""
    import warnings

    from rotorfault.control.stabilisability import _rows_divided

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        test = detectability(np.array([[0.0, 0.0], [1e300, 1.0]]), np.array([[0.0, 1e300]]))
    assert test.holds and test.failing == ()
    # Exact, and the plain quotient wherever nothing overflows.
    rng = np.random.default_rng(7)
    b = rng.normal(size=(5, 3)) * np.exp2(rng.integers(-50, 50, size=(5, 3)))
    scale = np.exp2(rng.integers(-40, 40, size=5)).astype(float)
    assert np.array_equal(_rows_divided(b, scale), b / scale[:, None])
    shifted = _rows_divided(np.array([[1e300, 3.0], [1.0, 1.0]]), np.array([2.0**-1000, 1.0]))
    # Column 1 (3 x 2^1000 would pass 2^1000) shifted by 2^-2; column 0 keeps its ratio exactly.
    assert np.all(np.isfinite(shifted)) and shifted[:, 1].tolist() == [3.0 * 2.0**998, 0.25]
    assert shifted[0, 0] * 2.0**-1000 / shifted[1, 0] == 1e300


def test_pbh_tests_refuse_a_subnormal_entry_and_see_the_smallest_normal_one() -> None:
    """An oscillator seen through C = [0, c]: O = [C; CA] = [[0, c], [-c, 0]] has rank 2 for any
    c != 0, so the pair is detectable. c = 1e-300 is seen (the scaling lifts it); c = 1e-310 lies
    beyond the 2^+-1000 scaling and read as 0 (not detectable, wrong) after an overflow warning in
    the complex pencil's norms (long hostile run, 2026-11-28): it is refused by name instead. The
    norms are exact for a complex column whose peak is subnormal (a power-of-two scaling)."""
    import warnings

    from rotorfault.control.stabilisability import _norms

    oscillator = np.array([[0.0, 1.0], [-1.0, 0.0]])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert detectability(oscillator, [[0.0, 1e-300]]).holds
        with pytest.raises(ValueError, match=r"^c: an entry of 1e-310 is subnormal"):
            detectability(oscillator, [[0.0, 1e-310]])
        with pytest.raises(ValueError, match=r"^b: an entry of -4.94e-324 is subnormal"):
            stabilisability(oscillator, [[0.0], [-5e-324]])
        column = np.array([[3e-310 + 4e-310j], [0.0]])
        assert _norms(column, 0)[0] == abs(3e-310 + 4e-310j)


def test_discrete_stabilisability_tests_the_unit_circle() -> None:
    """Discrete: |lambda| >= 1 needs an input (a mode at 0.5 does not, one at -1 does)."""
    a = np.diag([0.5, -1.0])
    assert stabilisability(a, [[1.0], [0.0]], discrete=False).holds  # continuous: both stable
    refused = stabilisability(a, [[1.0], [0.0]], discrete=True)
    assert not refused.holds and refused.failing[0].eigenvalue == -1.0
    assert stabilisability(a, [[0.0], [1.0]], discrete=True).holds


def test_python_control_with_slycot_returns_a_non_solution_here() -> None:
    """Why rotorfault never calls control.lqr for a design: on the healthy fixed-pitch model
    (rank 10, not stabilisable) python-control with slycot returned a gain whose closed loop is
    unstable and whose Riccati residual is ~4e6 ||Q|| (issue 25); without slycot it raises. Our
    design refuses before solving (test_wang_flights)."""
    pytest.importorskip("slycot")
    fixed = vpp.fixed_pitch(vpp.preset())
    model = vpp.linearize(fixed, vpp.fixed_pitch_trim(fixed, failed=()), pitch_fixed=True)
    q, r = np.diag(1.0 / vpp.STATE_SCALE**2), np.eye(4) / 1000.0**2
    try:
        k, x, _ = ct.lqr(model.A, model.B, q, r)
    except (ValueError, np.linalg.LinAlgError, ArithmeticError, ct.ControlArgument):
        return  # this slycot refuses too: nothing silent to show
    k, x = np.asarray(k), np.asarray(x)
    residual = model.A.T @ x + x @ model.A - x @ model.B @ k + q
    assert np.linalg.norm(residual) / np.linalg.norm(q) > 1.0 or np.max(np.linalg.eigvals(model.A - model.B @ k).real) >= 0
    with pytest.raises(ValueError, match="^stabilisability"):
        design_lqr((model.A, model.B), q, r)


@pytest.mark.parametrize(("which", "value"), [("plant A", 1e300), ("plant B", 1e300), ("plant B", 1e-310)])
def test_plants_in_the_control_rooms_scale(which: str, value: float) -> None:
    """Issue 27 (the hostile harness): B = 1e300 overflowed X B K in the Riccati residual (a
    RuntimeWarning, no named refusal). A plant is held to the rule systems are
    (``realisation.MIN_ENTRY``, ``MAX_ENTRY``), naming the matrix."""
    plant = {"plant A": -np.eye(1), "plant B": np.eye(1)}
    plant[which] = np.array([[value]])
    with pytest.raises(ValueError, match=rf"^{which}'s largest entry must be 0 or lie in \[1e-50, 1e\+50\]"):
        design_lqr((plant["plant A"], plant["plant B"]), np.eye(1), np.eye(1))


def test_the_allocated_lqr_takes_an_allocator_with_its_own_solver_settings() -> None:
    """The design reads the allocator's pseudo-inverse map (which reads no solver setting): an
    allocator made with non-default settings designs the same gain as a default one (the rule
    that refuses a setting a method does not read is for a user's ``method="pinv"``, not this)."""
    sim = rf.Simulator(rf.Airframe.preset("quad-x"))
    default = rf.lqr_hover_allocated(sim, rf.Allocator(sim.airframe))
    for settings in ({"max_iterations": 50}, {"tolerance": 1e-8}, {"clarabel_tolerance": 1e-9}):
        law = rf.lqr_hover_allocated(sim, rf.Allocator(sim.airframe, **settings))  # type: ignore[arg-type]
        np.testing.assert_array_equal(law.law.gain, default.law.gain)
    with pytest.raises(ValueError, match='^max_iterations: method="pinv" does not iterate'):
        rf.Allocator(sim.airframe, max_iterations=50).allocate(np.zeros(4), method="pinv")

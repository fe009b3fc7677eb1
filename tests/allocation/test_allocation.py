"""Constrained control allocation: Ke's limit cases (eqs. (34)/(35)), Lanzon's failed-rotor map
(eqs. (6)-(10)), attainable-set queries against scipy's LP, the Clarabel Python package as a third
independent solver, closed-loop flight through the allocator, and bad input.

The 10,000-problem comparison with Clarabel's Rust path and the KKT checks live in
``crates/rfcore/tests/allocation.rs``."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from scipy.optimize import linprog  # type: ignore[import-untyped]

import rotorfault as rf
from rotorfault.allocation import Allocator

KE_WEIGHTS = [1.0, 20.0, 20.0, 0.01]  # Ke Table IV ordering: w_p = w_q >> w_f >> w_r


@pytest.fixture(scope="module")
def ke() -> rf.Airframe:
    return rf.Airframe.preset("ke-quadcopter")


def test_eq34_equal_weights_give_the_moore_penrose_inverse(ke: rf.Airframe) -> None:
    m = ke.effectiveness_matrix()
    u_c = np.array([7.0, 0.05, -0.08, 0.01])
    expected = np.linalg.pinv(m) @ u_c
    assert np.all((expected > 0) & (expected < 8.5)), "no bound active"
    for method in ("active-set", "pinv", "clarabel"):
        for w in (1.0, 37.0):
            got = rf.allocate(ke, u_c, weights=[w] * 4, method=method)
            # Clarabel is an interior-point reference: T to 1e-6 (the bar), not exact.
            tol = 1e-12 if method != "clarabel" else 1e-6
            np.testing.assert_allclose(got.commands, expected, rtol=0, atol=tol, err_msg=method)
            assert got.attained or method == "clarabel"


def test_eq35_zero_yaw_weight_gives_the_pseudo_inverse_of_e1_m(ke: rf.Airframe) -> None:
    m = ke.effectiveness_matrix()
    u_c = np.array([7.0, 0.05, -0.08, 0.3])  # the yaw demand is dropped with w_r = 0
    expected = np.linalg.pinv(m[:3]) @ u_c[:3]
    for method in ("active-set", "pinv"):
        got = rf.allocate(ke, u_c, weights=[1.0, 20.0, 20.0, 0.0], method=method)
        np.testing.assert_allclose(got.commands, expected, rtol=0, atol=1e-12, err_msg=method)
        np.testing.assert_allclose(got.achieved[:3], u_c[:3], rtol=0, atol=1e-12)
    # give_up_yaw drops the row instead of weighting it to zero: the same answer.
    dropped = rf.allocate(ke, u_c[:3], weights=[1.0, 20.0, 20.0], give_up_yaw=True)
    np.testing.assert_allclose(dropped.commands, expected, rtol=0, atol=1e-12)


def test_ke_weights_sacrifice_yaw_when_the_rotors_saturate(ke: rf.Airframe) -> None:
    u_c = np.array([7.0, 0.05, -0.08, 0.5])  # far more yaw than four 8.5 N rotors give
    got = rf.allocate(ke, u_c, weights=KE_WEIGHTS)
    assert not got.attained
    np.testing.assert_allclose(got.achieved[:3], u_c[:3], rtol=0, atol=2e-4)
    assert got.achieved[3] < u_c[3]
    assert np.all(got.commands >= 0) and np.all(got.commands <= 8.5)


# --- Lanzon et al. eqs. (6)-(11): rotor 2 lost, inputs (u_f, tau_q, tau_r) --------------------

def lanzon_map(l: float, d: float) -> np.ndarray:
    """Eq. (6): [u_f, tau_q, tau_r] = A [f1, f3, f4] (Lanzon's z-up body frame)."""
    return np.array([[1.0, 1.0, 1.0], [-l, l, 0.0], [d, d, -d]])


def lanzon_inverse(l: float, d: float) -> np.ndarray:
    """Eq. (9), as printed."""
    return 0.25 * np.array([[1.0, -2.0 / l, 1.0 / d], [1.0, 2.0 / l, 1.0 / d], [2.0, 0.0, -2.0 / d]])


@pytest.fixture(scope="module")
def lanzon() -> rf.Airframe:
    return rf.Airframe.preset("lanzon-quadrotor")


def test_lanzon_eq6_and_eq9_are_inverses_and_match_the_preset(lanzon: rf.Airframe) -> None:
    l, d = float(lanzon.arm_length_m[0]), lanzon.drag_torque_ratio_m
    a, a_inv = lanzon_map(l, d), lanzon_inverse(l, d)
    np.testing.assert_allclose(a @ a_inv, np.eye(3), rtol=0, atol=1e-12)
    np.testing.assert_allclose(a_inv @ a, np.eye(3), rtol=0, atol=1e-12)
    # The preset (FRD) with rows thrust, pitch, yaw and rotors 1, 3, 4 is eq. (6) with the pitch
    # and yaw axes flipped (z-up -> z-down).
    frd = lanzon.effectiveness_matrix()[np.ix_([0, 2, 3], [0, 2, 3])]
    np.testing.assert_allclose(np.diag([1.0, -1.0, -1.0]) @ frd, a, rtol=0, atol=1e-15)


def test_lanzon_allocation_of_the_three_remaining_rotors_is_eq9(lanzon: rf.Airframe) -> None:
    """The generic allocator, given the failed airframe's (u_f, tau_q, tau_r) rows, reproduces
    eq. (9) exactly wherever the thrusts are inside their bounds; rotor 2 gets zero."""
    l, d, f_max = float(lanzon.arm_length_m[0]), lanzon.drag_torque_ratio_m, 5.0
    failed = lanzon.with_failed_rotors([2])
    flip = np.diag([1.0, -1.0, -1.0])  # Lanzon's frame -> FRD rows
    matrix = failed.effectiveness_matrix()[[0, 2, 3]]
    rng = np.random.default_rng(6)
    f = rng.uniform(0.05, f_max - 0.05, size=(500, 3))
    u = f @ lanzon_map(l, d).T
    expected = u @ lanzon_inverse(l, d).T
    # Weights that put thrust, pitch and yaw on one scale (1/l^2, 1/d^2): exact to rounding.
    normalised = Allocator(matrix, weights=[1.0, l**-2, d**-2], bounds=(0.0, f_max)).allocate(u @ flip)
    np.testing.assert_allclose(normalised.commands[:, [0, 2, 3]], expected, rtol=0, atol=1e-12)
    # Unit weights: the yaw row is d = 2.4e-3 times the thrust row, so H = M^T M has condition
    # number ~1e6 and the normal equations lose six digits: 1e-9 relative.
    unit = Allocator(matrix, bounds=(0.0, f_max)).allocate(u @ flip)
    np.testing.assert_allclose(unit.commands[:, [0, 2, 3]], expected, rtol=1e-9, atol=0)
    for got in (normalised, unit):
        np.testing.assert_allclose(got.commands[:, 1], 0.0, atol=0)
        assert all(s == "optimal" for s in got.status)


def test_lanzon_constraints_8_and_10_hold_exactly_inside_the_bounds(lanzon: rf.Airframe) -> None:
    l, d, f_max = float(lanzon.arm_length_m[0]), lanzon.drag_torque_ratio_m, 5.0
    a, a_inv = lanzon_map(l, d), lanzon_inverse(l, d)
    rng = np.random.default_rng(8)
    u_f, tau_q, tau_r = (rng.uniform(-1, 1, 20_000) * s for s in (3 * f_max, l * f_max, d * 3 * f_max))
    u = np.column_stack([u_f, tau_q, tau_r])
    eq8 = (np.abs(tau_q) <= l / 2 * (u_f + tau_r / d)) & (np.abs(tau_r) <= d * u_f)
    eq10 = (
        (u_f - 2 * tau_q / l + tau_r / d >= 0) & (u_f + 2 * tau_q / l + tau_r / d >= 0) & (2 * u_f - 2 * tau_r / d >= 0)
    )
    f = u @ a_inv.T
    nonnegative = np.all(f >= 0, axis=1)
    # (8) <=> (10) <=> eq. (9) gives f >= 0; both sides of the equivalence occur in the sample.
    np.testing.assert_array_equal(eq8, eq10)
    np.testing.assert_array_equal(eq8, nonnegative)
    assert 0.1 < eq8.mean() < 0.9
    # Thrusts inside [0, f_max] map to inputs satisfying (8) and u_f <= 3 f_max (the text after (10)).
    inside = rng.uniform(0, f_max, size=(5000, 3)) @ a.T
    assert np.all(np.abs(inside[:, 1]) <= l / 2 * (inside[:, 0] + inside[:, 2] / d) + 1e-12)
    assert np.all(np.abs(inside[:, 2]) <= d * inside[:, 0] + 1e-12)
    assert np.all(inside[:, 0] <= 3 * f_max + 1e-12)
    # The allocator attains exactly the inputs whose eq. (9) thrusts are within bounds.
    allocator = Allocator(a, bounds=(0.0, f_max))
    got = allocator.allocate(u)
    within = np.all((f >= 0) & (f <= f_max), axis=1)
    np.testing.assert_array_equal(got.attained, within)


def test_lanzon_rate_constraint_11_is_the_inverse_map_of_the_rate_limit(lanzon: rf.Airframe) -> None:
    """Eq. (11): |d/dt f_j| <= Delta f in terms of the input rates, i.e. eq. (9) applied to rates."""
    l, d = float(lanzon.arm_length_m[0]), lanzon.drag_torque_ratio_m
    rates = np.random.default_rng(3).normal(size=(100, 3)) * [10.0, 0.5, 0.05]
    printed = np.column_stack(
        [
            rates[:, 0] / 4 - rates[:, 1] / (2 * l) + rates[:, 2] / (4 * d),
            rates[:, 0] / 4 + rates[:, 1] / (2 * l) + rates[:, 2] / (4 * d),
            rates[:, 0] / 2 - rates[:, 2] / (2 * d),
        ]
    )
    np.testing.assert_allclose(printed, rates @ lanzon_inverse(l, d).T, rtol=1e-13, atol=1e-12)


# --- attainable set -------------------------------------------------------------------------

def lp_max_along(m: np.ndarray, lower: np.ndarray, upper: np.ndarray, d: np.ndarray, base: np.ndarray) -> float:
    n, k = m.shape
    res = linprog(
        c=np.r_[np.zeros(k), -1.0],
        A_eq=np.c_[m, -d],
        b_eq=base,
        bounds=[(lo, hi) for lo, hi in zip(lower, upper)] + [(None, None)],
        method="highs",
    )
    assert res.status == 0
    return float(res.x[-1])


@pytest.mark.parametrize("name", ["quad-x", "hexa-pnpnpn", "hexa-ppnnpn", "octo-x"])
def test_max_virtual_control_matches_scipy_linprog(name: str) -> None:
    frame = rf.Airframe.preset(name)
    m = frame.effectiveness_matrix()
    rng = np.random.default_rng(len(name))
    for _ in range(10):
        d = rng.normal(size=4)
        got = rf.max_virtual_control(frame, d, base=frame.hover_wrench if hasattr(frame, "hover_wrench") else None)
        base = np.zeros(4)
        got = rf.max_virtual_control(frame, d)
        assert got is not None
        expected = lp_max_along(m, frame.min_thrust_n, frame.max_thrust_n, d, base)
        assert got.scale == pytest.approx(expected, rel=1e-8, abs=1e-9)
        np.testing.assert_allclose(m @ got.commands, got.scale * d, rtol=0, atol=1e-7 * np.abs(d).max() * got.scale + 1e-9)


def test_hover_thrust_margin_analytic_cases(ke: rf.Airframe) -> None:
    weight = ke.mass_kg * ke.gravity_m_s2
    healthy = rf.hover_thrust_margin(ke)
    assert healthy.max_thrust_n == pytest.approx(4 * 8.5, rel=1e-9)
    assert healthy.margin_n == pytest.approx(4 * 8.5 - weight, rel=1e-9)
    assert healthy.thrust_to_weight == pytest.approx(34 / weight, rel=1e-9)
    # One rotor lost: with yaw held at zero only zero thrust balances (the remaining diagonal pair
    # spins the same way; the third rotor must then be off too) ...
    failed = rf.hover_thrust_margin(ke, efficiency=[1, 1, 0, 1])
    assert failed.max_thrust_n == pytest.approx(0.0, abs=1e-7)
    assert failed.margin_n < 0
    # ... and with yaw given up (a spinning vehicle), the opposite pair at full thrust.
    spinning = rf.hover_thrust_margin(ke, efficiency=[1, 1, 0, 1], give_up_yaw=True)
    assert spinning.max_thrust_n == pytest.approx(2 * 8.5, rel=1e-9)


@pytest.mark.parametrize("name", ["hexa-pnpnpn", "hexa-ppnnpn"])
def test_hover_thrust_margin_matches_linprog_for_every_single_failure(name: str) -> None:
    frame = rf.Airframe.preset(name)
    for rotor in range(frame.rotor_count):
        health = np.ones(frame.rotor_count)
        health[rotor] = 0.0
        got = rf.hover_thrust_margin(frame, efficiency=health)
        m = frame.with_efficiency(health).effectiveness_matrix()
        expected = lp_max_along(m, frame.min_thrust_n, frame.max_thrust_n, np.array([1.0, 0, 0, 0]), np.zeros(4))
        assert got.max_thrust_n == pytest.approx(expected, rel=1e-8, abs=1e-8)
        # Du's ACAI sign and the hover margin agree on whether the failed vehicle can hover.
        if rf.acai(frame.with_efficiency(health), formula="facet-margin") > 1e-9:
            assert got.margin_n > 0


# --- the Clarabel Python package: a third, independent solver --------------------------------

def test_active_set_matches_the_clarabel_python_package() -> None:
    import clarabel  # type: ignore[import-untyped]  # a test dependency (pyproject [test])
    from scipy import sparse  # type: ignore[import-untyped]

    rng = np.random.default_rng(33)
    for trial in range(200):
        n, m = 4, int(rng.integers(4, 9))
        matrix = rng.uniform(-1, 1, size=(n, m))
        weights = 10 ** rng.uniform(-2, 2, size=n)
        lower = rng.uniform(-2, 1, size=m)
        upper = lower + rng.uniform(0.1, 5, size=m)
        u_c = 3 * matrix @ rng.uniform(lower, upper) + rng.uniform(-2, 2, size=n)
        allocator = Allocator(matrix, weights=weights, bounds=(lower, upper))
        exact = allocator.allocate(u_c)
        h = matrix.T @ np.diag(weights) @ matrix
        q = -matrix.T @ (weights * u_c)
        a = sparse.csc_matrix(np.vstack([np.eye(m), -np.eye(m)]))
        settings = clarabel.DefaultSettings()
        settings.verbose = False
        settings.tol_gap_abs = settings.tol_gap_rel = settings.tol_feas = 1e-10
        solver = clarabel.DefaultSolver(
            sparse.csc_matrix(np.triu(h)), q, a, np.r_[upper, -lower], [clarabel.NonnegativeConeT(2 * m)], settings
        )
        solution = solver.solve()
        reference = np.clip(np.array(solution.x), lower, upper)
        f_exact, kkt = allocator.objective(u_c, exact.commands)
        f_ref, _ = allocator.objective(u_c, reference)
        scale = max(f_ref, 0.5 * float(u_c @ (weights * u_c)))
        assert f_exact <= f_ref + 1e-12 * scale, trial
        assert f_ref - f_exact <= 1e-9 * scale, trial
        assert kkt <= 1e-9 * np.abs(np.r_[lower, upper]).max(), trial


# --- invariants (hypothesis lives in test_properties; these are exact identities) -------------

def test_renumbering_rotors_renumbers_the_commands() -> None:
    frame = rf.Airframe.preset("hexa-ppnnpn")
    u_c = np.array([[14.0, 0.3, -0.2, 0.05], [40.0, 2.0, 1.0, 0.3]])
    base = rf.allocate(frame, u_c, weights=KE_WEIGHTS)
    for perm in itertools.islice(itertools.permutations(range(6)), 0, 720, 97):
        p = list(perm)
        allocator = Allocator(
            frame.effectiveness_matrix()[:, p], weights=KE_WEIGHTS, bounds=(frame.min_thrust_n[p], frame.max_thrust_n[p])
        )
        got = allocator.allocate(u_c)
        np.testing.assert_allclose(got.commands, base.commands[:, p], rtol=0, atol=1e-11)


def test_unit_scaling_scales_the_commands() -> None:
    frame = rf.Airframe.preset("octo-x")
    u_c = np.array([[30.0, 1.0, -0.5, 0.2], [5.0, 0.1, 0.1, 0.0]])
    base = rf.allocate(frame, u_c, weights=KE_WEIGHTS)
    for k in (1e-3, 7.0, 1e3):
        scaled = rf.allocate(
            frame.effectiveness_matrix(), k * u_c, weights=KE_WEIGHTS, bounds=(k * frame.min_thrust_n, k * frame.max_thrust_n)
        )
        np.testing.assert_allclose(scaled.commands, k * base.commands, rtol=1e-10, atol=1e-12 * k)
        # Weights scaled together change nothing.
        same = rf.allocate(frame, u_c, weights=np.array(KE_WEIGHTS) * k)
        np.testing.assert_allclose(same.commands, base.commands, rtol=0, atol=1e-10)


def test_prioritised_allocation_meets_the_first_group_then_the_second(ke: rf.Airframe) -> None:
    u_c = np.array([7.0, 0.1, 0.0, 0.5])
    got = rf.allocate(ke, u_c, method="clarabel", priorities=[[0, 1, 2], [3]])
    np.testing.assert_allclose(got.achieved[:3], u_c[:3], rtol=0, atol=1e-7)
    # Yaw gets the most the rotors can give with thrust and roll/pitch held: an LP bound.
    limit = rf.max_virtual_control(ke, [0, 0, 0, 1.0], base=np.r_[u_c[:3], 0.0])
    assert limit is not None
    assert got.achieved[3] == pytest.approx(limit.scale, rel=1e-6)


# --- closed loop ----------------------------------------------------------------------------

def test_known_rotor_failure_flown_through_the_allocator() -> None:
    """A hexacopter that lost rotor 1 (controllable, Du Table III) hovers with LQR on the virtual
    control and the allocator that knows the failure; position error decays from 1 m."""
    frame = rf.Airframe.preset("hexa-ppnnpn").with_failed_rotors([1])
    sim = rf.Simulator(frame)
    controller = rf.lqr_hover_allocated(sim, Allocator(frame), position=(0, 0, -10))
    tr = sim.run(rf.State(position=(1.0, -0.5, -10.5)), 15.0, controller=controller)
    assert not tr.diverged
    assert np.abs(tr.position[-1] - [0, 0, -10]).max() < 1e-3
    assert np.all(tr.rotor_command[:, 0] == 0.0), "the failed rotor is never used"
    assert np.all(tr.rotor_command >= 0) and np.all(tr.rotor_command <= frame.max_thrust_n + 1e-12)


def test_allocated_controller_is_validated() -> None:
    frame = rf.Airframe.preset("quad-x")
    law = rf.LinearFeedback(np.zeros((3, 12)), np.zeros(12), np.zeros(3))
    with pytest.raises(ValueError, match="law"):
        rf.Allocated(law, Allocator(frame))
    with pytest.raises(TypeError, match="allocator"):
        rf.Allocated(rf.LinearFeedback(np.zeros((4, 12)), np.zeros(12), np.zeros(4)), frame)


# --- bad input ------------------------------------------------------------------------------

@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"weights": [1.0, -1.0, 1.0, 1.0]}, "weights\\[1\\]"),
        ({"weights": [1.0, np.nan, 1.0, 1.0]}, "weights\\[1\\]"),
        ({"weights": [1.0, 1.0]}, "weights"),
        ({"bounds": (2.0, 1.0)}, "lower\\[0\\]"),
        ({"bounds": ([0, 0, 0, np.inf], 1.0)}, "lower\\[3\\]"),
        ({"bounds": ([0, 0, 0], 1.0)}, "lower"),
        ({"regularization": -1.0}, "regularization"),
        ({"preferred": [0.0, 0.0]}, "preferred"),
        ({"method": "simplex"}, "method"),
    ],
)
def test_bad_input_is_a_value_error_naming_the_field(ke: rf.Airframe, kwargs: dict, field: str) -> None:
    with pytest.raises(ValueError, match=f"^{field}"):
        rf.allocate(ke, [7.0, 0, 0, 0], **kwargs)


def test_bad_virtual_controls_and_matrices(ke: rf.Airframe) -> None:
    with pytest.raises(ValueError, match=r"^virtual_control\[1, 2\]"):
        rf.allocate(ke, [[7.0, 0, 0, 0], [7.0, 0, np.nan, 0]])
    with pytest.raises(ValueError, match="^virtual_control"):
        rf.allocate(ke, [7.0, 0, 0])
    with pytest.raises(ValueError, match="^virtual_control"):
        rf.allocate(ke, np.zeros((2, 2, 4)))
    with pytest.raises(TypeError, match="^virtual_control"):
        rf.allocate(ke, "7 0 0 0")
    with pytest.raises(ValueError, match=r"^matrix\[0, 1\]"):
        rf.allocate([[1.0, np.inf]], [1.0], bounds=(0, 1))
    with pytest.raises(ValueError, match="^bounds"):
        rf.allocate([[1.0, 1.0]], [1.0])
    with pytest.raises(ValueError, match="^priorities"):
        rf.allocate(ke, [7.0, 0, 0, 0], method="clarabel", priorities=[[0, 1], [1]])
    with pytest.raises(ValueError, match="^priorities"):
        rf.allocate(ke, [7.0, 0, 0, 0], method="active-set", priorities=[[0]])
    with pytest.raises(ValueError, match="^direction"):
        rf.max_virtual_control(ke, [0, 0, 0, 0])


def test_inputs_are_not_mutated(ke: rf.Airframe) -> None:
    u_c = np.array([[40.0, 1.0, 0, 0.3]])
    weights = np.array(KE_WEIGHTS)
    lower, upper = np.zeros(4), np.full(4, 8.5)
    copies = [a.copy() for a in (u_c, weights, lower, upper)]
    allocator = Allocator(ke, weights=weights, bounds=(lower, upper))
    allocator.allocate(u_c)
    for a, b in zip((u_c, weights, lower, upper), copies):
        np.testing.assert_array_equal(a, b)
    with pytest.raises(ValueError):
        allocator.matrix[0, 0] = 2.0


def test_attainable_slice_shrinks_with_a_failure_and_vanishes_when_hover_is_lost() -> None:
    from rotorfault.allocation import attainable_slice, plot_attainable_slices

    frame = rf.Airframe.preset("hexa-ppnnpn")
    healthy = attainable_slice(frame, directions=36)
    assert healthy is not None
    for rotor in range(6):
        health = np.ones(6)
        health[rotor] = 0.0
        failed = attainable_slice(frame, efficiency=health, directions=36)
        margin = rf.hover_thrust_margin(frame, efficiency=health).margin_n
        # Du Table III: rotors 5 and 6 leave PPNNPN unable to hover with zero torque.
        assert (failed is None) == (rotor in (4, 5)) == (margin < 0)
        if failed is not None:
            # Same directions, so compare radii: the failed set lies inside the healthy one.
            assert np.all(np.linalg.norm(failed, axis=1) <= np.linalg.norm(healthy, axis=1) + 1e-7)
    fig = plot_attainable_slices(frame)
    labels = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert "rotor 5 failed: hover unattainable" in labels and "healthy" in labels
    import matplotlib.pyplot as plt

    plt.close(fig)
    with pytest.raises(ValueError, match="^axes"):
        attainable_slice(frame, axes=(1, 1))
    with pytest.raises(ValueError, match="^axes"):
        attainable_slice(frame, axes=(1, 3), give_up_yaw=True)


# --- regressions from the review of the first version ---------------------------------------


def test_warm_started_controller_gives_the_cold_answer() -> None:
    """A rotor held at a bound with a zero multiplier used to stay there under warm starts."""
    frame = rf.Airframe.preset("hexa-ppnnpn").with_failed_rotors([1])
    allocator = Allocator(frame)
    hover = [frame.hover_thrust_n, 0, 0, 0]
    law = rf.OpenLoop([0, 0.01], [[15.04, 1.96, 1.42, -1.06], hover])
    tr = rf.Simulator(frame).run(rf.State(position=(0, 0, -10)), 0.02, controller=rf.Allocated(law, allocator))
    np.testing.assert_allclose(tr.rotor_command[-1], allocator.allocate(hover).commands, atol=1e-12)


def test_allocated_accepts_a_discrete_lti() -> None:
    quad = rf.Airframe.preset("quad-x")
    law = rf.Lti(np.zeros((1, 1)), np.zeros((1, 12)), np.zeros((4, 1)), np.zeros((4, 12)), np.zeros(12), [quad.hover_thrust_n, 0, 0, 0], dt_s=1 / 400)
    tr = rf.Simulator(quad).run(rf.State(position=(0, 0, -10)), 0.1, controller=rf.Allocated(law, Allocator(quad)))
    np.testing.assert_allclose(tr.rotor_command[-1], quad.hover_thrust_n / 4, rtol=1e-12)


def test_lqr_hover_allocated_rejects_what_it_cannot_design_for() -> None:
    quad = rf.Airframe.preset("quad-x")
    sim = rf.Simulator(quad)
    with pytest.raises(ValueError, match="^allocator:"):
        rf.lqr_hover_allocated(sim, Allocator(quad, give_up_yaw=True))
    with pytest.raises(ValueError, match="^allocator.weights"):
        rf.lqr_hover_allocated(sim, Allocator(quad, weights=[1, 1, 1, 0]))
    with pytest.raises(ValueError, match="^allocator.regularization"):
        rf.lqr_hover_allocated(sim, Allocator(quad, regularization=0.1))


def test_prioritised_allocation_survives_pinned_commands() -> None:
    quad = rf.Airframe.preset("quad-x")
    got = Allocator(quad).allocate([25.69185773, -0.36281204, 1.31643175, -1.44105278], method="clarabel", priorities=[[0], [1, 2], [3]])
    assert got.status == "optimal"


def test_objective_and_attainable_set_edge_cases(ke: rf.Airframe) -> None:
    from rotorfault.allocation import attainable_slice

    with pytest.raises(ValueError, match=r"^commands\[0\]"):
        Allocator(ke).objective([7, 0, 0, 0], [np.nan, 1, 1, 1])
    quad = rf.Airframe.preset("quad-x")
    # Half a rotor lost: hover with zero torque is out of reach, so no slice through it.
    assert rf.hover_thrust_margin(quad, efficiency=[0.5, 1, 1, 1]).margin_n < 0
    assert attainable_slice(quad, axes=(0, 1), efficiency=[0.5, 1, 1, 1]) is None
    assert attainable_slice(quad, axes=(np.int64(1), 2), directions=np.int64(8)) is not None
    behind = rf.max_virtual_control(ke, [1, 0, 0, 0], base=[-1, 0, 0, 0])
    assert behind is not None and behind.scale == pytest.approx(35.0, rel=1e-8)


def test_more_bad_input(ke: rf.Airframe) -> None:
    with pytest.raises(ValueError, match="^virtual_control"):
        rf.allocate(ke, [])
    with pytest.raises(TypeError, match="^bounds"):
        rf.allocate([[1.0, 1.0]], [1.0], bounds={0: 1, 1: 2})
    with pytest.raises(ValueError, match="^priorities"):
        rf.allocate(ke, [7.0, 0, 0, 0], method="clarabel", priorities=[[2**70]])


def test_rate_limit_folds_into_the_bounds(ke: rf.Airframe) -> None:
    """Lanzon's rate limit (11): each thrust within 50 N/s x 2.5 ms of the previous command."""
    allocator = Allocator(ke, weights=KE_WEIGHTS)
    previous = np.array([1.0, 8.5, 0.05, 4.0])
    limited = allocator.rate_limited(previous, 50.0 * 0.0025)
    np.testing.assert_allclose(limited.lower, [0.875, 8.375, 0.0, 3.875], atol=1e-15)
    np.testing.assert_allclose(limited.upper, [1.125, 8.5, 0.175, 4.125], atol=1e-15)
    got = limited.allocate([30.0, 1.0, 0.0, 0.0])
    assert np.all(np.abs(got.commands - previous) <= 0.125 + 1e-12)
    with pytest.raises(ValueError, match=r"^max_change\[0\]"):
        allocator.rate_limited(previous, [-1.0, 0, 0, 0])


def test_a_setting_the_method_does_not_read_is_refused_not_dropped() -> None:
    """``tolerance=1e-3`` with ``method="clarabel"`` or ``"pinv"`` returned a certificate held to
    1e-9 (those methods certify at DEFAULT_TOLERANCE), and ``"pinv"`` dropped ``max_iterations``
    and ``clarabel_tolerance``: each is refused, naming it; what a method reads still works, and
    the defaults given explicitly are no loss."""
    quad = rf.Airframe.preset("quad-x")
    u = [15.0, 0.1, 0.0, 0.0]
    for method in ("clarabel", "pinv"):
        with pytest.raises(ValueError, match=f"^tolerance: method='{method}' holds its certificate to DEFAULT_TOLERANCE"):
            rf.allocate(quad, u, method=method, tolerance=1e-3)
    with pytest.raises(ValueError, match="^tolerance: method='clarabel'"):
        rf.allocate(quad, u, method="clarabel", priorities=[[0, 1, 2], [3]], tolerance=1e-3)
    with pytest.raises(ValueError, match='^max_iterations: method="pinv" does not iterate, got 5'):
        rf.allocate(quad, u, method="pinv", max_iterations=5)
    with pytest.raises(ValueError, match='^clarabel_tolerance: method="pinv" does not call Clarabel'):
        rf.Allocator(quad, clarabel_tolerance=1e-6).allocate(u, method="pinv")
    assert rf.allocate(quad, u, tolerance=1e-3).certificate.tolerance == 1e-3
    assert rf.allocate(quad, u, method="clarabel", max_iterations=50, clarabel_tolerance=1e-8).status == "optimal"
    assert rf.allocate(quad, u, method="pinv", tolerance=rf.allocation.DEFAULT_TOLERANCE).status == "unconstrained"

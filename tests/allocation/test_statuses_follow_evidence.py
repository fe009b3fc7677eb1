"""Statuses agree with their evidence (issue 27): an allocation is ``optimal`` exactly when its
certificate holds (prioritised allocation too, whose certificate is every stage's KKT conditions);
the tie rule (the optimum closest to the preferred command) holds on every tie, checked against a
second QP; a trim is ``balanced`` by its residual.

The second solver is Clarabel's Python package (independent of the crate the core links):
stage by stage the optimum given what the earlier stages achieved, and for ties
``min |T - T_pref|^2`` over ``{box, M_w T = M_w T*}``."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

import rotorfault as rf

clarabel = pytest.importorskip("clarabel")
sparse = pytest.importorskip("scipy.sparse")

#: How close the second QP's answer must be (commands are O(1-10) N; the interior-point answer of
#: a degenerate tie is accurate to about 1e-5 N, measured: 5.9e-6 where a rotor sits on a bound).
COMMAND_ATOL = 1e-4


def qp(p: np.ndarray[Any, Any], q: np.ndarray[Any, Any], a_eq: np.ndarray[Any, Any], b_eq: np.ndarray[Any, Any],
       lo: np.ndarray[Any, Any], hi: np.ndarray[Any, Any]) -> np.ndarray[Any, Any]:
    m = len(q)
    a = np.vstack([a_eq, np.eye(m), -np.eye(m)])
    cones = ([clarabel.ZeroConeT(len(b_eq))] if len(b_eq) else []) + [clarabel.NonnegativeConeT(2 * m)]
    settings = clarabel.DefaultSettings()
    settings.verbose = False
    settings.tol_gap_abs = settings.tol_gap_rel = settings.tol_feas = 1e-12
    solution = clarabel.DefaultSolver(sparse.csc_matrix(p), q, sparse.csc_matrix(a), np.concatenate([b_eq, hi, -lo]), cones, settings).solve()
    assert str(solution.status) in ("Solved", "AlmostSolved"), solution.status
    return np.array(solution.x)


def closest_optimum(matrix: np.ndarray[Any, Any], weights: np.ndarray[Any, Any], lo: np.ndarray[Any, Any], hi: np.ndarray[Any, Any],
                    achieved: np.ndarray[Any, Any], preferred: np.ndarray[Any, Any]) -> np.ndarray[Any, Any]:
    rows = weights > 0
    m = matrix.shape[1]
    return qp(np.eye(m), -preferred, matrix[rows], achieved[rows], lo, hi)


def clean(matrix: np.ndarray[Any, Any]) -> np.ndarray[Any, Any]:
    """The effectiveness matrix without the rounding of sin(pi) (1e-17): on the stored matrix
    such an entry is a real, if tiny, lever the exact solver uses and the second QP cannot see."""
    return np.where(np.abs(matrix) < 1e-12 * np.abs(matrix).max(), 0.0, matrix)


def tie_problems(count: int, seed: int) -> list[dict[str, Any]]:
    """Problems with ties: more rotors than weighted axes (give up yaw, zero weights, a failed
    rotor), attainable points with rotors on their bounds and points beyond, preferred commands."""
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(count):
        frame = rf.Airframe.preset(str(rng.choice(["quad-x", "hexa-pnpnpn", "hexa-ppnnpn", "octo-x", "quad-plus"])))
        m = frame.rotor_count
        eta = np.ones(m)
        if rng.random() < 0.4:
            eta[rng.integers(m)] = rng.choice([0.0, rng.uniform(0.2, 0.9)])
        frame = frame.with_efficiency(eta)
        rows = 3 if rng.random() < 0.4 else 4
        matrix = clean(frame.effectiveness_matrix()[:rows])
        weights = np.ones(rows) if rng.random() < 0.5 else rng.choice([0.0, 0.01, 1.0, 20.0], size=rows)
        if weights.max() == 0:
            weights[0] = 1.0
        point = rng.uniform(0, 1, m) * frame.max_thrust_n
        held = rng.choice(m, rng.integers(0, m), replace=False)
        point[held] = frame.max_thrust_n[held] * rng.choice([0.0, 1.0], size=held.size)
        u = matrix @ point + (rng.normal(0, 0.3, rows) if rng.random() < 0.3 else 0.0)
        preferred = rng.uniform(-2, 10, m) if rng.random() < 0.7 else np.zeros(m)
        if np.linalg.matrix_rank(matrix[weights > 0]) < m:  # a tie: several optima
            out.append(dict(matrix=matrix, weights=weights, lo=frame.min_thrust_n, hi=frame.max_thrust_n, u=u, preferred=preferred))
    return out


def test_the_tie_rule_holds_on_every_tie() -> None:
    problems = tie_problems(1100, seed=27)
    assert len(problems) >= 900
    worst = 0.0
    for k, p in enumerate(problems):
        result = rf.Allocator(p["matrix"], weights=p["weights"], bounds=(p["lo"], p["hi"]), preferred=p["preferred"]).allocate(p["u"])
        assert result.status == "optimal" and result.certificate.holds, (k, result.status)
        best = closest_optimum(p["matrix"], p["weights"], p["lo"], p["hi"], p["matrix"] @ result.commands, p["preferred"])
        worst = max(worst, float(np.max(np.abs(best - result.commands))))
        # The closest optimum is unique: ours (exactly optimal, certified) may be no farther from
        # T_pref than the second QP's (accurate to its tolerance), and lies where it does.
        ours, theirs = (float(np.sum((x - p["preferred"]) ** 2)) for x in (result.commands, best))
        assert ours <= theirs + 1e-9 * (1.0 + theirs), (k, ours, theirs)
        np.testing.assert_allclose(result.commands, best, rtol=0, atol=COMMAND_ATOL, err_msg=f"problem {k}")
    print(f"{len(problems)} problems with ties: worst distance to the closest optimum {worst:.2e}")


def test_a_tie_that_needs_two_rotors_to_move_together() -> None:
    """Found by the issue's search (main: 2.7 N from the closest optimum, reported optimal): hexa
    PNPNPN giving up yaw, rotor 1 failed; phase 2 released one held rotor at a time, and no single
    rotor can move while keeping thrust, roll and pitch."""
    frame = rf.Airframe.preset("hexa-pnpnpn").with_efficiency([0, 1, 1, 1, 1, 1])
    matrix = clean(frame.effectiveness_matrix()[:3])
    u = np.array([16.55207545732465, 1.0245693246361938, 0.5915353753821393])
    preferred = np.array([8.352971900729408, 5.659595208750641, -0.6844426927422851, 3.7350635971687565, -1.9162150185609148, -0.5477585331111907])
    result = rf.Allocator(matrix, bounds=(0.0, 6.125), preferred=preferred).allocate(u)
    best = closest_optimum(matrix, np.ones(3), np.zeros(6), np.full(6, 6.125), u, preferred)
    np.testing.assert_allclose(result.commands, best, rtol=0, atol=COMMAND_ATOL)
    np.testing.assert_allclose(result.commands, [6.125, 5.213537728662, 0.0, 1.822924542675, 3.390613185987, 6.125], atol=1e-9)


def test_a_zero_virtual_control_with_a_preferred_command_certifies() -> None:
    """main: ``iteration-limit`` through the Clarabel fallback, commands 2e-4 off: the rounding of
    steps from T_pref looked like a failed optimum when u_c = 0."""
    frame = rf.Airframe.preset("quad-plus").with_efficiency([1, 1, 0, 1])
    result = rf.Allocator(frame, give_up_yaw=True, preferred=[7.77, 1.52, 7.34, 2.92]).allocate([0.0, 0.0, 0.0])
    assert result.status == "optimal" and result.solved_by == "active-set"
    np.testing.assert_allclose(result.commands, [0.0, 0.0, 6.125, 0.0], atol=1e-12)


def stage_values(matrix: np.ndarray[Any, Any], weights: np.ndarray[Any, Any], u: np.ndarray[Any, Any], groups: list[list[int]],
                 commands: np.ndarray[Any, Any]) -> list[float]:
    return [float(np.sum(weights[g] * (matrix[g] @ commands - u[g]) ** 2)) for g in groups]


def test_prioritised_allocation_is_optimal_exactly_when_certified_and_each_stage_is_optimal() -> None:
    """Each stage's value equals the second QP's optimum given what the earlier stages achieved
    (the lexicographic conditions, checked independently); status ``optimal`` iff the certificate
    holds; and nearly every answer certifies (main: 'optimal' with the one-stage certificate
    failing on 192 of 200 quad-x problems)."""
    rng = np.random.default_rng(5)
    certified = 0
    total = 0
    for name in ("quad-x", "hexa-pnpnpn", "octo-x", "hexa-ppnnpn"):
        frame = rf.Airframe.preset(name)
        matrix = clean(frame.effectiveness_matrix())
        lo, hi = frame.min_thrust_n, frame.max_thrust_n
        for _ in range(60):
            weights = rng.choice([0.01, 1.0, 20.0], size=4)
            groups = [[[0, 1, 2], [3]], [[0], [1, 2], [3]], [[3], [0, 1, 2]], [[0, 1], [2]]][rng.integers(4)]
            u = rng.uniform(-1, 1, 4) * np.array([hi.sum(), 3, 3, 1])
            u[0] = abs(u[0])
            preferred = rng.uniform(0, 6, frame.rotor_count) if rng.random() < 0.5 else None
            result = rf.Allocator(matrix, weights=weights, bounds=(lo, hi), preferred=preferred).allocate(u, method="clarabel", priorities=groups)
            total += 1
            assert (result.status == "optimal") == result.certificate.holds, (result.status, result.certificate)
            certified += result.certificate.holds
            if not result.certificate.holds:
                continue
            ours = stage_values(matrix, weights, u, groups, result.commands)
            for k, group in enumerate(groups):
                earlier = [r for g in groups[:k] for r in g]
                a = np.sqrt(weights[group])[:, None] * matrix[group]
                b = np.sqrt(weights[group]) * u[group]
                x = qp(a.T @ a, -a.T @ b, matrix[earlier], matrix[earlier] @ result.commands, lo, hi)
                best = float(np.sum((a @ x - b) ** 2))
                assert ours[k] <= best + 1e-9 * (1.0 + best), (name, groups, k, ours[k], best)
    assert certified >= 0.97 * total, f"{certified} of {total} certified"


def test_clarabel_statuses_follow_their_certificates() -> None:
    rng = np.random.default_rng(9)
    frame = rf.Airframe.preset("hexa-pnpnpn")
    for _ in range(100):
        u = rng.uniform(-1, 1, 4) * np.array([40, 3, 3, 1])
        for kwargs in ({}, {"priorities": [[0, 1, 2], [3]]}, {"priorities": [[0], [1, 2, 3]]}):
            result = rf.allocate(frame, u, method="clarabel", **kwargs)
            assert (result.status == "optimal") == result.certificate.holds, (kwargs, result.status, result.certificate)


def test_trims_are_balanced_by_their_residual() -> None:
    from rotorfault.control import lqr, vpp

    trim = lqr.hover_trim(rf.Simulator(rf.Airframe.preset("hexa-pnpnpn")))
    assert trim.balanced and trim.residual <= lqr.TRIM_RESIDUAL_TOL
    wang = vpp.preset()
    assert vpp.trim(wang).balanced
    # Sec. 3.4's layout with propeller 1 failed: yaw does not balance, and the result says so.
    unbalanced = vpp.fixed_pitch_trim(vpp.fixed_pitch(wang, "wang-standard-fixed-pitch"))
    assert unbalanced.balanced == (unbalanced.residual <= lqr.TRIM_RESIDUAL_TOL)

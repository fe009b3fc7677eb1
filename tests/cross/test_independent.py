"""Independent checks of the ACAI against computations that share no code with rotorfault.

The reference is the attainable set built from scratch: the 2^m images B f of the vertices of the
thrust box, their convex hull by ``scipy.spatial.ConvexHull`` (qhull), and, for hover
feasibility, ``scipy.optimize.linprog``. qhull returns facets as ``normal . x + offset <= 0``
with unit normals, so for a point G

    hull_margin(G) = min over facets of -(normal . G + offset)

is the distance from G to the boundary when G is inside, and minus the largest violation of a
facet inequality when G is outside.

What each test proves:

- ``test_inside_acai_equals_hull_distance``: on random full-rank airframes (4-8 rotors, random
  arm angles/lengths/spins/k_mu, boxes with zero, negative and positive f_min, efficiencies in
  [0.2, 1]) with G strictly inside, both formulas return the hull distance, with yaw (n = 4) and
  without (n = 3, rows 0..2), for >= 100 inside cases per dimension.
  ``test_rank_deficient_*``: rank B < n (e.g. four rotors spinning the same way) gives -inf.
- ``test_outside_facet_margin_equals_largest_hull_violation``: for G strictly outside (all
  efficiencies > 0), "facet-margin" = -(largest hull violation) and "eq13" lies in
  [-|facet-margin| - tol, 0].
- ``test_failed_rotors_inside_exact_outside_bracketed``: with some efficiencies exactly 0, inside
  values are still exact; outside, largest hull violation <= -facet-margin <= true distance
  (bounded least squares, ``scipy.optimize.lsq_linear``): facet-margin is a lower bound.
- ``test_acai_from_matrix_general_dimension``: random matrices with n = 1, 2, 3, 5 (the general-n
  path, n = 1 against the analytic interval) agree with the hull inside and outside.
- ``test_du_ppnnpn_*`` / ``test_du_pnpnpn_*``: Du et al. (JGCD 2015) Tables II and III. PPNNPN
  with rotor 5 or 6 failed: hover is infeasible (linprog), G is 0.2133 outside a facet
  (hull) = -facet-margin = the true distance (bounded least squares), while eq13 prints exactly
  0.0 like the paper. The positive Table III entries are hull distances. PNPNPN with any one
  rotor failed: hover is feasible but on the boundary; both formulas give exactly +0.0.
- ``test_batch_equals_single_calls``: ``acai_batch`` is bit-for-bit ``acai`` on hundreds of rows,
  including rows with failed rotors (eta = 0) and rank-deficient rows (-inf).

Tolerance: ``REL_TOL = 1e-9`` of the problem scale
``sum_k |b_k| (f_max_k - f_min_k) / 2 + |G|`` (b_k with efficiencies applied). This is the
library's own resolution (ZERO_RTOL: values within it are reported as 0.0), so it cannot promise
more; the observed agreement is ~1e-15 of the scale.
"""

from __future__ import annotations

import functools
import itertools
import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt
import pytest
from scipy.optimize import linprog, lsq_linear
from scipy.spatial import ConvexHull

import rotorfault as rf

REL_TOL = 1e-9
#: G counts as strictly inside/outside when the hull margin exceeds this fraction of the scale.
STRICT = 1e-6
#: Inside and outside cases each random campaign must actually check, per dimension.
MIN_CASES = 100

FloatArray = npt.NDArray[np.float64]


# --------------------------------------------------------------------------------------------
# Independent reference: the zonotope as the convex hull of the box-vertex images.
# --------------------------------------------------------------------------------------------


def box_vertex_images(b: FloatArray, f_min: FloatArray, f_max: FloatArray) -> FloatArray:
    """All 2^m points B f with f a vertex of the box (one row each)."""
    m = b.shape[1]
    corners = np.array(list(itertools.product((0.0, 1.0), repeat=m)))
    return (f_min + corners * (f_max - f_min)) @ b.T


def hull_margin(b: FloatArray, f_min: FloatArray, f_max: FloatArray, g: FloatArray) -> float:
    """min over hull facets of -(normal . G + offset): distance to the boundary if G is inside,
    minus the largest facet violation if G is outside (qhull normals are unit)."""
    hull = ConvexHull(box_vertex_images(b, f_min, f_max))
    normals, offsets = hull.equations[:, :-1], hull.equations[:, -1]
    assert np.allclose(np.linalg.norm(normals, axis=1), 1.0, rtol=0, atol=1e-12)
    return float(-np.max(normals @ g + offsets))


def problem_scale(b: FloatArray, f_min: FloatArray, f_max: FloatArray, g: FloatArray) -> float:
    """sum_k |b_k| (f_max_k - f_min_k) / 2 + |G|, with b_k the efficiency-scaled columns."""
    return float(np.sum(np.linalg.norm(b, axis=0) * (f_max - f_min) / 2) + np.linalg.norm(g))


def hover_wrench(airframe: rf.Airframe, n: int) -> FloatArray:
    return np.array([airframe.mass_kg * airframe.gravity_m_s2, 0.0, 0.0, 0.0])[:n]


def is_positive_zero(x: float) -> bool:
    return x == 0.0 and math.copysign(1.0, x) == 1.0


# --------------------------------------------------------------------------------------------
# 1-2. Random airframes against the hull, n = 4 and n = 3.
# --------------------------------------------------------------------------------------------


def random_airframe(rng: np.random.Generator) -> rf.Airframe:
    m = int(rng.integers(4, 9))
    f_max = rng.uniform(2.0, 8.0, m)
    box_kind = int(rng.integers(3))
    if box_kind == 0:
        f_min = np.zeros(m)
    elif box_kind == 1:  # reversible rotors
        f_min = -rng.uniform(0.0, 0.5, m) * f_max
    else:  # mixed signs, some strictly positive minimum thrusts
        f_min = rng.uniform(-0.3, 0.3, m) * f_max
    eta = rng.uniform(0.2, 1.0, m)
    # Weight near the centre of the attainable thrust range: hover usually feasible.
    centre = float(np.sum(eta * (f_min + f_max)) / 2)
    half = float(np.sum(eta * (f_max - f_min)) / 2)
    weight = max(centre + rng.uniform(-0.5, 0.5) * half, 0.05 * half)
    gravity = 9.81
    return rf.Airframe(
        rng.uniform(0.0, 2 * np.pi, m),
        rng.uniform(0.1, 0.5, m),
        rng.choice([-1.0, 1.0], m),
        f_max,
        weight / gravity,
        [0.02, 0.02, 0.04],
        float(rng.uniform(0.01, 0.2)),
        min_thrust_n=f_min,
        efficiency=eta,
        gravity_m_s2=gravity,
    )


@dataclass(frozen=True)
class Case:
    eq13: float
    margin: float  # formula="facet-margin"
    hull: float
    scale: float


@dataclass(frozen=True)
class Campaign:
    inside: list[Case]
    outside: list[Case]
    rank_deficient: list[tuple[float, float]]
    near_boundary: int


@functools.lru_cache(maxsize=None)
def campaign(n: int) -> Campaign:
    """800 random airframes, classified by the hull (same airframes for n = 4 and n = 3)."""
    rng = np.random.default_rng(20150601)
    give_up_yaw = n == 3
    inside: list[Case] = []
    outside: list[Case] = []
    rank_deficient: list[tuple[float, float]] = []
    near_boundary = 0
    for _ in range(800):
        airframe = random_airframe(rng)
        b = airframe.effectiveness_matrix()[:n]
        g = hover_wrench(airframe, n)
        f_min, f_max = airframe.min_thrust_n, airframe.max_thrust_n
        eq13 = rf.acai(airframe, give_up_yaw=give_up_yaw)
        margin = rf.acai(airframe, give_up_yaw=give_up_yaw, formula="facet-margin")
        if np.linalg.matrix_rank(b) < n:  # e.g. four rotors all spinning the same way
            rank_deficient.append((eq13, margin))
            continue
        case = Case(eq13, margin, hull_margin(b, f_min, f_max, g), problem_scale(b, f_min, f_max, g))
        if case.hull > STRICT * case.scale:
            inside.append(case)
        elif case.hull < -STRICT * case.scale:
            outside.append(case)
        else:
            near_boundary += 1
    return Campaign(inside, outside, rank_deficient, near_boundary)


@pytest.mark.parametrize("n", [4, 3], ids=["with-yaw", "give-up-yaw"])
def test_inside_acai_equals_hull_distance(n: int) -> None:
    result = campaign(n)
    assert len(result.inside) >= MIN_CASES
    worst = 0.0
    for case in result.inside:
        tol = REL_TOL * case.scale
        assert case.eq13 == pytest.approx(case.hull, rel=0, abs=tol)
        assert case.margin == pytest.approx(case.hull, rel=0, abs=tol)
        worst = max(worst, abs(case.eq13 - case.hull) / case.scale)
    assert worst < REL_TOL


@pytest.mark.parametrize("n", [4, 3], ids=["with-yaw", "give-up-yaw"])
def test_outside_facet_margin_equals_largest_hull_violation(n: int) -> None:
    result = campaign(n)
    assert len(result.outside) >= MIN_CASES
    for case in result.outside:
        tol = REL_TOL * case.scale
        assert case.margin == pytest.approx(case.hull, rel=0, abs=tol)
        # Eq. (13) as printed: sign(min d_j) min |d_j|, never below the facet margin.
        assert case.eq13 <= 0.0
        assert abs(case.eq13) <= abs(case.margin) + tol


@pytest.mark.parametrize("n", [4, 3], ids=["with-yaw", "give-up-yaw"])
def test_rank_deficient_random_geometries_return_minus_inf(n: int) -> None:
    for eq13, margin in campaign(n).rank_deficient:
        assert eq13 == -math.inf
        assert margin == -math.inf


def true_distance(b: FloatArray, f_min: FloatArray, f_max: FloatArray, g: FloatArray) -> float:
    """min |B f - G| over the box (bounded least squares): the distance from G to Omega.
    Zero columns (failed rotors) contribute nothing and are dropped (BVLS can cycle on them)."""
    keep = np.any(b != 0.0, axis=0)
    b = b[:, keep]
    result = lsq_linear(b, g, bounds=(f_min[keep], f_max[keep]), method="bvls", max_iter=1000)
    assert result.success
    return float(np.linalg.norm(b @ result.x - g))


@pytest.mark.parametrize("n", [4, 3], ids=["with-yaw", "give-up-yaw"])
def test_failed_rotors_inside_exact_outside_bracketed(n: int) -> None:
    """With some efficiencies exactly 0 (failed rotors): inside, both formulas are still the hull
    distance; outside, facet-margin uses supporting directions that are no longer facets, so it
    is only bracketed: largest hull violation <= -facet-margin <= true distance (bounded least
    squares), and |eq13| <= |facet-margin|."""
    rng = np.random.default_rng(6)
    inside = outside = 0
    for _ in range(900):
        airframe = random_airframe(rng)
        eta = airframe.efficiency.copy()
        eta[rng.random(eta.size) < 0.2] = 0.0
        airframe = airframe.with_efficiency(eta)
        b = airframe.effectiveness_matrix()[:n]
        g = hover_wrench(airframe, n)
        f_min, f_max = airframe.min_thrust_n, airframe.max_thrust_n
        eq13 = rf.acai(airframe, give_up_yaw=n == 3)
        margin = rf.acai(airframe, give_up_yaw=n == 3, formula="facet-margin")
        if np.linalg.matrix_rank(b) < n:
            assert eq13 == margin == -math.inf
            continue
        reference = hull_margin(b, f_min, f_max, g)
        scale = problem_scale(b, f_min, f_max, g)
        tol = REL_TOL * scale
        if reference > STRICT * scale:
            inside += 1
            assert eq13 == pytest.approx(reference, rel=0, abs=tol)
            assert margin == pytest.approx(reference, rel=0, abs=tol)
        elif reference < -STRICT * scale:
            outside += 1
            assert -reference - tol <= -margin <= true_distance(b, f_min, f_max, g) + tol
            assert eq13 <= 0.0
            assert abs(eq13) <= abs(margin) + tol
    assert inside >= MIN_CASES
    assert outside >= MIN_CASES


# --------------------------------------------------------------------------------------------
# 3. acai_from_matrix in general dimension.
# --------------------------------------------------------------------------------------------


def interval_margin(b: FloatArray, f_min: FloatArray, f_max: FloatArray, g: float) -> float:
    """n = 1: Omega = [lo, hi]; signed distance of g to the nearer end (negative outside)."""
    ends = np.stack([b[0] * f_min, b[0] * f_max])
    lo, hi = float(np.sum(ends.min(axis=0))), float(np.sum(ends.max(axis=0)))
    return min(g - lo, hi - g)


@pytest.mark.parametrize(
    ("n", "m_low", "m_high"), [(1, 1, 6), (2, 2, 7), (3, 3, 8), (5, 5, 8)], ids=lambda v: str(v)
)
def test_acai_from_matrix_general_dimension(n: int, m_low: int, m_high: int) -> None:
    rng = np.random.default_rng(1000 + n)
    inside = outside = 0
    for _ in range(250):
        m = int(rng.integers(m_low, m_high + 1))
        b = rng.normal(size=(n, m))
        f_min = rng.uniform(-1.0, 1.0, m)
        f_max = f_min + rng.uniform(0.1, 2.0, m)
        g = b @ rng.uniform(f_min, f_max) + rng.normal(scale=0.6, size=n)
        eq13 = rf.acai_from_matrix(b, f_min, f_max, g)
        margin = rf.acai_from_matrix(b, f_min, f_max, g, formula="facet-margin")
        if n == 1:
            reference = interval_margin(b, f_min, f_max, float(g[0]))
        else:
            assert np.linalg.matrix_rank(b) == n
            reference = hull_margin(b, f_min, f_max, g)
        scale = problem_scale(b, f_min, f_max, g)
        tol = REL_TOL * scale
        assert margin == pytest.approx(reference, rel=0, abs=tol)
        if reference > STRICT * scale:
            inside += 1
            assert eq13 == pytest.approx(reference, rel=0, abs=tol)
        elif reference < -STRICT * scale:
            outside += 1
            assert eq13 <= 0.0
            assert abs(eq13) <= abs(margin) + tol
            if n == 1:  # a single direction: eq. (13) is the signed distance too
                assert eq13 == pytest.approx(reference, rel=0, abs=tol)
    assert inside >= 50
    assert outside >= 25


def test_acai_from_matrix_rank_deficient_is_minus_inf() -> None:
    b = np.array([[1.0, 2.0, -1.0], [2.0, 4.0, -2.0], [0.5, 1.0, -0.5]])  # rank 1 in 3-D
    for formula in ("eq13", "facet-margin"):
        assert rf.acai_from_matrix(b, np.zeros(3), np.ones(3), [0.1, 0.2, 0.05], formula=formula) == -math.inf
    # Fewer actuators than axes.
    assert rf.acai_from_matrix(np.eye(3)[:, :2], np.zeros(2), np.ones(2), [0.5, 0.5, 0.0]) == -math.inf


# --------------------------------------------------------------------------------------------
# 4. Du et al. (JGCD 2015), Tables II and III.
# --------------------------------------------------------------------------------------------


def hover_lp(airframe: rf.Airframe) -> Any:
    """Feasibility LP: B f = G, f_min <= f <= f_max, failed rotors (eta = 0) pinned to zero."""
    b = airframe.effectiveness_matrix()
    bounds = [
        (0.0, 0.0) if eta == 0.0 else (lo, hi)
        for eta, lo, hi in zip(airframe.efficiency, airframe.min_thrust_n, airframe.max_thrust_n)
    ]
    return linprog(
        np.zeros(airframe.rotor_count), A_eq=b, b_eq=hover_wrench(airframe, 4), bounds=bounds, method="highs"
    )


def hull_of(airframe: rf.Airframe) -> tuple[float, float]:
    b = airframe.effectiveness_matrix()
    g = hover_wrench(airframe, 4)
    f_min, f_max = airframe.min_thrust_n, airframe.max_thrust_n
    return hull_margin(b, f_min, f_max, g), problem_scale(b, f_min, f_max, g)


@pytest.mark.parametrize("rotor", [5, 6])
def test_du_ppnnpn_rotor_failed_hover_infeasible_but_eq13_prints_zero(rotor: int) -> None:
    airframe = rf.Airframe.preset("hexa-ppnnpn").with_failed_rotors([rotor])
    assert hover_lp(airframe).status == 2  # infeasible: no thrusts in [0, K] balance hover
    margin_hull, scale = hull_of(airframe)
    largest_violation = -margin_hull
    assert round(largest_violation, 4) == 0.2133
    margin = rf.acai(airframe, formula="facet-margin")
    assert margin == pytest.approx(-largest_violation, rel=0, abs=REL_TOL * scale)
    # The nearest attainable wrench lies inside that facet: the violation is the distance.
    b = airframe.effectiveness_matrix()
    distance = true_distance(b, airframe.min_thrust_n, airframe.max_thrust_n, hover_wrench(airframe, 4))
    assert distance == pytest.approx(largest_violation, rel=0, abs=REL_TOL * scale)
    eq13 = rf.acai(airframe)  # the default formula reproduces the paper's printed 0
    assert eq13 == 0.0
    assert is_positive_zero(eq13)


@pytest.mark.parametrize(
    ("rotor", "table_iii"), [(None, 1.1295), (1, 0.7221), (2, 0.4510), (3, 0.4510), (4, 0.7221)]
)
def test_du_ppnnpn_table_iii_positive_entries_match_hull(rotor: int | None, table_iii: float) -> None:
    airframe = rf.Airframe.preset("hexa-ppnnpn")
    if rotor is not None:
        airframe = airframe.with_failed_rotors([rotor])
    assert hover_lp(airframe).status == 0
    margin_hull, scale = hull_of(airframe)
    assert round(margin_hull, 4) == table_iii
    for formula in ("eq13", "facet-margin"):
        assert rf.acai(airframe, formula=formula) == pytest.approx(margin_hull, rel=0, abs=REL_TOL * scale)


@pytest.mark.parametrize("rotor", [1, 2, 3, 4, 5, 6])
def test_du_pnpnpn_single_failure_hover_feasible_on_boundary(rotor: int) -> None:
    airframe = rf.Airframe.preset("hexa-pnpnpn").with_failed_rotors([rotor])
    lp = hover_lp(airframe)
    assert lp.status == 0  # hover is attainable ...
    margin_hull, scale = hull_of(airframe)
    assert abs(margin_hull) <= REL_TOL * scale  # ... but only on the boundary
    for formula in ("eq13", "facet-margin"):
        value = rf.acai(airframe, formula=formula)
        assert value == 0.0
        assert is_positive_zero(value)


def test_du_pnpnpn_healthy_table_ii() -> None:
    airframe = rf.Airframe.preset("hexa-pnpnpn")
    margin_hull, scale = hull_of(airframe)
    assert round(margin_hull, 4) == 1.4861
    assert rf.acai(airframe) == pytest.approx(margin_hull, rel=0, abs=REL_TOL * scale)


# --------------------------------------------------------------------------------------------
# 5. Batch = single calls, bit for bit.
# --------------------------------------------------------------------------------------------


def batch_airframes() -> list[rf.Airframe]:
    rng = np.random.default_rng(77)
    presets = [rf.Airframe.preset(name) for name in ("quad-x", "hexa-ppnnpn", "hexa-pnpnpn", "octo-x")]
    return presets + [random_airframe(rng) for _ in range(3)]


@pytest.mark.parametrize("give_up_yaw", [False, True])
@pytest.mark.parametrize("formula", ["eq13", "facet-margin"])
def test_batch_equals_single_calls(formula: str, give_up_yaw: bool) -> None:
    rng = np.random.default_rng(4242)
    for airframe in batch_airframes():
        m = airframe.rotor_count
        etas = rng.uniform(0.0, 1.0, (300, m))
        etas[rng.random((300, m)) < 0.25] = 0.0  # failed rotors
        etas[rng.random((300, m)) < 0.1] = 1.0  # healthy rotors
        etas[:5] = 0.0  # all failed: -inf
        etas[5] = 1.0
        batch = rf.acai_batch(airframe, etas, give_up_yaw=give_up_yaw, formula=formula)
        single = np.array([rf.acai(airframe, row, give_up_yaw=give_up_yaw, formula=formula) for row in etas])
        assert batch.shape == (300,)
        assert np.array_equal(batch, single)
        assert np.array_equal(np.signbit(batch), np.signbit(single))
        assert np.all(batch[:5] == -np.inf)
        assert not np.any(np.isnan(batch))

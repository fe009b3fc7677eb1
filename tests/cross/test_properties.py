"""Property-based tests (hypothesis, derandomized) of the ACAI's structural invariants.

What each test proves:

- ``test_invariant_under_rotor_renumbering``: permuting every per-rotor array (angle, arm, spin,
  thrust bounds, eta) leaves the ACAI unchanged, both formulas, with and without yaw, to 1e-12 of
  the problem scale. The zonotope {B f} is the same set (its generators are only reordered), so
  any difference is summation / enumeration-order rounding. Geometries with a *nearly* dependent
  column group (sine in [1e-12, 1e-6], i.e. rotors within ~1e-7 rad of each other) are excluded
  explicitly; ``test_renumbering_near_degenerate_geometry_*`` shows what happens there: the
  normal of a group with sine ~1e-9 is only accurate to ~eps/sine (an intrinsic conditioning
  limit, not an algorithmic one), so eq13 outside moves by 1.7e-10 of the scale, within the
  library's stated resolution ZERO_RTOL x scale.
- ``test_monotone_in_each_efficiency``: with every box containing zero (f_min <= 0 <= f_max;
  f_min == 0 and f_min < 0 both drawn), raising one eta_i never decreases "facet-margin" beyond
  rounding (1e-12 of the scale); for "eq13" the positive part max(rho, 0) and the verdict rho > 0
  are monotone, and both formulas give the same verdict.
- ``test_eq13_is_not_monotone_outside``: a concrete counterexample (Du's PPNNPN hexacopter, rotor 5
  partly recovering) where raising eta_5 *decreases* eq13 while G stays outside (checked with an
  independent hull), and facet-margin increases.
- ``test_facet_margin_monotone_across_zero_snap`` and its premise check: a regression test for a
  defect this suite found -- the "exactly 0.0" threshold used to grow with eta (eta-weighted
  column norms), so raising an efficiency turned a small positive margin (2.1e-8) into 0.0 and
  flipped the verdict although the distance (independent hull) does not change. The threshold
  now uses the nominal column norms.
- ``test_linear_in_thrust_scale``: scaling f_min, f_max and the weight by s > 0 scales the ACAI by
  s (1e-12 of the scale), both formulas.
- ``test_give_up_yaw_never_smaller*``: if G is inside or on the 4-axis set (facet-margin >= 0, or
  eq13 > 0), the 3-axis ACAI is >= the 4-axis one: the 3-D attainable set is the projection of
  the 4-D one, and a ball of radius rho around G projects onto a ball of radius rho around G[:3].
  ``test_eq13_zero_does_not_mean_on_boundary``: eq13 == 0 is not enough (hypothesis found a case
  where eq13 = 0 with yaw while G is 0.048 outside and the 3-axis ACAI is negative).
- ``test_zero_is_positive_zero*``: an ACAI equal to zero is +0.0, never -0.0.
"""

from __future__ import annotations

import itertools
import math
import warnings
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
import numpy.typing as npt
import pytest
from hypothesis import Phase, assume, event, given, settings
from hypothesis import strategies as st
from scipy.spatial import ConvexHull

import rotorfault as rf

# When a hypothesis test fails, hypothesis' pytest plugin imports libcst to print a patch; libcst
# warns (DeprecationWarning) on import, and filterwarnings = ["error"] turns that into a pytest
# INTERNALERROR that hides the real failure. Import it once here with that warning silenced.
with warnings.catch_warnings():
    warnings.simplefilter("ignore", DeprecationWarning)
    try:
        import libcst  # noqa: F401
    except ImportError:  # pragma: no cover - libcst is optional
        pass

FloatArray = npt.NDArray[np.float64]

REL_TOL = 1e-12
GRAVITY = 9.81
FORMULAS = ("eq13", "facet-margin")
COMBOS = list(itertools.product(FORMULAS, (False, True)))

#: Deterministic in CI. The "explain" phase is left out: it imports libcst, whose
#: DeprecationWarning would turn a real failure report into a warning error (filterwarnings=error).
SETTINGS = settings(
    derandomize=True,
    deadline=None,
    max_examples=300,
    database=None,
    phases=[Phase.explicit, Phase.reuse, Phase.generate, Phase.target, Phase.shrink],
)

finite = {"allow_nan": False, "allow_infinity": False, "allow_subnormal": False}


# --------------------------------------------------------------------------------------------
# Strategies and helpers
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Setup:
    """Everything per rotor, plus mass; eta is passed separately to ``rf.acai``."""

    angle: FloatArray
    arm: FloatArray
    spin: FloatArray
    f_min: FloatArray
    f_max: FloatArray
    eta: FloatArray
    mass: float
    k_mu: float

    @property
    def m(self) -> int:
        return len(self.angle)

    def airframe(self) -> rf.Airframe:
        return rf.Airframe(
            self.angle,
            self.arm,
            self.spin,
            self.f_max,
            self.mass,
            [0.02, 0.02, 0.04],
            self.k_mu,
            min_thrust_n=self.f_min,
            gravity_m_s2=GRAVITY,
        )

    def acai(self, give_up_yaw: bool, formula: str, eta: Any = None) -> float:
        eta = self.eta if eta is None else eta
        return rf.acai(self.airframe(), eta, give_up_yaw=give_up_yaw, formula=formula)

    def scale(self, give_up_yaw: bool, eta: Any = None) -> float:
        """sum_k |b_k| eta_k (f_max_k - f_min_k) / 2 + |G|: the size of the problem."""
        eta = self.eta if eta is None else np.asarray(eta)
        b = self.airframe().effectiveness_matrix()[: 3 if give_up_yaw else 4] * eta
        return float(np.sum(np.linalg.norm(b, axis=0) * (self.f_max - self.f_min) / 2) + self.mass * GRAVITY)


def lists(m: int, elements: st.SearchStrategy[Any]) -> st.SearchStrategy[list[Any]]:
    return st.lists(elements, min_size=m, max_size=m)


efficiencies = st.one_of(
    st.just(1.0), st.floats(0.5, 1.0, **finite), st.floats(0.0, 1.0, **finite), st.just(0.0)
)


@st.composite
def setups(
    draw: st.DrawFn,
    box: str = "any",
    eta_strategy: st.SearchStrategy[float] = efficiencies,
    spread: float = 0.7,
) -> Setup:
    """Random airframes. ``box``: "any" (f_min may be negative, zero or positive) or
    "contains-zero" (f_min <= 0 <= f_max, with f_min == 0 and f_min < 0 both likely). The
    weight is the eta-weighted thrust centre +- ``spread`` x the eta-weighted half range.

    Half the layouts are jittered regular polygons with alternating spins (so hover is often
    feasible, and the unjittered ones are exactly symmetric, with many coplanar generators),
    half have arbitrary arm angles and spins."""
    m = draw(st.integers(4, 8))
    if draw(st.booleans()):
        jitter = np.array(draw(lists(m, st.floats(-0.3, 0.3, **finite))))
        angle = np.mod(2 * math.pi * np.arange(m) / m + jitter, 2 * math.pi)
        first = draw(st.sampled_from([-1.0, 1.0]))
        spin = first * (-1.0) ** np.arange(m)
    else:
        angle = np.array(draw(lists(m, st.floats(0.0, 2 * math.pi, exclude_max=True, **finite))))
        spin = np.array(draw(lists(m, st.sampled_from([-1.0, 1.0]))))
    f_max = np.array(draw(lists(m, st.floats(1.0, 10.0, **finite))))
    if box == "contains-zero":
        ratio = lists(m, st.one_of(st.just(0.0), st.floats(-0.8, 0.0, **finite)))
    else:
        ratio = lists(m, st.floats(-0.8, 0.5, **finite))
    f_min = np.array(draw(ratio)) * f_max
    eta = np.array(draw(lists(m, eta_strategy)))
    # Weight around the centre of the attainable thrust range: G inside, on or outside.
    centre, half = float(eta @ (f_min + f_max) / 2), float(eta @ (f_max - f_min) / 2)
    position = draw(st.floats(-spread, spread, **finite))
    weight = max(centre + position * half, 0.05 * float(np.sum(f_max - f_min)))
    return Setup(
        angle=angle,
        arm=np.array(draw(lists(m, st.floats(0.1, 0.5, **finite)))),
        spin=spin,
        f_min=f_min,
        f_max=f_max,
        eta=eta,
        mass=weight / GRAVITY,
        k_mu=draw(st.floats(0.01, 0.2, **finite)),
    )


def group_sines(setup: Setup, n: int) -> FloatArray:
    """For every group of n - 1 nominal columns (rows 0..n-1 of B without efficiencies): the
    (n-1)-volume they span over the product of their lengths (1: orthogonal, 0: dependent). This
    is the quantity the library compares with RANK_RTOL; the normal of a group is only accurate
    to about machine epsilon / sine."""
    b = setup.airframe().effectiveness_matrix()[:n]
    sines = []
    for group in itertools.combinations(range(setup.m), n - 1):
        columns = b[:, group]
        volume = float(np.prod(np.linalg.svd(columns, compute_uv=False)))
        sines.append(volume / float(np.prod(np.linalg.norm(columns, axis=0))))
    return np.array(sines)


def well_conditioned(setup: Setup) -> bool:
    """No column group is *nearly* dependent (sine in [1e-12, 1e-6]): groups are either exactly
    dependent to rounding (skipped by the library whatever the order) or clearly independent.
    Needed where two *different* enumerations are compared (renumbering, 3 vs 4 axes): with
    nearly coincident rotors eq13's outside value moves by ~1e-10 of the scale under
    renumbering (see test_renumbering_near_degenerate_geometry_*)."""
    return all(
        not np.any((sines >= 1e-12) & (sines <= 1e-6))
        for sines in (group_sines(setup, 4), group_sines(setup, 3))
    )


def assert_close(actual: float, expected: float, tol: float) -> None:
    if math.isinf(expected) or math.isinf(actual):
        assert actual == expected
    else:
        assert abs(actual - expected) <= tol, (actual, expected, tol)


def is_positive_zero(x: float) -> bool:
    return x == 0.0 and math.copysign(1.0, x) == 1.0


def hull_margin(b: FloatArray, f_min: FloatArray, f_max: FloatArray, g: FloatArray) -> float:
    """Independent reference: -(largest violation) of the hull facets of the box-vertex images
    (positive: distance to the boundary from inside)."""
    corners = np.array(list(itertools.product((0.0, 1.0), repeat=b.shape[1])))
    hull = ConvexHull((f_min + corners * (f_max - f_min)) @ b.T)
    return float(-np.max(hull.equations[:, :-1] @ g + hull.equations[:, -1]))


# --------------------------------------------------------------------------------------------
# Invariance under renumbering the rotors
# --------------------------------------------------------------------------------------------


@SETTINGS
@given(setup=setups(), data=st.data())
def test_invariant_under_rotor_renumbering(setup: Setup, data: st.DataObject) -> None:
    assume(well_conditioned(setup))
    perm = np.array(data.draw(st.permutations(range(setup.m)), label="permutation"))
    permuted = replace(
        setup,
        angle=setup.angle[perm],
        arm=setup.arm[perm],
        spin=setup.spin[perm],
        f_min=setup.f_min[perm],
        f_max=setup.f_max[perm],
        eta=setup.eta[perm],
    )
    for formula, give_up_yaw in COMBOS:
        tol = REL_TOL * setup.scale(give_up_yaw)
        assert_close(permuted.acai(give_up_yaw, formula), setup.acai(give_up_yaw, formula), tol)


def near_degenerate_pair() -> tuple[rf.Airframe, rf.Airframe]:
    """Found by hypothesis (then shrunk by hand): rotor 3 sits 6e-8 rad from rotors 1, 2 and 4
    (all cw, on the x axis), so the groups {1, 2, 3} and {2, 3, 4} have sine 1.4e-9, just above
    RANK_RTOL; their normals are accurate only to ~eps / sine ~ 1e-7. The second airframe swaps
    rotors 3 and 4."""
    angle = np.array([0.0, 0.0, 6e-8, 0.0, 1.0])
    arm = np.array([0.5, 0.25, 0.109375, 0.5, 0.5])
    spin = np.array([-1.0, -1.0, -1.0, -1.0, 1.0])

    def build(order: list[int]) -> rf.Airframe:
        return rf.Airframe(
            angle[order], arm[order], spin[order], np.ones(5), 2.5 / GRAVITY, [0.02, 0.02, 0.04], 0.125,
            gravity_m_s2=GRAVITY,
        )

    return build([0, 1, 2, 3, 4]), build([0, 1, 3, 2, 4])


def test_renumbering_near_degenerate_geometry_within_library_resolution() -> None:
    """Outside the well-conditioned regime the renumbering error of eq13 (G outside) is still
    within the library's stated resolution ZERO_RTOL x scale, and facet-margin stays exact."""
    original, swapped = near_degenerate_pair()
    b = original.effectiveness_matrix()
    scale = float(np.sum(np.linalg.norm(b, axis=0)) / 2 + original.hover_thrust_n)
    margin = rf.acai(original, formula="facet-margin")
    assert margin == pytest.approx(-0.267114, abs=1e-6)  # G outside
    assert abs(rf.acai(swapped, formula="facet-margin") - margin) <= REL_TOL * scale
    assert abs(rf.acai(swapped) - rf.acai(original)) <= rf.ZERO_RTOL * scale


# --------------------------------------------------------------------------------------------
# Monotonicity in the efficiencies
# --------------------------------------------------------------------------------------------


@SETTINGS
@given(setup=setups(box="contains-zero"), data=st.data())
def test_monotone_in_each_efficiency(setup: Setup, data: st.DataObject) -> None:
    i = data.draw(st.integers(0, setup.m - 1), label="rotor")
    raised = setup.eta.copy()
    raised[i] = data.draw(
        st.one_of(st.just(1.0), st.floats(float(setup.eta[i]), 1.0, **finite)), label="raised eta_i"
    )
    for give_up_yaw in (False, True):
        tol = REL_TOL * setup.scale(give_up_yaw, raised)
        before = setup.acai(give_up_yaw, "facet-margin")
        after = setup.acai(give_up_yaw, "facet-margin", raised)
        event(f"give_up_yaw={give_up_yaw}: {'inside' if before > 0 else 'outside/boundary/-inf'}")
        assert after >= before - tol, (before, after)
        eq13_before = setup.acai(give_up_yaw, "eq13")
        eq13_after = setup.acai(give_up_yaw, "eq13", raised)
        assert max(eq13_after, 0.0) >= max(eq13_before, 0.0) - tol
        assert (eq13_after > 0) or not (eq13_before > 0)
        # The verdicts of the two formulas agree.
        assert (eq13_before > 0) == (before > 0)
        assert (eq13_after > 0) == (after > 0)


def test_eq13_is_not_monotone_outside() -> None:
    """PPNNPN hexacopter, rotor 5 at efficiency 0.001 then 0.05 (others healthy): G is outside in
    both (independent hull); raising eta_5 moves G closer (facet-margin -0.211 -> -0.120) but eq13
    goes from -0.0011 to -0.0103: it decreases. From eta_5 = 0 it also drops, from 0.0."""
    hexa = rf.Airframe.preset("hexa-ppnnpn")
    etas = [np.array([1.0, 1.0, 1.0, 1.0, e, 1.0]) for e in (0.0, 0.001, 0.05)]
    eq13 = [rf.acai(hexa, eta) for eta in etas]
    margin = [rf.acai(hexa, eta, formula="facet-margin") for eta in etas]
    g = np.array([hexa.hover_thrust_n, 0.0, 0.0, 0.0])
    for eta, value in zip(etas, margin):
        b = hexa.with_efficiency(eta).effectiveness_matrix()
        reference = hull_margin(b, hexa.min_thrust_n, hexa.max_thrust_n, g)
        assert reference < -0.1  # G clearly outside
        if eta[4] > 0:  # all efficiencies > 0: facet-margin is -(largest hull violation)
            assert value == pytest.approx(reference, rel=0, abs=1e-12)
    assert margin[0] < margin[1] < margin[2]  # the monotone reading improves
    assert eq13[0] == 0.0  # Du Table III's printed 0
    assert eq13[0] > eq13[1] > eq13[2]  # eq. (13) gets worse as the rotor recovers
    assert eq13[1] == pytest.approx(-0.0011295, abs=1e-7)
    assert eq13[2] == pytest.approx(-0.0102833, abs=1e-7)


# Quad-x geometry whose hover wrench lies 2.1163620e-8 inside a facet spanned by rotors that do
# not include rotor 1: 1.030e-9 of the problem scale with eta = [0.8, 0.7, 0.6, 0.5], but only
# 0.999e-9 of the (larger) scale once eta_1 = 1. The distance itself does not change.
SNAP_MASS_KG = 1.24999997321
SNAP_ETA = np.array([0.8, 0.7, 0.6, 0.5])
SNAP_RAISED = np.array([1.0, 0.7, 0.6, 0.5])


def snap_airframe() -> rf.Airframe:
    q = rf.Airframe.preset("quad-x")
    return rf.Airframe(
        q.arm_angle_rad,
        q.arm_length_m,
        q.spin_sign,
        q.max_thrust_n,
        SNAP_MASS_KG,
        q.inertia_kg_m2,
        q.drag_torque_ratio_m,
        gravity_m_s2=q.gravity_m_s2,
    )


def test_snap_reproducer_premise() -> None:
    """The premise of the regression test below, checked without the library's ACAI: the true
    distance (hull) is the same 2.1e-8 for both efficiency vectors, and it is above ZERO_RTOL x the
    eta-weighted scale (the snap threshold of earlier builds) before the change, below it after."""
    airframe = snap_airframe()
    g = np.array([airframe.hover_thrust_n, 0.0, 0.0, 0.0])
    ratios = []
    distances = []
    for eta in (SNAP_ETA, SNAP_RAISED):
        b = airframe.with_efficiency(eta).effectiveness_matrix()
        scale = float(np.sum(np.linalg.norm(b, axis=0) * airframe.max_thrust_n / 2) + np.linalg.norm(g))
        distance = hull_margin(b, airframe.min_thrust_n, airframe.max_thrust_n, g)
        distances.append(distance)
        ratios.append(distance / scale)
    assert distances[0] == pytest.approx(2.1163620e-8, rel=1e-6)
    assert distances[1] == pytest.approx(distances[0], rel=1e-6)
    assert ratios[0] > rf.ZERO_RTOL > ratios[1]


def test_facet_margin_monotone_across_zero_snap() -> None:
    """Raising eta_1 never lowers the index, and the verdict agrees for both vectors."""
    airframe = snap_airframe()
    for formula in FORMULAS:
        before = rf.acai(airframe, SNAP_ETA, formula=formula)
        after = rf.acai(airframe, SNAP_RAISED, formula=formula)
        assert after >= before, (formula, before, after)
        assert (after > 0) == (before > 0)


# --------------------------------------------------------------------------------------------
# Linear scaling
# --------------------------------------------------------------------------------------------


@SETTINGS
@given(
    setup=setups(),
    factor=st.one_of(st.sampled_from([0.5, 2.0, 10.0]), st.floats(1e-3, 1e3, **finite)),
)
def test_linear_in_thrust_scale(setup: Setup, factor: float) -> None:
    scaled = replace(setup, f_min=setup.f_min * factor, f_max=setup.f_max * factor, mass=setup.mass * factor)
    for formula, give_up_yaw in COMBOS:
        tol = REL_TOL * factor * setup.scale(give_up_yaw)
        expected = factor * setup.acai(give_up_yaw, formula)
        assert_close(scaled.acai(give_up_yaw, formula), expected, tol)


# --------------------------------------------------------------------------------------------
# Giving up yaw
# --------------------------------------------------------------------------------------------


@SETTINGS
@given(
    setup=st.one_of(
        setups(),
        setups(eta_strategy=st.one_of(st.just(1.0), st.floats(0.6, 1.0, **finite)), spread=0.3),
    )
)
def test_give_up_yaw_never_smaller(setup: Setup) -> None:
    assume(well_conditioned(setup))
    # "G inside or on the boundary" is facet-margin >= 0, but only eq13 > 0: eq. (13) also
    # prints 0 for some G outside (see test_eq13_zero_does_not_mean_on_boundary).
    for formula, inside in (("facet-margin", lambda x: x >= 0.0), ("eq13", lambda x: x > 0.0)):
        with_yaw = setup.acai(False, formula)
        event(f"{formula}: 4-axis ACAI inside" if inside(with_yaw) else f"{formula}: vacuous")
        if inside(with_yaw):
            give_up_yaw_acai = setup.acai(True, formula)
            assert give_up_yaw_acai >= with_yaw - REL_TOL * setup.scale(False)


def test_eq13_zero_does_not_mean_on_boundary() -> None:
    """Found by hypothesis: eq13 = 0.0 with yaw although G is 0.048 outside the 4-D set (hull),
    so outside that even its projection misses the 3-D set (give_up_yaw ACAI < 0). The
    projection property above therefore needs eq13 > 0; facet-margin >= 0 is enough."""
    airframe = rf.Airframe(
        np.arange(6) * math.pi / 3,
        [0.5, 0.5, 0.125, 0.125, 0.5, 0.125],
        [-1, 1, -1, 1, -1, 1],
        [1.0, 1.0, 3.0, 1.0, 1.0, 1.0],
        3.5 / GRAVITY,
        [0.02, 0.02, 0.04],
        0.125,
        gravity_m_s2=GRAVITY,
    )
    eta = np.array([1.0, 1.0, 1.0, 1.0, 0.0, 1.0])
    b = airframe.with_efficiency(eta).effectiveness_matrix()
    g = np.array([airframe.hover_thrust_n, 0.0, 0.0, 0.0])
    outside_4d = hull_margin(b, airframe.min_thrust_n, airframe.max_thrust_n, g)
    outside_3d = hull_margin(b[:3], airframe.min_thrust_n, airframe.max_thrust_n, g[:3])
    assert outside_4d == pytest.approx(-0.048033, abs=1e-6)
    assert outside_3d == pytest.approx(-0.023518, abs=1e-6)
    eq13 = rf.acai(airframe, eta)
    assert eq13 == 0.0  # as if G were on the boundary
    assert rf.acai(airframe, eta, give_up_yaw=True) == pytest.approx(outside_3d, abs=1e-12)
    assert rf.acai(airframe, eta, formula="facet-margin") == pytest.approx(outside_4d, abs=1e-12)


def test_give_up_yaw_never_smaller_presets() -> None:
    """Deterministic companion with many non-vacuous cases (4-axis ACAI >= 0)."""
    rng = np.random.default_rng(31)
    checked = 0
    for name in rf.Airframe.presets():
        airframe = rf.Airframe.preset(name)
        b = airframe.effectiveness_matrix()
        scale = float(np.sum(np.linalg.norm(b, axis=0) * airframe.max_thrust_n / 2) + airframe.hover_thrust_n)
        etas = rng.uniform(0.3, 1.0, (100, airframe.rotor_count))
        for formula in FORMULAS:
            with_yaw = rf.acai_batch(airframe, etas, formula=formula)
            give_up_yaw_acai = rf.acai_batch(airframe, etas, give_up_yaw=True, formula=formula)
            ok = with_yaw >= 0 if formula == "facet-margin" else with_yaw > 0
            checked += int(ok.sum())
            assert np.all(give_up_yaw_acai[ok] >= with_yaw[ok] - REL_TOL * scale)
    assert checked >= 300


# --------------------------------------------------------------------------------------------
# +0.0, never -0.0
# --------------------------------------------------------------------------------------------


@SETTINGS
@given(setup=setups(box="contains-zero"))
def test_zero_is_positive_zero(setup: Setup) -> None:
    for formula, give_up_yaw in COMBOS:
        value = setup.acai(give_up_yaw, formula)
        assert not math.isnan(value)
        if value == 0.0:
            assert is_positive_zero(value)


def test_zero_is_positive_zero_on_known_boundaries() -> None:
    values = []
    for rotor in range(1, 7):
        hexa = rf.Airframe.preset("hexa-pnpnpn").with_failed_rotors([rotor])
        values += [rf.acai(hexa, formula=f) for f in FORMULAS]
    for rotor in (5, 6):
        values.append(rf.acai(rf.Airframe.preset("hexa-ppnnpn").with_failed_rotors([rotor])))
    batch = rf.acai_batch(rf.Airframe.preset("hexa-pnpnpn"), 1.0 - np.eye(6))
    values += batch.tolist()
    # G outside with one d_j exactly 0: eq. (13) computes -min|d_j| = -0.0 before snapping.
    values.append(rf.acai_from_matrix(np.eye(2), [0.0, 0.0], [1.0, 1.0], [2.0, 1.0]))
    values.append(
        rf.acai_from_matrix(np.eye(2), [-1.0, -1.0], [1.0, 1.0], [-1.0, 0.0], formula="facet-margin")
    )
    values.append(rf.acai_from_matrix(np.array([[2.0, -1.0]]), [0.0, -1.0], [1.0, 1.0], [3.0]))
    assert len(values) == 23
    for value in values:
        assert is_positive_zero(value), value

"""Issue 19, items 1, 2 and 6: verdicts free of the rows' units, and the hover verdict carried by
every ACAI result.

Scale invariance is a hypothesis property over n = 3..6 and row ratios up to 1e8, checked against
an independent LP (scipy's HiGHS): G is attainable iff some u in the box has B u = G."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy.optimize import linprog

import rotorfault as rf

SETTINGS = settings(max_examples=60, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])


def lp_attainable(b: np.ndarray, lo: np.ndarray, hi: np.ndarray, g: np.ndarray) -> bool:
    """Feasibility of B u = G, lo <= u <= hi, on the row-normalised system (an LP's own
    tolerances are absolute, so the rows are brought to unit size first: that is a statement
    about the LP, not about rotorfault)."""
    scale = 1.0 / np.linalg.norm(b, axis=1)
    done = linprog(np.zeros(b.shape[1]), A_eq=b * scale[:, None], b_eq=g * scale, bounds=list(zip(lo, hi)), method="highs")
    return bool(done.status == 0)


@st.composite
def problems(draw: st.DrawFn) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    n = draw(st.integers(3, 6))
    m = n + draw(st.integers(1, 2))
    seed = draw(st.integers(0, 2**32 - 1))
    rng = np.random.default_rng(seed)
    b = rng.normal(size=(n, m))
    lo = np.where(rng.random(m) < 0.3, -rng.uniform(0.1, 1.0, m), 0.0)
    hi = rng.uniform(0.5, 2.0, m)
    u = rng.uniform(lo, hi) * draw(st.sampled_from([0.5, 1.0, 1.3]))  # inside, near, outside the box
    g = b @ u
    # The units: each row multiplied by its own factor, ratios up to 1e8.
    units = 10.0 ** rng.uniform(-4.0, 4.0, n)
    return b, lo, hi, g, units


@SETTINGS
@given(problem=problems())
def test_verdicts_are_free_of_units_and_agree_with_an_lp(problem: tuple[np.ndarray, ...]) -> None:
    b, lo, hi, g, units = problem
    plain = rf.acai_from_matrix(b, lo, hi, g)
    scaled = rf.acai_from_matrix(b * units[:, None], lo, hi, g * units)
    assert plain.hover == scaled.hover
    assert (plain > 0) == (scaled > 0) and (plain == 0) == (scaled == 0)
    if plain.hover in ("inside", "outside"):  # a boundary point is a tie the LP cannot break
        assert plain.hover_feasible == lp_attainable(b * units[:, None], lo, hi, g * units)


def test_the_issue_cases() -> None:
    b = np.array(
        [[0, -7e-4, -5e-4, -1e-4, -9e-4, -3e-4, 1.3e-3], [-4e-4, -1.9e-3, -1e-4, -1.3e-3, -1.8e-3, -4e-4, -1e-4],
         [1.2, -0.4, -1.8, -0.9, -0.7, 0.7, -1.4], [-3e-4, -2e-4, 1.5e-3, 1.7e-3, 2e-4, -4e-4, -1e-3],
         [-1.6e-3, 6e-4, 1.1e-3, 0, -3e-4, -1.1e-3, 8e-4], [-9e-2, 1e-2, 8e-2, -4e-2, 6e-2, -5e-2, 6e-2]]
    )
    g = np.array([2.99e-4, -3.234e-3, -0.957405, 8.63e-4, -1.442e-3, -0.101647])
    value = rf.acai_from_matrix(b, np.zeros(7), np.ones(7), g)
    assert value.hover == "outside" and value < 0  # was +4.41e-05, "inside"
    assert not lp_attainable(b, np.zeros(7), np.ones(7), g)
    a, k = 1e-5, 1e-6
    tiny = np.array([[1, 1, 1, 1], [-a, a, a, -a], [a, a, -a, -a], [k, -k, k, -k]])
    g = np.array([10.0, 0, 0, 0])
    value = rf.acai_from_matrix(tiny, np.zeros(4), np.full(4, 6.0), g)
    # Du eqs. (14), (29), (30) written out: every facet pair spanned by 3 of the 4 columns.
    distances = []
    for skip in range(4):
        group = np.delete(tiny, skip, axis=1)
        normal = np.linalg.svd(group.T)[2][-1]
        half_width = np.sum(np.abs(normal @ tiny)) * 3.0
        distances.append(half_width - abs(normal @ (tiny @ np.full(4, 3.0) - g)))
    assert value.hover == "inside" and math.isclose(value, min(distances), rel_tol=1e-9)  # was -inf
    assert math.isclose(value, 9.9e-6, rel_tol=1e-3)


def test_every_result_carries_the_hover_verdict() -> None:
    ppnnpn = rf.Airframe.preset("hexa-ppnnpn")
    failed = ppnnpn.with_failed_rotors([5])
    value = rf.acai(failed)
    assert value == 0.0 and value.hover == "outside" and not value.hover_feasible and repr(value) == "0.0*"
    assert "0.0000*" in str(rf.controllability(failed)) and rf.controllability(failed).hover == "outside"
    eta = [0.621, 0.001, 0.0, 0.919, 0.455, 0.764]
    batch = rf.acai_batch(ppnnpn, [eta], with_hover=True)
    assert batch.hover_code.tolist() == [-1] and rf.acai(ppnnpn, eta).hover == "outside"
    arrays = rf.failure_table(ppnnpn, max_failed=1).to_arrays()
    assert arrays["hover"].tolist() == ["inside"] * 5 + ["outside"] * 2
    scan = rf.efficiency_scan(rf.Airframe.preset("hexa-ppnnpn"), (5,), 0.5, formula="facet-margin")
    assert scan.formula == "facet-margin" and scan.hover_code.tolist() == [-1, 1, 1]
    assert np.all(scan.acai[scan.hover_code < 0] < 0)  # the facet margin never reads 0 outside


def test_controllability_rank_is_free_of_the_inertia_units() -> None:
    quad = rf.Airframe.preset("quad-x")
    for inertia in ([1e-12] * 3, [1e8] * 3):
        tiny = rf.Airframe(
            arm_angle_rad=quad.arm_angle_rad, arm_length_m=quad.arm_length_m, spin=["cw", "ccw", "cw", "ccw"],
            max_thrust_n=quad.max_thrust_n, mass_kg=quad.mass_kg, inertia_kg_m2=inertia,
            drag_torque_ratio_m=quad.drag_torque_ratio_m,
        )
        assert rf.controllability(tiny).controllability_rank == 8


def test_pickled_acai_keeps_its_verdict() -> None:
    import pickle

    value = rf.acai(rf.Airframe.preset("hexa-ppnnpn").with_failed_rotors([6]))
    back = pickle.loads(pickle.dumps(value))
    assert back == value and back.hover == "outside"
    with pytest.raises(TypeError, match="^with_hover"):
        rf.acai_batch(rf.Airframe.preset("quad-x"), np.ones((1, 4)), with_hover="yes")  # type: ignore[call-overload]

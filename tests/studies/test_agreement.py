"""certify against flights (issue 30): every single and double failure of Ke's quadcopter and of
the PX4 quadrotor imported from its parameters, certify's verdict beside a flight of each of our
controllers (:mod:`rotorfault.studies.agreement`: the failure at 1 s, 10 s after it, verdicts
from the last 5 s: holds within 2 m horizontally, 1 m in altitude, 0.5 m/s). Where certify says
survivable some controller holds; where it says not, none does."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import pytest

from rotorfault.studies import deciding as D
from rotorfault.studies.agreement import CONTROLLERS, CertifyAgreement, certify_against_flights, px4_vehicle

DATA = Path(__file__).parents[1] / "data"


@pytest.fixture(scope="module")
def agreement() -> CertifyAgreement:
    return certify_against_flights([D.vehicle("ke-quadcopter"), px4_vehicle(DATA / "px4-quad-x.params")])


def test_certify_agrees_with_the_flights(agreement: CertifyAgreement) -> None:
    # 4 single and 6 double failures per quadrotor.
    assert [len(c.failed) for c in agreement.cases].count(1) == 8 and len(agreement.cases) == 20
    assert not agreement.disagreements(), agreement.table()
    n = agreement.counts()
    assert n["agree"] == n["cases"] and n["not_survivable_held"] == 0 and n["survivable_held"] == n["survivable"]
    # Both answers occur: the comparison is not vacuous.
    assert 0 < n["survivable"] < n["cases"], agreement.table()


def test_every_controller_flew_or_says_why(agreement: CertifyAgreement) -> None:
    for case in agreement.cases:
        assert [f.controller for f in case.flights] == list(CONTROLLERS)
        for f in case.flights:
            assert f.verdict in ("holds", "drifts", "circles", "crashed", "diverged", "design-refused", "not-applicable")
            assert f.note or f.verdict not in ("design-refused", "not-applicable", "crashed", "diverged")
            if f.holds:
                assert f.horizontal_error_m <= 2.0 and f.altitude_error_m <= 1.0


def test_the_comparison_can_fail(agreement: CertifyAgreement) -> None:
    """Without the controllers that fly a spinning vehicle (only the hover LQR, which refuses a
    quadrotor without a rotor), every survivable-by-spinning case disagrees."""
    only_lqr = [dataclasses.replace(c, flights=tuple(f for f in c.flights if f.controller == "linear-feedback"))
                for c in agreement.cases]
    spinning = [c for c in only_lqr if c.hover == "no" and c.spinning.hover == "spinning"]
    assert spinning and all(not c.agrees for c in spinning)


def test_the_table_shows_each_case(agreement: CertifyAgreement) -> None:
    table = agreement.table()
    assert table.count("\n| ke-quadcopter |") == 10 and table.count("\n| px4-quad-x |") == 10
    assert all(len(r) == len(agreement.headers()) for r in agreement.rows())


def test_bad_input_is_refused_by_field() -> None:
    with pytest.raises(ValueError, match="max_failed"):
        certify_against_flights([], max_failed=3)
    with pytest.raises(ValueError, match="controllers"):
        certify_against_flights([], controllers=["pid"])
    with pytest.raises(TypeError, match=r"vehicles\[0\]"):
        certify_against_flights(["ke-quadcopter"])  # type: ignore[list-item]
    assert certify_against_flights([]).cases == ()

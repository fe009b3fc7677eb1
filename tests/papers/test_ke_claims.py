"""Ke's flight claims scored (issue 28): each claim beside our flight of the same scenario, its
verdict over the whole window, whether the claim holds here and why. Measured (ke-hil, default
law): every stabilisation claim holds (the spin settles: 19.6, 30.5, 42.0, 42.1 rad/s against
Ke's about 23, 38, 42, 42) while no flight holds its setpoint (verdict drifts); Fig. 7's front
pair crashes, as Ke predicts; the horizontal overshoot after one failure is 15.4 m, not under
10 m."""

from __future__ import annotations

import pytest

from rotorfault.papers import ke as ke_paper


@pytest.fixture(scope="module")
def claims() -> list[ke_paper.PaperClaim]:
    names = [name for name, *_ in ke_paper.KE_CLAIMS]
    return ke_paper.flight_claims([ke_paper.run_scenario(n) for n in names] + [ke_paper.run_scenario("one-failure", law="baseline")])


def test_each_claim_has_our_measurement_verdict_and_reason(claims: list[ke_paper.PaperClaim]) -> None:
    assert [c.where for c in claims] == [
        "Sec. V-C, Fig. 16", "Sec. V-C, Figs. 9 and 16", "Sec. V-C, Fig. 16", "Sec. V-C, Fig. 16", "Sec. IV-B, Fig. 7", "Sec. V-C 3)",
    ]
    assert [c.verdict for c in claims] == ["drifts", "drifts", "drifts", "drifts", "crashed", "drifts"]
    assert [c.status for c in claims] == ["confirmed"] * 5 + ["not confirmed"]
    assert all(c.reason and c.measurement and c.paper == ke_paper.PAPER for c in claims)
    assert "steady spin 19.6 rad/s" in claims[0].measurement and "about 23" in claims[0].reason
    assert "it does not hold its setpoint (verdict drifts" in claims[0].reason
    assert claims[4].measurement.startswith("crashed at 12.34 s")
    assert "largest horizontal error 15.4 m" in claims[5].measurement


def test_a_claim_whose_flight_was_not_flown_is_left_out_and_the_baseline_is_not_scored() -> None:
    run = ke_paper.run_scenario("two-opposite")
    got = ke_paper.flight_claims([run, ke_paper.run_scenario("two-opposite", law="baseline")])
    assert [c.where for c in got] == ["Sec. V-C, Fig. 16"] and "42.0 rad/s" in got[0].measurement

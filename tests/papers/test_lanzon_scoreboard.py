"""Lanzon's scoreboard (issue 28): every scored row can fail. Each test breaks what a row
measures and watches it fail:

- eq. (26): the closed loop under the RFL against the printed linear model across the flown
  region; with the linearisation switched off (alpha = 0, beta = I) the scored rows fail, while
  the 13 Jacobian-at-0 entries (consistency, not scored) still pass;
- the loop shape: measured on the achieved loop G K, so a design for another crossover (80 or
  150 rad/s) or another low-frequency gain fails the printed rows;
- the flight claims: confirmed only when the whole flight holds, with crashed / diverged / circles
  reported as such; the rotor-inertia sweep says where the verdict changes.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from rotorfault.control.lanzon import LanzonVehicle, design
from rotorfault.papers._numbers import score
from rotorfault.papers import lanzon, lanzon_checks, lanzon_report


def _no_linearisation(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(LanzonVehicle, "rfl", lambda self, x: (np.zeros(3), np.eye(3)))


@pytest.mark.parametrize("izz", lanzon.IZZ_VALUES)
def test_eq26_closed_loop_is_exact_across_the_region(izz: float) -> None:
    check = lanzon_checks.eq26_closed_loop(LanzonVehicle(inertia_zz_kg_m2=izz))
    assert check.linearised and check.samples == lanzon_checks.EQ26_SAMPLES
    assert check.max_relative_error < lanzon_checks.EQ26_CLOSED_LOOP_RTOL
    # the samples cover the region (not a neighbourhood of hover)
    assert np.max(np.abs(check.worst_state) / np.asarray(lanzon_checks.EQ26_STATE_HALF_WIDTH)) > 0.1


@pytest.mark.parametrize("izz", lanzon.IZZ_VALUES)
def test_eq26_without_the_linearisation_fails(izz: float) -> None:
    off = lanzon_checks.eq26_closed_loop(LanzonVehicle(inertia_zz_kg_m2=izz), linearised=False)
    assert off.max_relative_error > 1e5 * lanzon_checks.EQ26_CLOSED_LOOP_RTOL


def test_scored_eq26_rows_fail_and_consistency_rows_pass_without_the_linearisation(monkeypatch: pytest.MonkeyPatch) -> None:
    assert [n.status for n in lanzon_checks.eq26_numbers()] == ["pass", "pass"]
    assert all(n.status == "pass" for n in lanzon_checks.eq26_jacobian_numbers())
    _no_linearisation(monkeypatch)
    assert [n.status for n in lanzon_checks.eq26_numbers()] == ["differs", "differs"]
    # the Jacobian at 0 cannot tell: these rows are consistency checks, not scored
    jac = lanzon_checks.eq26_jacobian_numbers()
    assert len(jac) == 13 and all(n.status == "pass" for n in jac)
    assert all("consistency" in n.note and n.kind == "consistency" and not n.scored for n in jac)


def test_eq26_rows_fail_with_a_wrong_model_term(monkeypatch: pytest.MonkeyPatch) -> None:
    """A gyroscopic coupling of the wrong sign in the RFL's model of the drift: off hover the
    closed loop is no longer (26)."""
    true_lie = LanzonVehicle.lie_terms
    monkeypatch.setattr(LanzonVehicle, "lie_terms", lambda self, x: true_lie(self, x) * np.array([1.0, 1.01, 1.0]))
    assert all(n.status == "differs" for n in lanzon_checks.eq26_numbers())


@pytest.fixture(scope="module")
def paper_design():  # type: ignore[no-untyped-def]
    return design()


def _row(numbers, word: str):  # type: ignore[no-untyped-def]
    (row,) = [n for n in numbers if word in n.quantity]
    return row


def test_loop_rows_measure_the_achieved_loop(paper_design) -> None:  # type: ignore[no-untyped-def]
    loop = lanzon_checks.achieved_loop(paper_design)
    numbers = lanzon_checks.loop_shape_numbers(paper_design)
    assert all("achieved loop G K" in n.quantity for n in numbers)
    # the achieved crossover is not the target the design was given (100 rad/s): measured 80.5
    assert loop.crossover_rad_s == pytest.approx(80.5, abs=0.5)
    assert _row(numbers, "crossover frequency").ours == loop.crossover_rad_s
    assert _row(numbers, "gain at 0.01").status == "pass"
    assert _row(numbers, "slope from crossover").status == "pass"
    # the central controller is strictly proper here: the achieved loop rolls off at -60, not -40
    assert loop.slope_high_db_dec == pytest.approx(-60.0, abs=0.5)
    # margins: the coprime-factor margin by frequency sweep is at least the guaranteed 1/gamma
    assert paper_design.stability_margin <= loop.stability_margin <= 1.0
    assert loop.sensitivity_peak > 1.0 and 0 < loop.phase_margin_deg < 90 and loop.gain_margin_db > 0


@pytest.mark.parametrize("crossover", [80.0, 150.0])
def test_another_crossover_fails_the_printed_row(crossover: float) -> None:
    row = _row(lanzon_checks.loop_shape_numbers(design(crossover_rad_s=crossover)), "crossover frequency")
    assert row.status == "differs", row


def test_another_low_gain_fails_the_printed_row() -> None:
    row = _row(lanzon_checks.loop_shape_numbers(design(low_gain_db=40.0)), "gain at 0.01")
    assert row.status == "differs", row


def test_the_report_scores_only_reproduced_rows(tmp_path: Path) -> None:
    from rotorfault.papers._report import ReportSection

    original = lanzon_report.report_section
    try:
        lanzon_report.report_section = lambda out, quick=False: ReportSection("lanzon-flights", "stub")  # type: ignore[assignment]
        section = lanzon_checks.report_section(tmp_path, quick=True)
    finally:
        lanzon_report.report_section = original  # type: ignore[assignment]
    # 2 eq. (26) closed-loop rows and 4 loop-shape rows scored (kind reproduced), the 13
    # Jacobian-at-0 entries beside them as consistency rows (not scored).
    assert score(section.numbers) == {"reproduced": 6, "passed": 4, "differs": 2, "input": 0, "consistency": 13, "unclassified": 0}
    assert all(n.kind == "consistency" for n in section.numbers if "consistency" in n.quantity)


# -- flights -----------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def short_runs() -> list[lanzon.LanzonRun]:
    return lanzon.three_way(duration_s=8.0, cases=[lanzon.design_case("b")])


def test_verdicts_cover_the_whole_flight(short_runs: list[lanzon.LanzonRun]) -> None:
    by = {(r.scenario.name, r.vehicle.inertia_zz_kg_m2): lanzon.flight_verdict(r) for r in short_runs}
    # Scenario A with the paper's limits sinks into the ground from 10 m: a crash, never a success
    assert by[("A", lanzon.IZZ_PRINTED)] == "crashed"
    assert by[("A", lanzon.IZZ_PROBABLE)] == "diverged"
    assert by[("B", lanzon.IZZ_PROBABLE)] == "diverged"


def test_only_the_attitude_outcomes_are_judged_by_the_paper() -> None:
    """Scenario A's ``level`` / ``not-level`` are this paper's question; every position outcome
    and divergence kind gets the verdict of ``flight.outcomes`` (one table, not a copy here)."""
    from types import SimpleNamespace
    from typing import get_args

    from rotorfault._typing import DivergenceKind, FlightOutcome
    from rotorfault.flight.outcomes import verdict_of

    def verdict(outcome: str) -> str:
        return lanzon.flight_verdict(SimpleNamespace(outcome=outcome))  # type: ignore[arg-type]

    assert (verdict("level"), verdict("not-level")) == ("holds", "drifts")
    for outcome in get_args(FlightOutcome) + get_args(DivergenceKind):
        assert verdict(outcome) == verdict_of(outcome), outcome
    assert verdict("circling") == "circles" and verdict("tilt") == "diverged"


def test_claims_are_confirmed_only_when_the_flight_holds(short_runs: list[lanzon.LanzonRun]) -> None:
    claims = lanzon.flight_claims(short_runs)
    assert len(claims) == 4 and {c.where for c in claims} == {w for w, _ in lanzon.CLAIMS.values()}
    for c in claims:
        assert c.status == ("confirmed" if c.verdict == "holds" else "not confirmed")
        assert c.measurement and c.reason
    crashed = [c for c in claims if c.verdict == "crashed"]
    assert crashed and "hit the ground" in crashed[0].measurement
    lines = lanzon.claims_table(claims)
    assert len(lines) == 2 + len(claims) and "| verdict |" in lines[0]


def test_each_scenario_gets_its_own_paths_figure(short_runs: list[lanzon.LanzonRun], tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="one scenario per figure"):
        lanzon.plot_paths(short_runs, str(tmp_path / "mixed.png"))
    for name in ("A", "B"):
        fig = lanzon.plot_paths([r for r in short_runs if r.scenario.name == name], str(tmp_path / f"{name}.png"))
        assert f"scenario {name}" in fig._suptitle.get_text()  # type: ignore[union-attr]
        assert (tmp_path / f"{name}.png").stat().st_size > 0


def test_rotor_inertia_changes_the_verdict() -> None:
    """The paper prints no I_R: at the probable I_zz the paper's design holds Scenario B without
    the rotors' gyroscopic moment and is lost with ours (3e-5)."""
    points = lanzon.rotor_inertia_sweep((0.0, 3e-5), izz_values=(lanzon.IZZ_PROBABLE,), cases=("b",), duration_s=20.0)
    verdicts = {p.rotor_inertia_kg_m2: p.verdict for p in points}
    assert verdicts == {0.0: "holds", 3e-5: "diverged"}
    (change,) = lanzon.verdict_changes(points)
    assert "holds at I_R = 0 -> diverged at 3e-05" in change
    table = lanzon.sweep_table(points)
    assert table[2].endswith("| holds | diverged |")


def test_verdict_changes_and_the_sweep_figure(tmp_path: Path) -> None:
    from rotorfault.plotting.verdicts import plot_verdict_sweep

    pts = [lanzon.SweepPoint(1e-3, "c", ir, v, "") for ir, v in ((0.0, "holds"), (1e-5, "holds"), (2e-5, "circles"))]
    assert lanzon.verdict_changes(pts) == ["I_zz = 0.001, case (c): holds at I_R = 1e-05 -> circles at 2e-05"]
    rows = [{"I_zz": p.inertia_zz_kg_m2, "case": p.case, "I_R": p.rotor_inertia_kg_m2, "verdict": p.verdict} for p in pts]
    plot_verdict_sweep(rows, str(tmp_path / "s.png"), parameter="I_R", parameter_label="I_R (kg m^2)", series="case",
                       panel="I_zz", title="t")
    assert (tmp_path / "s.png").stat().st_size > 0
    with pytest.raises(ValueError, match="verdicts"):
        plot_verdict_sweep([{**rows[0], "verdict": "survived"}], None, parameter="I_R", parameter_label="x", series="case",
                           panel="I_zz", title="t")


def test_the_eq26_region_covers_the_papers_flights() -> None:
    """The paper's design (cases a and b), both scenarios and I_zz, 60 s: every state flown (up to
    0.5 s before a loss) lies inside the region the scored eq. (26) rows sample."""
    runs = lanzon.three_way(cases=[lanzon.design_case("a"), lanzon.design_case("b")])
    half = np.asarray(lanzon_checks.EQ26_STATE_HALF_WIDTH)
    for run in runs:
        tr = run.trajectory
        keep = tr.t < tr.t[-1] - 0.5 if tr.diverged else np.ones(len(tr.t), dtype=bool)
        paper = np.array([LanzonVehicle.paper_state(x) for x in np.column_stack([
            tr.position, tr.velocity, tr.euler, tr.omega])[keep]])
        hat = np.column_stack([paper[:, 0], paper[:, 1], paper[:, 3], paper[:, 4], paper[:, 5] - run.vehicle.spin_rate_rad_s])
        assert np.all(np.abs(hat) <= half), (run.title, np.max(np.abs(hat), axis=0))

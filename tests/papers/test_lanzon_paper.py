"""Lanzon et al.'s two flights (rotorfault.papers.lanzon): the scenarios against Tables 2 and 3, the
windowed verdicts, the three-way comparison's key measurements with stated bounds, a small Monte
Carlo batch, the report directory and the ``lanzon-report`` CLI."""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

import rotorfault as rf
from rotorfault.cli import cli
from rotorfault.control import lanzon as L
from rotorfault.papers import lanzon as P, lanzon_report as R


def test_scenarios_are_tables_2_and_3() -> None:
    a, b = P.scenarios()
    q = math.pi / 4
    # Table 2: phi, theta, psi, p, q, r; Table 3 adds x, y, z = 5 m (z up) at rest.
    # (the State stores a quaternion: angles come back to within a few ulp)
    np.testing.assert_allclose(L.LanzonVehicle.paper_state(a.initial_state().vector())[:6],
                               [-q, q, q, -0.5, 0.5, 2.7], rtol=0, atol=1e-15)
    np.testing.assert_allclose(L.LanzonVehicle.paper_state(b.initial_state().vector()),
                               [0.075, 0.025, 0.1, 0.03, 0.02, 2.7, 5, 5, 5, 0, 0, 0], atol=1e-15)
    assert a.position is None and b.position == (0.0, 0.0, -1.0)  # z = 1 m up
    assert a.duration_s == b.duration_s == 60.0
    assert [c.label for c in P.design_cases()] == ["a", "b", "c"]
    assert [c.limits for c in P.design_cases()] == [False, True, True]
    with pytest.raises(ValueError, match="scenario: unknown 'C'"):
        P.scenario("C")
    with pytest.raises(ValueError, match="case: unknown 'd'"):
        P.design_case("d")


@pytest.fixture(scope="module")
def runs_printed() -> dict[tuple[str, str], P.LanzonRun]:
    """Scenario A (20 s) and B (60 s) with (b) and (c), Table 1's printed I_zz."""
    out = {}
    v = L.LanzonVehicle()
    for label in ("b", "c"):
        case = P.design_case(label)
        d = case.design(v)
        out[("A", label)] = P.fly("A", case, vehicle=v, designed=d, duration_s=20.0, record_every=20)
        out[("B", label)] = P.fly("B", case, vehicle=v, designed=d, record_every=20)
    return out


def test_our_design_flies_both_scenarios_with_the_limits(runs_printed: dict[tuple[str, str], P.LanzonRun]) -> None:
    a, b = runs_printed[("A", "c")], runs_printed[("B", "c")]
    # Scenario A from 10 m up (Table 2 prints no position): the inner loop alone sinks 26 m
    # before it levels, so it hits the ground at 4.10 s (issue #28).
    assert a.outcome == "crashed" and a.lost_at_s == pytest.approx(4.104, abs=1e-3)
    assert -a.trajectory.position[0, 2] == P.SCENARIO_A_HEIGHT_M and a.trajectory.position[-1, 2] < 1e-9
    # Without the ground the same flight is level (tilt < 1 deg, spin within 10 % of
    # m g d / k_r = 2.7 rad/s) by 20 s, 25 m lower.
    sim = a.vehicle.simulator(limits=a.case.limits, ground=False)
    controller = L.LanzonController(a.design, position=None, outer_loop=a.case.outer_loop)
    free = sim.run(a.scenario.initial_state(), 20.0, controller=controller, faults=[rf.RotorFault(2, 0.0)], record_every=20)
    attitude = P.attitude_metrics(free, a.vehicle.spin_rate_rad_s)
    assert attitude.outcome == "level", attitude
    assert attitude.level_after_s is not None and attitude.level_after_s < 16.0
    assert abs(attitude.window_spin_rad_s - 2.7) < 0.27  # type: ignore[operator]
    assert attitude.max_altitude_loss_m is not None and attitude.max_altitude_loss_m > 2 * P.SCENARIO_A_HEIGHT_M  # 25.3 m
    # Scenario B: holds the setpoint, within 1 cm at 60 s; thrusts inside the limits.
    assert b.outcome == "holds-position"
    assert b.final_error_m is not None and b.final_error_m < 0.01
    assert b.trajectory.rotor_thrust.min() >= 0.0 and b.trajectory.rotor_thrust.max() <= 5.0
    assert np.all(b.trajectory.rotor_thrust[:, 1] == 0.0)  # rotor 2 is dead


def test_paper_design_with_limits_never_settles_in_scenario_b(runs_printed: dict[tuple[str, str], P.LanzonRun]) -> None:
    # The finding of the three-way table (printed I_zz): (b) stays up but does not reach the
    # setpoint within 60 s (measured: circling it on a shrinking circle, 0.31-0.49 m off and 2-3.4
    # deg of tilt over the last 5 s, mean speed 0.45 m/s, just under Ke's 0.5 m/s "circling"
    # threshold); (c) does (test above).
    b = runs_printed[("B", "b")]
    assert not b.trajectory.diverged
    assert b.final_error_m is not None and b.final_error_m > 0.1
    assert P.tilt_deg(b.trajectory)[-int(5 / (20e-3)):].max() > 1.0
    # Still moving round the set point at the end (not settled, whatever the verdict's threshold):
    assert b.position is not None and b.position.window_mean_horizontal_speed_m_s > 0.3


def test_attitude_verdict_of_a_lost_run() -> None:
    v = L.LanzonVehicle(inertia_zz_kg_m2=P.IZZ_PROBABLE)
    run = P.fly("B", "b", vehicle=v, duration_s=5.0, record_every=20)
    # Measured: lost (tilt) at about 1.5-2.1 s with the probable I_zz (the gyroscopic moment).
    assert run.lost_at_s is not None and run.lost_at_s < 5.0
    assert run.outcome in ("tilt", "body-rate", "altitude-loss", "speed")
    assert run.final_error_m is None
    assert P.outcome_text(run.outcome, run.lost_at_s).startswith(f"lost ({run.outcome}) at ")


def test_monte_carlo_small_batch() -> None:
    # 50 runs of design (c), 20 s, +-20 % on mass, inertias, k_r, I_R, 15 dB noise.
    result = P.monte_carlo("lanzon", runs=50, duration_s=20.0, seed=3)
    assert result.runs == 50 and len(result.outcomes) == 50
    assert result.factors.shape == (50, 5)
    assert result.factors.min() >= 0.8 and result.factors.max() <= 1.2
    assert 0.0 <= result.held_fraction <= 1.0
    again = P.monte_carlo("lanzon", runs=4, duration_s=20.0, seed=3)
    assert again.outcomes == result.outcomes[:4]  # reproducible: run i uses seed + i
    np.testing.assert_array_equal(again.final_error_m, result.final_error_m[:4])
    with pytest.raises(ValueError, match="controller: expected 'lanzon' or 'ke'"):
        P.monte_carlo("pid", runs=1)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="spread: must lie in"):
        P.monte_carlo(runs=1, spread=1.5)
    with pytest.raises(ValueError, match="runs: must be >= 1"):
        P.monte_carlo(runs=0)


def test_report_directory(tmp_path: Path, runs_printed: dict[tuple[str, str], P.LanzonRun]) -> None:
    runs = list(runs_printed.values())
    mc = P.monte_carlo("lanzon", runs=2, duration_s=2.0)
    out = tmp_path / "report"
    path = R.write_report(runs, out, monte_carlo_results=[mc], command="test")
    text = path.read_text(encoding="utf-8")
    assert "| 0.00116 | (c) our design (30 rad/s), paper's limits |" in text
    rows = list(csv.DictReader((out / "lanzon-report.csv").read_text(encoding="utf-8").splitlines()))
    assert len(rows) == 4 and {r["case"] for r in rows} == {"b", "c"}
    assert len(list(csv.DictReader((out / "monte-carlo.csv").read_text(encoding="utf-8").splitlines()))) == 2
    manifest = json.loads((out / "manifest.json").read_text(encoding="utf-8"))
    for name in ("A-c-izz-0.00116.png", "B-b-izz-0.00116.png", "paths-3d.png", "loop-shape-b.png", "loop-shape-c.png"):
        assert name in manifest["outputs"]
        assert (out / name).stat().st_size > 10_000
    with pytest.raises(ValueError, match="holds a previous output; pass --force"):
        R.write_report(runs, out)


def test_cli_lanzon_report_checks_before_flying(tmp_path: Path) -> None:
    (tmp_path / "busy").mkdir()
    (tmp_path / "busy" / "notes.txt").write_text("mine")
    result = CliRunner().invoke(cli, ["lanzon-report", "--out", str(tmp_path / "busy"), "--quick"])
    assert result.exit_code == 1
    assert "is not empty and holds no manifest.json" in result.output
    result = CliRunner().invoke(cli, ["lanzon-report", "--out", str(tmp_path / "r"), "--runs", "-1"])
    assert result.exit_code == 1 and "runs: must be >= 0" in result.output


def test_cli_lanzon_report_quick(tmp_path: Path) -> None:
    out = tmp_path / "r"
    result = CliRunner().invoke(cli, ["lanzon-report", "--out", str(out), "--quick", "--runs", "2", "--no-figures"])
    assert result.exit_code == 0, result.output
    text = (out / "lanzon-report.md").read_text(encoding="utf-8")
    assert text.count("| 0.00116 | (") == 3 and text.count("| 0.0116 | (") == 3
    assert "Ke uniform passive FTC" in text
    again = CliRunner().invoke(cli, ["lanzon-report", "--out", str(out), "--quick", "--runs", "0", "--no-figures"])
    assert again.exit_code == 1 and "pass --force" in again.output
    again = CliRunner().invoke(cli, ["lanzon-report", "--out", str(out), "--quick", "--runs", "0", "--no-figures", "--force"])
    assert again.exit_code == 0, again.output


def test_lanzon_names_are_exported_lazily() -> None:
    import rotorfault.control as control

    assert control.LanzonController is L.LanzonController
    assert callable(control.ncfsyn)
    assert rf.LanzonController is L.LanzonController
    assert rf.ncfsyn is control.ncfsyn

"""Lanzon's and Wang's flights on the truth (or the paper's noise) and on motion capture with the
estimator, side by side: which designs survive realistic sensing (issue 29). Both papers fly at
1 kHz, so the IMU runs at 1 kHz too (an ICM-42688-P output data rate); measured numbers are in
the docstrings."""

from __future__ import annotations

import pytest

import rotorfault as rf
from rotorfault.papers import lanzon, lanzon_report, wang

MOCAP_1KHZ = rf.Sensing(imu_rate_hz=1000.0)


@pytest.mark.parametrize(("scenario", "case"), [("B", "a"), ("B", "c")])
def test_lanzon_keeps_its_verdict_on_mocap(scenario: str, case: str) -> None:
    """Measured (final error truth / mocap): B-a holds 0.000 / 0.002 m; B-c holds 0.003 / 0.010 m."""
    truth = lanzon.fly(scenario, case)
    sensed = lanzon.fly(scenario, case, sensing=MOCAP_1KHZ)
    assert sensed.trajectory.sensed == "mocap"
    assert sensed.outcome == truth.outcome, (truth.outcome, sensed.outcome)
    if truth.outcome == "holds-position":
        assert sensed.final_error_m is not None and sensed.final_error_m < 0.05


def test_lanzon_design_b_in_scenario_b_is_marginal_and_mocap_tips_it_into_circling() -> None:
    """Design (b), Scenario B, with the install-independent 11-state synthesis (issue 25) holds
    on the truth, barely (README: 0.403 m); on mocap the estimate's delay and noise tip it into
    circling. Both verdicts are measured, and the report's side by side shows "differs"."""
    truth = lanzon.fly("B", "b")
    sensed = lanzon.fly("B", "b", sensing=MOCAP_1KHZ)
    assert (truth.outcome, sensed.outcome) == ("holds-position", "circling")


def test_lanzon_design_a_in_scenario_a_is_lost_on_mocap() -> None:
    """Design (a) in Scenario A (the spinning vehicle levelling from a tilt) levels on the truth
    and is lost on 1 kHz mocap (seed 0: crashed). The case is marginal on sensors: over seeds 0-5,
    1 kHz mocap gave crashed 1, tilt 2, level 3 and the IMU at 500 Hz crashed 2, tilt 1, level 3
    (with the covariance in 10 ms blocks; with 5 ms blocks 1 kHz gave tilt 4, body-rate 1, level 1
    and 500 Hz level 3, tilt 1, body-rate 1, crashed 1, seed 0 tilting at 1 kHz and levelling at
    500 Hz; before the estimator fused at most one fix per 10 ms, seed 0 levelled at 1 kHz)."""
    assert lanzon.fly("A", "a").outcome == "level"
    assert lanzon.fly("A", "a", sensing=MOCAP_1KHZ).outcome == "crashed"


@pytest.mark.parametrize("number", [1, 2, 3])
def test_wang_lqr_flies_on_mocap(number: int) -> None:
    """Wang's LQR on the VPP quadcopter with propeller 1 failed: not lost on mocap, its late
    position error within 5 cm of the truth run's (scenarios 1 and 3; 0.295 / 0.295 m and 1.688 /
    1.683 m measured) and, in scenario 2, below the paper's 15 dB noise run (0.047 against 0.158 m
    measured: realistic sensing is kinder than 15 dB on every state)."""
    paper = wang.fly(number)
    sensed = wang.fly(number, sensing=MOCAP_1KHZ)
    assert sensed.trajectory.sensed == "mocap" and sensed.lost_at_s is None
    if number == 2:
        assert paper.trajectory.sensed == "paper-noise"
        assert sensed.max_error_after_s < paper.max_error_after_s
    else:
        assert abs(sensed.max_error_after_s - paper.max_error_after_s) < 0.05


def test_lanzon_report_table_flags_a_verdict_that_sensing_changes() -> None:
    # Previous test: A-a crashes on 1 kHz mocap with seed 0 and levels with seed 1.
    truth = [lanzon.fly("A", "a")]
    lost = lanzon_report.sensing_table(truth, [lanzon.fly("A", "a", sensing=lanzon.MOCAP_AT_LOOP_RATE)])
    same = lanzon_report.sensing_table(truth, [lanzon.fly("A", "a", sensing=rf.Sensing(imu_rate_hz=1000.0, seed=1))])
    assert lost.rows[0][3:6] == ("level", "crashed", "differs")
    assert same.rows[0][3:6] == ("level", "level", "same")

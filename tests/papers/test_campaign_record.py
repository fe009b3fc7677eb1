"""The committed record of the full deciding campaign (issue 30) against the code: it reads as a
bench result, its cells are the suite's cells, its decision adds up, and a record that no longer
matches (a cell dropped, a count off) is refused."""

from __future__ import annotations

import copy

import numpy as np
import pytest

import rotorfault as rf
from rotorfault.papers import campaign as C
from rotorfault.papers import reproduce
from rotorfault.studies import deciding as D


@pytest.mark.parametrize("name", [C.RECORD, C.SENSED_RECORD])
def test_the_record_matches_the_suite_and_reads_as_a_bench_result(name: str) -> None:
    data = C.recorded_full_run(name)
    run = data["campaign"]
    suite = D.DecidingCampaign.from_dict(run["suite"])
    assert suite.runs == C.FULL_RUNS and suite.cells == D.DecidingCampaign(runs=C.FULL_RUNS).cells
    assert suite.sensing == (None if name == C.RECORD else rf.Sensing())
    assert len(run["cells"]) == len(suite.cells) == 65 and len(run["decision"]) == 13
    assert name in {b.file for b in reproduce.bench_results(reproduce.default_bench_directory())}
    # Every cell that misses the target has its measurement and a written reason.
    missed = {(d["vehicle"], d["fault_class"]) for d in run["decision"] if d["survivable"] and D.target_verdict(d) != "met"}
    assert missed == {(m["vehicle"], m["fault_class"]) for m in run["misses"]}
    assert all(m.get("why") for m in run["misses"])


@pytest.mark.parametrize(
    ("break_it", "message"),
    [
        (lambda r: r["cells"].pop(3), "not the suite's cells"),
        (lambda r: r["cells"][0].update(held=r["cells"][0]["runs"] + 1), "counts do not add up"),
        (lambda r: r["decision"][0].update(spinning=r["decision"][0]["spinning"] + 1), "counts do not add up"),
        (lambda r: r["decision"][1].update(share=0.5 if r["decision"][1]["share"] != 0.5 else 0.25), "share"),
        (lambda r: r.pop("certified"), "certified"),
    ],
)
def test_a_record_that_does_not_match_is_refused(break_it: object, message: str) -> None:
    data = copy.deepcopy(C.recorded_full_run())
    break_it(data["campaign"])  # type: ignore[operator]
    with pytest.raises(ValueError, match=message):
        C.check_record(data)


def test_the_sensed_records_comparison_is_the_truth_records_held_runs_cell_for_cell() -> None:
    """The paired comparison against the truth adds up to both records' held counts: the runs held
    on the truth (both + truth only) are the truth record's, those held on sensors its own."""
    truth = {(c["vehicle"], c["fault_class"], c["controller"]): c for c in C.recorded_full_run()["campaign"]["cells"]}
    sensed = C.recorded_full_run(C.SENSED_RECORD)["campaign"]
    for r in sensed["against_truth"]:
        t = truth[(r["vehicle"], r["fault_class"], r["controller"])]
        assert r["both"] + r["truth_only"] == t["held"] and r["runs"] == t["runs"]
    # A missed run the best controller holds on the truth is one of its runs held on the truth only.
    by_cell = {(r["vehicle"], r["fault_class"], r["controller"]): r for r in sensed["against_truth"]}
    for m in sensed["misses"]:
        assert 0 <= m["held_on_truth"] <= min(m["missed"], by_cell[(m["vehicle"], m["fault_class"], m["controller"])]["truth_only"])


def test_the_run_for_run_comparison_counts_by_hand_and_refuses_rows_that_do_not_pair() -> None:
    """``benches/deciding_record.py``'s comparison on four hand-made rows of one cell: one held on
    both, one on each side only, one on neither; the spin past the gyro's range counted on the
    truth's rows only (a lost run's NaN spin is not past it); rows out of order are refused."""
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benches"))
    import deciding_record as R

    key = {"vehicle": np.array(["v"] * 4), "fault_class": np.array(["f"] * 4), "controller": np.array(["c"] * 4), "index": np.arange(4),
           "applicable": np.ones(4, dtype=bool)}
    sensed = {**key, "holds": np.array([True, False, True, False]), "hold_final_spin_rad_s": np.array([50.0, 50.0, 50.0, 50.0])}
    truth = {**key, "holds": np.array([True, True, False, False]), "hold_final_spin_rad_s": np.array([40.0, 36.0, np.nan, 50.0])}
    (row,) = R.against_truth(sensed, truth, 35.0)
    assert row == {"vehicle": "v", "fault_class": "f", "controller": "c", "runs": 4, "both": 1, "truth_only": 1, "sensed_only": 1,
                   "neither": 1, "truth_only_past_gyro_range": 1, "both_past_gyro_range": 1}
    (row,) = R.against_truth(sensed, truth, 38.0)
    assert (row["truth_only_past_gyro_range"], row["both_past_gyro_range"]) == (0, 1)
    with pytest.raises(SystemExit, match="not the sensed suite's"):
        R.against_truth(sensed, {**truth, "index": np.array([1, 0, 2, 3])}, 35.0)


@pytest.mark.parametrize(
    ("break_it", "message"),
    [
        (lambda r: r["against_truth"].pop(), "one row per cell"),
        (lambda r: r["against_truth"][3].update(both=r["against_truth"][3]["both"] + 1), "counts do not add up"),
        (lambda r: r["against_truth"][3].update(controller="other"), "comparison"),
        (lambda r: r["against_truth"][3].update(truth_only_past_gyro_range=r["against_truth"][3]["truth_only"] + 1), "counts do not add up"),
        (lambda r: r["suite"].pop("sensing"), "sensing"),
    ],
)
def test_a_sensed_record_that_does_not_match_is_refused(break_it: object, message: str) -> None:
    data = copy.deepcopy(C.recorded_full_run(C.SENSED_RECORD))
    break_it(data["campaign"])  # type: ignore[operator]
    with pytest.raises(ValueError, match=message):
        C.check_record(data, C.SENSED_RECORD)


def test_each_record_is_refused_under_the_others_name() -> None:
    with pytest.raises(ValueError, match="sensing"):
        C.check_record(copy.deepcopy(C.recorded_full_run(C.SENSED_RECORD)), C.RECORD)
    with pytest.raises(ValueError, match="sensing"):
        C.check_record(copy.deepcopy(C.recorded_full_run()), C.SENSED_RECORD)
    with pytest.raises(ValueError, match="name"):
        C.recorded_full_run("other.json")

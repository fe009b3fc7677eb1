"""The committed record of the full deciding campaign (issue 30) against the code: it reads as a
bench result, its cells are the suite's cells, its decision adds up, and a record that no longer
matches (a cell dropped, a count off) is refused."""

from __future__ import annotations

import copy

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
        assert r["both"] + r["truth_only"] == truth[(r["vehicle"], r["fault_class"], r["controller"])]["held"]


@pytest.mark.parametrize(
    ("break_it", "message"),
    [
        (lambda r: r["against_truth"].pop(), "one row per cell"),
        (lambda r: r["against_truth"][3].update(both=r["against_truth"][3]["both"] + 1), "counts do not add up"),
        (lambda r: r["against_truth"][3].update(controller="other"), "comparison"),
        (lambda r: r["suite"].pop("sensing"), "sensing"),
    ],
)
def test_a_sensed_record_that_does_not_match_is_refused(break_it: object, message: str) -> None:
    data = copy.deepcopy(C.recorded_full_run(C.SENSED_RECORD))
    break_it(data["campaign"])  # type: ignore[operator]
    with pytest.raises(ValueError, match=message):
        C.check_record(data, C.SENSED_RECORD)
    with pytest.raises(ValueError, match="sensing"):
        C.check_record(copy.deepcopy(C.recorded_full_run(C.SENSED_RECORD)), C.RECORD)

"""The controllability report is the core's class (issue 26: types cross the boundary once): it
carries the question asked, prints as it always did (the core's formatting, the one every ACAI
table uses), and compares, hashes, prints its fields and pickles like the dataclass it replaced."""

from __future__ import annotations

import math
import pickle

import hypothesis.strategies as st
import pytest
from hypothesis import given

import rotorfault as rf
from rotorfault import _rfcore
from rotorfault.analysis import acai_label, format_acai

#: str() of the outside case, as the Python dataclass printed it before the move (copied).
OUTSIDE_TEXT = """hexa-ppnnpn: efficiency = [1, 1, 1, 1, 1, 0], axes = thrust, roll, pitch, yaw
  rank C(A, B) = 8 of 8
  rank B_f     = 4 of 4
  ACAI eq13    = 0.0000* (eq. (13) prints 0 although the hover wrench lies outside the attainable set)
  verdict      = uncontrollable: hover wrench outside the attainable set"""


def test_the_report_is_the_cores_class_with_the_question_asked() -> None:
    frame = rf.Airframe.preset("hexa-ppnnpn").with_failed_rotors([6])
    report = rf.controllability(frame, give_up_yaw=True, formula="facet-margin")
    assert type(report) is _rfcore.ControllabilityReport is rf.ControllabilityReport
    assert report.airframe == frame.name and report.efficiency == (1.0,) * 5 + (0.0,)
    assert report.give_up_yaw and report.axes == "thrust-roll-pitch" and report.formula == "facet-margin"
    assert str(rf.controllability(frame)) == OUTSIDE_TEXT
    undefined = str(rf.controllability(rf.Airframe.preset("quad-x").with_failed_rotors([1, 2])))
    assert "efficiency = [0, 0, 1, 1]" in undefined and "ACAI eq13    = undefined (-inf)" in undefined


def test_the_report_compares_hashes_prints_and_pickles() -> None:
    frame = rf.Airframe.preset("hexa-pnpnpn")
    report = rf.controllability(frame, [1, 1, 1, 1, 1, 0.5])
    back = pickle.loads(pickle.dumps(report))
    assert back == report and hash(back) == hash(report) and repr(back) == repr(report) and str(back) == str(report)
    assert report != rf.controllability(frame) and report != "not a report"
    assert repr(report) == (
        "ControllabilityReport(airframe='hexa-pnpnpn', efficiency=(1.0, 1.0, 1.0, 1.0, 1.0, 0.5), give_up_yaw=False, "
        f"state_dimension=8, controllability_rank=8, virtual_control_dimension=4, effectiveness_rank=4, acai={report.acai!r}, "
        "formula='eq13', verdict='controllable', controllable=True, hover='inside', axes='thrust-roll-pitch-yaw')"
    )
    with pytest.raises(ValueError, match="^verdict: not a verdict"):
        _rfcore._controllability_report("x", [1.0], "wrench", 12, 12, 6, 6, 0.1, "eq13", "fine", "inside")


@given(st.floats(allow_nan=False), st.sampled_from(["inside", "boundary", "outside", "rank-deficient"]))
def test_the_cores_acai_format_is_pythons(value: float, hover: str) -> None:
    # The independent reading: the f-string the Python tables used before the formatting moved.
    expected = "undefined" if math.isinf(value) else (f"{value:.4f}*" if value >= 0.0 and hover == "outside" else f"{value:.4f}")
    assert format_acai(value, hover) == expected  # type: ignore[arg-type]


@given(st.floats(min_value=0.0, max_value=1.0).filter(lambda v: v == 0.0 or v >= 1e-300)
       | st.sampled_from([1e-5, 1e-4, 0.123456789, 0.99999951, 1 / 3]))
def test_efficiencies_print_as_pythons_general_format(value: float) -> None:
    frame = rf.Airframe.preset("quad-x")
    report = rf.controllability(frame, [value, 1.0, 1.0, 1.0])
    assert str(report).startswith(f"quad-x: efficiency = [{value:g}, 1, 1, 1], axes = ")


def test_acai_labels_name_the_formula() -> None:
    assert (acai_label("eq13"), acai_label("facet-margin")) == ("ACAI eq13", "ACAI facet-margin")

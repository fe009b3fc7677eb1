"""One name per concept (issue 26), checked where users meet it: the API, the CLI, tables.

- **Rotor numbering**: a rotor is *named* by its number from 1 everywhere (arguments, CLI flags,
  scan axis names, campaign failures, table rows, figure legends, messages); arrays with one
  entry per rotor (efficiency, thrust bounds, commands, recorded thrusts) are in rotor order, so
  entry ``[i]`` is rotor ``i + 1``. Never a 0.
- **Giving up yaw**: ``give_up_yaw`` / ``--give-up-yaw`` / ``..._give_up_yaw`` / "give-up-yaw" in
  headers; the old ``..._without_yaw`` attributes warn for one release.
- **The two ACAI formulas**: every printed ACAI names its formula (``ACAI eq13``, ``ACAI
  facet-margin``).
- **The core's names are the public ones**: a run's divergence is a ``Divergence`` with its
  ``kind`` (``DivergenceKind``) in Rust as in Python, and the core's ``Trajectory`` records
  ``rotor_command``, ``rotor_thrust_n`` and ``recorded_measurements`` (the unit in the Rust name,
  as ``t_s`` beside Python's ``t``).
"""

from __future__ import annotations

import json
import math
import re
from pathlib import Path
from typing import Any, get_args

import numpy as np
import pytest
from click.testing import CliRunner

import rotorfault as rf
from rotorfault.cli import cli


@pytest.fixture(scope="module")
def hexa() -> rf.Airframe:
    return rf.Airframe.preset("hexa-ppnnpn")


@pytest.fixture(autouse=True)
def _wide_console() -> object:
    """Tables wide enough that no header wraps (the console is shared by every test)."""
    from rotorfault.cli import console

    old = console.width
    console.width = 200
    yield
    console.width = old


# -- rotor numbering -------------------------------------------------------------------------------


def test_api_rotor_k_is_array_entry_k_minus_1(hexa: rf.Airframe) -> None:
    for k in range(1, hexa.rotor_count + 1):
        failed = hexa.with_failed_rotors([k]).efficiency
        assert failed[k - 1] == 0.0 and np.sum(failed == 0.0) == 1
        eff = np.ones(hexa.rotor_count)
        eff[k - 1] = 0.0
        assert rf.failure_table(hexa).case(k).acai == rf.acai(hexa, eff)


def test_api_a_fault_on_rotor_k_shows_in_column_k_minus_1() -> None:
    quad = rf.Airframe.preset("quad-x")
    run = rf.Simulator(quad, dt_s=0.01).run(rf.State(position=(0, 0, -10)), 0.05, faults=[rf.RotorFault(3, 0.02, 0.5)])
    assert run.efficiency[0].tolist() == [1, 1, 1, 1] and run.efficiency[-1].tolist() == [1, 1, 0.5, 1]


def test_api_scans_and_campaigns_name_rotors_from_1(hexa: rf.Airframe) -> None:
    scan = rf.efficiency_scan(hexa, rotors=(1,), step=0.5)
    base = np.ones(hexa.rotor_count)
    for level, value in zip(scan.levels, scan.acai):
        base[0] = level
        assert value == rf.acai(hexa, base)
    table = rf.acai_scan(hexa, samples={"efficiency_1": [0.0]}, formulas=("eq13",)).table
    assert table["acai_eq13"].to_pylist() == [rf.failure_table(hexa).case(1).acai]
    from rotorfault.studies import Campaign

    spec = Campaign(runs=1, failures=((2,),)).sample(0)
    assert [f.rotor for f in spec.faults()] == [2]


@pytest.mark.parametrize("bad", [0, 7])
def test_api_refuses_a_rotor_number_outside_1_to_m(hexa: rf.Airframe, bad: int) -> None:
    with pytest.raises(ValueError, match="rotor numbers run from 1 to 6"):
        hexa.with_failed_rotors([bad])
    with pytest.raises(ValueError, match="rotor numbers run from 1 to 6"):
        rf.efficiency_scan(hexa, rotors=(bad,), step=0.5)


def test_cli_rows_and_flags_name_rotors_from_1() -> None:
    runner = CliRunner()
    table = runner.invoke(cli, ["failures", "-a", "hexa-ppnnpn", "--formula", "facet-margin"])
    assert table.exit_code == 0, table.output
    row = next(line for line in table.output.splitlines() if line.startswith("5 "))  # plain text: not a terminal
    one = runner.invoke(cli, ["acai", "-a", "hexa-ppnnpn", "--efficiency", "1,1,1,1,0,1", "--formula", "facet-margin"])
    value = next(line for line in one.output.splitlines() if "ACAI facet-margin" in line).split()[-1]
    assert value in row  # rotor 5 failed is efficiency entry 5 (index 4) at 0
    bad = runner.invoke(cli, ["scan", "-a", "hexa-pnpnpn", "--rotors", "0,1,2", "--step", "0.5"])
    assert bad.exit_code == 1 and "rotor numbers run from 1 to 6" in bad.output


def test_figures_label_rotors_from_1() -> None:
    quad = rf.Airframe.preset("quad-x")
    run = rf.Simulator(quad, dt_s=0.01).run(rf.State(position=(0, 0, -10)), 0.05)
    fig = run.plot()
    labels = [t.get_text() for t in fig.axes[-1].get_legend().get_texts()]
    assert labels == ["rotor 1", "rotor 2", "rotor 3", "rotor 4"]


# -- giving up yaw ---------------------------------------------------------------------------------


def test_failure_rows_say_give_up_yaw_and_the_old_names_warn(hexa: rf.Airframe) -> None:
    row = rf.failure_table(hexa).case(1)
    assert row.acai_give_up_yaw == rf.acai(hexa.with_failed_rotors([1]), give_up_yaw=True)
    for old, new in (("acai_without_yaw", "acai_give_up_yaw"), ("controllable_without_yaw", "controllable_give_up_yaw"),
                     ("effectiveness_rank_without_yaw", "effectiveness_rank_give_up_yaw"),
                     ("verdict_without_yaw", "verdict_give_up_yaw"), ("hover_without_yaw", "hover_give_up_yaw")):
        with pytest.warns(DeprecationWarning, match=f"FailureCase.{old} is deprecated.*FailureCase.{new}"):
            assert getattr(row, old) == getattr(row, new)
    assert all(key.endswith("give_up_yaw") for key in type(row).FIELDS if "yaw" in key)


def test_the_certificate_says_give_up_yaw() -> None:
    result = CliRunner().invoke(cli, ["certify", "-a", "hexa-ppnnpn", "--json", "-"])
    cases = json.loads(result.output)["cases"]
    assert {c["hover"] for c in cases} <= {"all-axes", "give-up-yaw", "no"} and any(c["hover"] == "give-up-yaw" for c in cases)
    assert all("acai_give_up_yaw" in c and "acai_without_yaw" not in c for c in cases)
    from rotorfault.studies.certify import certify

    case = certify(rf.Airframe.preset("hexa-ppnnpn")).cases[1]
    with pytest.warns(DeprecationWarning, match="acai_give_up_yaw"):
        assert case.acai_without_yaw == case.acai_give_up_yaw


def test_tables_say_give_up_yaw_never_no_yaw(hexa: rf.Airframe) -> None:
    headers, _ = rf.failure_table(hexa).rows_for_display()
    assert headers[6:9] == ["ACAI eq13 give-up-yaw", "hover wrench give-up-yaw", "ok give-up-yaw"]
    out = CliRunner().invoke(cli, ["failures", "-a", "hexa-ppnnpn"]).output
    assert "give-up-yaw" in out and "no-yaw" not in out and "without yaw" not in out


# -- the ACAI formulas, named wherever an ACAI is printed ------------------------------------------


@pytest.mark.parametrize("formula", ["eq13", "facet-margin"])
def test_every_printed_acai_names_its_formula(hexa: rf.Airframe, formula: str) -> None:
    runner = CliRunner()
    for args in (["acai", "-a", "hexa-ppnnpn"], ["failures", "-a", "hexa-ppnnpn"],
                 ["scan", "-a", "hexa-pnpnpn", "--rotors", "1,2,5", "--step", "0.5"]):
        out = runner.invoke(cli, [*args, "--formula", formula]).output
        assert f"ACAI {formula}" in out, (args, out)
        assert "ACAI " + ("facet-margin" if formula == "eq13" else "eq13") not in out, (args, out)
    assert f"ACAI {formula}" in str(rf.controllability(hexa, formula=formula))  # type: ignore[arg-type]
    headers, _ = rf.failure_table(hexa, formula=formula).rows_for_display()  # type: ignore[arg-type]
    assert [h for h in headers if h.startswith("ACAI")] == [f"ACAI {formula}", f"ACAI {formula} give-up-yaw"]


def test_the_certificate_and_the_design_search_name_theirs() -> None:
    runner = CliRunner()
    cert = runner.invoke(cli, ["certify", "-a", "hexa-ppnnpn"]).output
    assert "ACAI facet-margin" in cert
    design = runner.invoke(cli, ["design", "-a", "hexa-pnpnpn", "--top", "1"]).output
    assert "(ACAI facet-margin)" in design and "worst single-failure ACAI facet-margin" in design


def test_the_du_report_rows_name_eq13() -> None:
    from rotorfault.papers import du

    assert all(n.quantity.startswith("ACAI eq13, ") for n in du.printed_numbers())
    assert not math.isnan(du.printed_numbers()[0].ours)


# -- flight verdicts: one table of words, for every paper and study ----------------------------------


@pytest.mark.parametrize("preset", ["hexa-ppnnpn", "hexa-pnpnpn"])
def test_certify_the_failures_table_and_the_report_say_the_same_of_each_case(preset: str, du_tables: list[Any]) -> None:
    """Issue 28: for the same case, the failure table (``rotorfault failures``), the certificate
    and Du's report table print the same words for the hover wrench (inside, boundary, outside
    with the same distance), with all axes and giving up yaw."""
    from rotorfault.allocation import hover_distances
    from rotorfault.studies.certify import certify, rows_for_display

    frame = rf.Airframe.preset(preset)
    table = rf.failure_table(frame, max_failed=2)
    headers, rows = table.rows_for_display(hover_distances(frame, [case.failed for case in table]))
    columns = [headers.index("hover wrench"), headers.index("hover wrench give-up-yaw")]
    failures = {row[0]: [row[k] for k in columns] for row in rows}
    cert_headers, cert_rows = rows_for_display(certify(frame))
    cert_columns = [cert_headers.index("hover wrench"), cert_headers.index("hover wrench give-up-yaw")]
    certified = {row[0]: [row[k] for k in cert_columns] for row in cert_rows}
    assert failures == certified
    assert any(cells[0] == "boundary" for cells in failures.values()) or any(cells[0].startswith("outside ") for cells in failures.values())
    if preset == "hexa-ppnnpn":
        assert failures["5"] == ["outside 0.2133", "inside"]
    else:
        assert all(failures[str(k)] == ["boundary", "inside"] for k in range(1, 7))
    report_tables = [t for t in du_tables if t.caption.startswith(f"{preset}:")]
    assert len(report_tables) == 1
    report = {row[0]: [row[k] for k in columns] for row in report_tables[0].rows}
    assert report == failures


@pytest.fixture(scope="module")
def du_tables(tmp_path_factory: pytest.TempPathFactory) -> list[Any]:
    """Du's report section's failure tables (built with the Fig. 4 scan at its quick step)."""
    from rotorfault.papers import du as du_paper

    return list(du_paper.report_section(tmp_path_factory.mktemp("du"), quick=True).tables)


def test_every_paper_labels_flights_with_the_one_verdict_table() -> None:
    from rotorfault.flight import outcomes
    from rotorfault.papers import ke as ke_paper
    from rotorfault.papers import lanzon as lanzon_paper

    assert ke_paper.OUTCOME_LABELS is outcomes.OUTCOME_LABELS and ke_paper.flight_metrics is outcomes.flight_metrics
    assert lanzon_paper.outcome_text is outcomes.outcome_text and lanzon_paper.flight_metrics is outcomes.flight_metrics
    assert outcomes.outcome_text("holds-position") == "holds position" and outcomes.outcome_text("not-level") == "not level"
    assert outcomes.outcome_text("tilt", 1.5) == "lost (tilt) at 1.50 s"
    from rotorfault.studies.summaries import FLYING

    assert FLYING == outcomes.FLYING == ("holds-position", "circling", "off-station")
    # The one verdict (issue 28) and the codes before it, kept for one release.
    assert outcomes.VERDICTS == ("holds", "drifts", "circles", "crashed", "diverged")
    assert [outcomes.verdict_of(c) for c in ("holds-position", "circling", "off-station", "crashed", "tilt", "step-size")] == [
        "holds", "circles", "drifts", "crashed", "diverged", "diverged"]
    assert set(outcomes.VERDICT_MEANINGS) == set(outcomes.VERDICTS)


def _pub_fields(source: str, struct: str) -> list[str]:
    body = re.search(r"pub struct " + struct + r" \{(.*?)\n\}", source, re.S)
    assert body, struct
    return re.findall(r"^\s*pub (\w+):", body.group(1), re.M)


def test_the_core_names_a_divergence_and_a_trajectory_as_python_does() -> None:
    from rotorfault._typing import DivergenceKind

    core = Path(__file__).resolve().parents[2] / "crates" / "rfcore" / "src"
    divergence = (core / "flight" / "simulation" / "divergence.rs").read_text(encoding="utf-8")
    assert _pub_fields(divergence, "Divergence") == list(rf.Divergence.FIELDS)
    kinds = re.search(r"pub fn name\(self\) -> &'static str \{(.*?)\n    \}", divergence, re.S)
    assert "pub enum DivergenceKind {" in divergence and kinds
    assert tuple(re.findall(r'=> "([a-z-]+)"', kinds.group(1))) == get_args(DivergenceKind)
    assert not [f for f in core.rglob("*.rs") if "DivergenceReason" in f.read_text(encoding="utf-8")]
    recording = (core / "flight" / "simulation" / "recording.rs").read_text(encoding="utf-8")
    # The rows Python splits into columns (states) or sensing fields (sensing) have no one name there.
    rust = [re.sub(r"_(s|n)$", "", f) for f in _pub_fields(recording, "Trajectory") if f not in ("states", "sensing")]
    assert rust == ["t", "rotor_command", "rotor_thrust", "efficiency", "recorded_measurements", "divergence"]
    assert set(rust) <= set(rf.Trajectory.FIELDS)

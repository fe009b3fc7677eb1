"""The deciding campaign's part of ``rotorfault reproduce`` (issue 30): the table vehicle x fault
class x controller (hold share, worst deviation, spin rate), the best controller per vehicle and
fault class against the 95 % target, and how many runs stand behind each cell. Computed by
:mod:`rotorfault.studies.deciding`, the same code as ``rotorfault campaign --suite deciding``."""

from __future__ import annotations

import json
import math
import time
from importlib import resources
from pathlib import Path
from typing import Any

from ._report import ReportSection, ReportTable

#: Runs per cell: the full report (the issue's 1,000) and ``--quick`` (a smoke test of the table).
FULL_RUNS = 1000
QUICK_RUNS = 6
#: The recorded full run (``benches/deciding_record.py``): shown beside the live table, labelled.
RECORD = "deciding_full_run.json"
#: The same suite flown on the motion-capture sensors and the estimator (``--sensing mocap``), with
#: its paired comparison against :data:`RECORD` (the same draws flown on the truth).
SENSED_RECORD = "deciding_full_run_mocap.json"
AGAINST_TRUTH_KEYS = ("vehicle", "fault_class", "controller", "runs", "both", "truth_only", "sensed_only", "neither",
                      "truth_only_past_gyro_range", "both_past_gyro_range")
RECORD_CELL_KEYS = ("vehicle", "fault_class", "controller", "runs", "not_applicable", "held", "share", "refused", "lost")
RECORD_DECISION_KEYS = ("vehicle", "fault_class", "runs", "survivable", "static_hover", "spinning", "not_survivable", "check_failed",
                        "controller", "held", "share", "low", "high", "miss", "all_fail", "not_survivable_held")


def recorded_full_run(name: str = RECORD) -> dict[str, Any]:
    """The committed record of the full campaign (``bench_results/deciding_full_run.json``; ``name``
    :data:`SENSED_RECORD`: flown on sensors), checked against the code: its cells are the suite's
    cells (same vehicles, fault classes, controllers, in order, the suite's runs each), its decision
    rows the suite's (vehicle, fault class) pairs with counts that add up, a record on sensors
    carries its paired comparison with the truth, cell for cell, adding up; a mismatch is a
    ``ValueError`` naming the field (a stale record)."""
    if name not in (RECORD, SENSED_RECORD):
        raise ValueError(f"name: expected {RECORD!r} or {SENSED_RECORD!r}, got {name!r}")
    path = resources.files("rotorfault.papers").joinpath("bench_results", name)
    return check_record(json.loads(path.read_text(encoding="utf-8")), name)


def check_record(data: dict[str, Any], name: str = RECORD) -> dict[str, Any]:
    """:func:`recorded_full_run`'s checks on a record already read (``data``, returned as is);
    ``name`` says what it must be (:data:`RECORD` on the truth, :data:`SENSED_RECORD` on sensors)."""
    from ..studies import deciding as D

    run = data.get("campaign")
    if not isinstance(run, dict):
        raise ValueError(f"{name}: campaign is missing")
    for key in ("command", "commit", "flown", "flown_on", "flight_seconds", "suite", "cells", "certified", "decision", "contradictions"):
        if key not in run:
            raise ValueError(f"{name}: campaign.{key} is missing")
    suite = D.DecidingCampaign.from_dict(run["suite"])
    cells = run["cells"]
    if [(c["vehicle"], c["fault_class"], c["controller"]) for c in cells] != [(c.vehicle, c.fault_class, c.controller) for c in suite.cells]:
        raise ValueError(f"{name}: campaign.cells are not the suite's cells (vehicles, fault classes, controllers, order)")
    for k, c in enumerate(cells):
        if set(c) != set(RECORD_CELL_KEYS):
            raise ValueError(f"{name}: campaign.cells[{k}] has fields {sorted(c)}, expected {sorted(RECORD_CELL_KEYS)}")
        if c["runs"] + c["not_applicable"] != suite.runs or not 0 <= c["held"] <= c["runs"] or c["lost"] + c["refused"] > c["runs"]:
            raise ValueError(f"{name}: campaign.cells[{k}] counts do not add up to {suite.runs} runs")
    pairs = list(dict.fromkeys((c.vehicle, c.fault_class) for c in suite.cells))
    decision = run["decision"]
    if [(d["vehicle"], d["fault_class"]) for d in decision] != pairs:
        raise ValueError(f"{name}: campaign.decision rows are not the suite's vehicle and fault class pairs")
    held = {(c["vehicle"], c["fault_class"], c["controller"]): c["held"] for c in cells}
    for k, d in enumerate(decision):
        if set(d) != set(RECORD_DECISION_KEYS):
            raise ValueError(f"{name}: campaign.decision[{k}] has fields {sorted(d)}, expected {sorted(RECORD_DECISION_KEYS)}")
        if (d["static_hover"] + d["spinning"] != d["survivable"] or d["survivable"] + d["not_survivable"] + d["check_failed"] != d["runs"]
                or d["runs"] > suite.runs or not 0 <= d["held"] <= d["survivable"] or d["all_fail"] > d["survivable"] - d["held"]
                or d["held"] > held[(d["vehicle"], d["fault_class"], d["controller"])]):
            raise ValueError(f"{name}: campaign.decision[{k}] counts do not add up")
        if d["survivable"] and not math.isclose(d["share"], d["held"] / d["survivable"], rel_tol=1e-12):
            raise ValueError(f"{name}: campaign.decision[{k}].share is not held / survivable")
    sensed = name == SENSED_RECORD
    if (suite.sensing is not None) != sensed:
        raise ValueError(f"{name}: campaign.suite.sensing must be {'a sensor suite' if sensed else 'absent (the truth)'}")
    if sensed:
        rows = run.get("against_truth")
        if not isinstance(rows, list) or len(rows) != len(cells):
            raise ValueError(f"{name}: campaign.against_truth must have one row per cell")
        for k, (c, r) in enumerate(zip(cells, rows)):
            if set(r) != set(AGAINST_TRUTH_KEYS) or (r["vehicle"], r["fault_class"], r["controller"]) != (c["vehicle"], c["fault_class"], c["controller"]):
                raise ValueError(f"{name}: campaign.against_truth[{k}] is not cell {k}'s comparison")
            if (r["both"] + r["truth_only"] + r["sensed_only"] + r["neither"] != r["runs"] or r["runs"] != c["runs"]
                    or r["both"] + r["sensed_only"] != c["held"] or not 0 <= r["truth_only_past_gyro_range"] <= r["truth_only"]
                    or not 0 <= r["both_past_gyro_range"] <= r["both"]):
                raise ValueError(f"{name}: campaign.against_truth[{k}] counts do not add up")
    return data


def _recorded_tables(section: ReportSection, name: str = RECORD) -> None:
    """The recorded full run beside the live table, labelled with what was run, when, on which commit,
    and what the controllers flew on."""
    from ..analysis import RelaxedHoverSettings
    from ..studies import deciding as D

    data = recorded_full_run(name)
    run = data["campaign"]
    cert = run["certified"]
    sensing = run["suite"].get("sensing")
    on = "on the truth" if sensing is None else f"on {sensing['suite']} sensors and the estimator"
    label = (f"Recorded full run {on} (not flown by this report): `{run['command']}` on commit {run['commit']}, flown {run['flown']} "
             f"({run['flown_on']}), {run['flight_seconds']:.1f} s; certify per run: {cert['how']} on commit {cert['commit']} "
             f"({cert['draws']:,} draws, {cert['seconds']:.0f} s of certify")
    label += f", {cert['seconds'] / cert['draws_timed']:.2f} s per draw)." if cert["draws_timed"] else ")."
    judged = run.get("holds_judged")
    if judged:
        label += (f" Holds judged again without flying by the current rule ({judged['rule']}): {judged['held_as_flown']:,} held as flown, "
                  f"{judged['held']:,} now ({judged['now_held']} newly held, {judged['no_longer_held']} no longer).")
    section.tables.append(ReportTable(
        f"{label} Hold share per cell over all runs (whatever certify says of them).",
        ("vehicle", "fault class", "controller", "held", "hold share", "lost", "design refused"),
        tuple((c["vehicle"], c["fault_class"], c["controller"], f"{c['held']}/{c['runs']}" if c["runs"] else "not applicable",
               f"{100 * c['share']:.1f} %" if c["runs"] else "", str(c["lost"]) if c["runs"] else "", str(c["refused"]) if c["runs"] else "")
              for c in run["cells"]),
    ))
    section.tables.append(ReportTable(
        f"{label} The decision: per vehicle and fault class, the runs certify calls survivable on the run's own vehicle and fault "
        f"(static hover / spinning), the best controller's hold share over them (95 % Wilson interval; a run its controller does not "
        f"apply to counts as not held) against the target (>= {100 * D.TARGET_SHARE:.0f} %), the survivable runs no controller holds "
        f"(target 0) and the runs certified not survivable that a controller holds ({len(run['contradictions'])} listed in the record).",
        ("vehicle", "fault class", "certified survivable (static / spinning)", "not survivable", "check failed", "best controller",
         "holds (95 % CI)", "misses the target by", "all fail", "not survivable, held"),
        tuple(D.decision_cells(d) for d in run["decision"]),
    ))
    if run["contradictions"]:
        section.tables.append(ReportTable(
            f"{label} Runs certified not survivable that a controller holds (a certify error or a hold-rule gap): "
            f"{run.get('contradictions_why', '')}",
            ("vehicle", "fault class", "run", "failed rotors", "efficiency", "static class", "wind (m/s)", "held by"),
            tuple((r["vehicle"], r["fault_class"], str(r["index"]), r["failed_rotors"], f"{r['efficiency']:.3f}", r["static_hover"],
                   f"{r['wind_speed_m_s']:.1f}", r["held_by"]) for r in run["contradictions"]),
        ))
    misses = {(m["vehicle"], m["fault_class"]): m for m in run.get("misses", [])}
    rows = []
    for d in run["decision"]:
        m = misses.get((d["vehicle"], d["fault_class"]))
        if m is None:
            continue
        outcomes = ", ".join(f"{n} {k}" for k, n in sorted(m["outcomes"].items(), key=lambda kv: -kv[1]))
        bins = ", ".join(f"{b['efficiency']}: {b['missed']}/{b['survivable']}" for b in m["by_efficiency"])
        lost = m["lost_after_failure_median_s"]
        tilt = m["peak_tilt_median_deg"]
        others = ", ".join(f"{k} {n}" for k, n in m["held_by_another"].items() if n) or "none"
        on_truth = f"; of them held on the truth (the same draws): {m['held_on_truth']}" if "held_on_truth" in m else ""
        rows.append((f"{d['vehicle']} {d['fault_class']}", f"{d['controller']} ({d['held']}/{d['survivable']}): {D.target_verdict(d)}", f"{m['missed']} not held{on_truth}: {outcomes}; by efficiency (not held / survivable) {bins}; "
                     f"wind median {m['wind_median_m_s']:.1f} m/s (all {m['wind_median_all_m_s']:.1f}); lost "
                     f"{'-' if lost is None else f'{lost:.1f} s'} after the failure (median), peak tilt {'-' if tilt is None else f'{tilt:.0f} deg'}; "
                     f"held instead by {others}; certify's spin at its search limit ({RelaxedHoverSettings().max_spin_rate_rad_s:g} rad/s) in {m.get('spin_at_search_limit', 0)}",
                     m.get("why", "")))
    if rows:
        section.tables.append(ReportTable(
            f"{label} Where the target is missed after the certify split: which cell, by how much, the measurement (the survivable runs "
            "the best controller does not hold) and why.",
            ("cell", "best controller, miss", "measurement", "why"), tuple(rows),
        ))
    if "against_truth" in run:
        section.tables.append(ReportTable(
            f"{label} Sensors against the truth, run for run: each cell's runs (the same draws and controller) held on both, on the "
            f"truth only, on the sensors only, on neither; and of those held on the truth only and on both, how many spin past the gyro's range "
            f"on the truth (the last 5 s mean yaw rate). {run.get('against_truth_why', '')}",
            ("vehicle", "fault class", "controller", "runs", "held on truth", f"held on {sensing['suite']}", "both", "truth only",
             f"{sensing['suite']} only", "neither", "spinning past the gyro's range on the truth: truth only / both"),
            tuple((r["vehicle"], r["fault_class"], r["controller"], str(r["runs"]), str(r["both"] + r["truth_only"]),
                   str(r["both"] + r["sensed_only"]), str(r["both"]), str(r["truth_only"]), str(r["sensed_only"]), str(r["neither"]),
                   f"{r['truth_only_past_gyro_range']} / {r['both_past_gyro_range']}")
                  for r in run["against_truth"] if r["runs"]),
        ))


def report_section(out: Path, *, quick: bool = False) -> ReportSection:
    from ..studies import deciding as D

    start = time.perf_counter()
    runs = QUICK_RUNS if quick else FULL_RUNS
    suite = D.DecidingCampaign(runs=runs)
    result = D.run_deciding(suite, progress=False)
    section = ReportSection("campaign", "The campaign that decides: which controller holds which failure",
                            source=f"rotorfault.studies.deciding; rotorfault campaign --suite deciding --runs {runs}")
    rows = []
    for r in result.cell_rows():
        if r["runs"] == 0:
            rows.append((r["vehicle"], r["fault_class"], r["controller"], "not applicable", "", "", "", "", r["note"]))
            continue
        rows.append((r["vehicle"], r["fault_class"], r["controller"], f"{r['held']}/{r['runs']}",
                     f"{100 * r['share']:.1f} % [{100 * r['low']:.1f}, {100 * r['high']:.1f}]", str(r["lost"]), str(r["refused"]),
                     f"{r['worst_altitude_m']:.2f} / {r['worst_horizontal_m']:.2f}", f"{r['spin_rad_s']:.1f}"))
    section.tables.append(ReportTable(
        f"Hold share per cell, {runs} runs each (95 % Wilson interval). Holds: not lost, no ground contact, within "
        f"{D.HOLD_ALTITUDE_M:g} m altitude and {D.HOLD_HORIZONTAL_M:g} m horizontal from {D.SETTLE_S:g} s after the failure to the end "
        f"({D.AFTER_FAULT_S:g} s after it), yaw rate not spinning up (rotorfault.studies.deciding_hold: growth over the last 5 s at most "
        f"{D.SPIN_GROWTH_MIN_RAD_S:g} rad/s or what the run's own damping, I_zz / k_r, explains; a settle ending below {D.SPIN_END_LIMIT_RAD_S:g} rad/s). Worst deviation over the runs not lost; "
        "spin: median steady yaw rate of the settled runs.",
        ("vehicle", "fault class", "controller", "held", "hold share", "lost", "design refused", "worst alt / horiz (m)", "spin (rad/s) / note"),
        tuple(rows),
    ))
    section.tables.append(ReportTable(
        f"Best controller per vehicle and fault class against the target (>= {100 * D.TARGET_SHARE:.0f} %)",
        ("vehicle", "fault class", "best controller", "hold share", "misses the target by"),
        tuple((b["vehicle"], b["fault_class"], b["controller"], f"{100 * b['share']:.1f} %",
               "met" if b["miss"] == 0 else f"{100 * b['miss']:.1f} points") for b in result.best()),
    ))
    section.tables.append(ReportTable(
        f"The decision from this report's own {runs} runs per cell: certify on each run's own vehicle and fault, the best controller "
        f"over the runs certified survivable against the target (>= {100 * D.TARGET_SHARE:.0f} %), survivable runs no controller holds, "
        "runs certified not survivable that a controller holds",
        ("vehicle", "fault class", "certified survivable (static / spinning)", "not survivable", "check failed", "best controller",
         "holds (95 % CI)", "misses the target by", "all fail", "not survivable, held"),
        tuple(D.decision_cells(d) for d in result.decision()),
    ))
    _recorded_tables(section)
    _recorded_tables(section, SENSED_RECORD)
    section.notes.append(
        f"{suite.total_runs:,} rows ({len(suite.cells)} cells x {runs}) in {result.seconds:.1f} s. Each controller is designed on the "
        "nominal vehicle; every run flies a vehicle with mass, inertia, thrust and drag-torque coefficients and motor time constant "
        "off by up to 20 %, in 0-5 m/s wind with a gust; the failures are total (a quarter of the runs) or partial (efficiency "
        "uniform in [0, 1]). Decisions and gaps: rotorfault.studies.deciding's docstring."
        + (" Quick mode: too few runs per cell to decide the 95 % target; the full report flies 1,000." if quick else "")
    )
    _certify_against_flights(section, quick=quick)
    section.run_time_s = time.perf_counter() - start
    return section


def _certify_against_flights(section: ReportSection, *, quick: bool) -> None:
    """Certify's verdict on every single and double failure beside our controllers' flights
    (:func:`rotorfault.studies.certify_against_flights`): every preset and the imported PX4 x500
    (``--quick``: Ke's quadcopter's single failures, to stay within the quick report's time)."""
    from ..analysis import ENTRY_TILT_LIMIT_RAD
    from ..analysis.airframe import rotor_labels
    from ..flight.outcomes import VERDICT_MEANINGS, WINDOW_S
    from ..studies import agreement as A
    from ..studies import deciding as D

    vehicles = [D.vehicle("ke-quadcopter")] if quick else A.preset_vehicles()
    result = A.certify_against_flights(vehicles, max_failed=1 if quick else 2)
    n = result.counts()
    unreachable = [f"{c.vehicle} {rotor_labels(c.failed)}" for c in result.cases if c.spinning.hover == "spinning" and not c.survivable]
    section.tables.append(ReportTable(
        f"Certify against flights: {n['cases']} {'single' if quick else 'single and double'} failures, {n['agree']} agree. Certified survivable (static "
        f"hover, or a relaxed hover a linear feedback can hold, its entry from hover not excluded): {n['survivable']}, held by at least one controller: "
        f"{n['survivable_held']}; certified not survivable: {n['not_survivable']}, held by a controller: {n['not_survivable_held']}. "
        f"Each controller told the failure, which comes at {A.FAILURE_TIME_S:g} s from hover; verdict over the last {WINDOW_S:g} s "
        f"of {A.FAILURE_TIME_S + A.AFTER_FAILURE_S:g} s (a run holding its place with its spin not settled by then flown on to "
        f"{A.FAILURE_TIME_S + A.SETTLE_AFTER_FAILURE_S:g} s, that verdict standing): holds = {VERDICT_MEANINGS['holds']}. Errors: the "
        "window's largest horizontal / altitude error; a lost flight: when, why, and its peak rotor command against the limit. "
        f"A spinning relaxed hover counts as survivable only where its entry from hover is not excluded "
        f"(rotorfault.analysis.entry_from_hover: the remaining rotors' roll/pitch-to-yaw ratio bounds the tilt reached before the "
        f"spin; limit {math.degrees(ENTRY_TILT_LIMIT_RAD):g} degrees, the simulator's). Spinning solution exists, not reachable "
        f"from hover: {'; '.join(unreachable) or 'none of these cases'}. rotorfault.studies.agreement's notes.",
        result.headers(), tuple(result.rows()),
    ))


__all__ = ["FULL_RUNS", "QUICK_RUNS", "RECORD", "SENSED_RECORD", "check_record", "recorded_full_run", "report_section"]

"""The deciding campaign's part of ``rotorfault reproduce`` (issue 30): the table vehicle x fault
class x controller (hold share, worst deviation, spin rate), the best controller per vehicle and
fault class against the 95 % target, and how many runs stand behind each cell. Computed by
:mod:`rotorfault.studies.deciding`, the same code as ``rotorfault campaign --suite deciding``."""

from __future__ import annotations

import math
import time
from pathlib import Path

from ._report import ReportSection, ReportTable

#: Runs per cell: the full report (the issue's 1,000) and ``--quick`` (a smoke test of the table).
FULL_RUNS = 1000
QUICK_RUNS = 6


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
        f"({D.AFTER_FAULT_S:g} s after it). Worst deviation over the runs not lost; spin: median steady yaw rate of the settled runs.",
        ("vehicle", "fault class", "controller", "held", "hold share", "lost", "design refused", "worst alt / horiz (m)", "spin (rad/s) / note"),
        tuple(rows),
    ))
    section.tables.append(ReportTable(
        f"Best controller per vehicle and fault class against the target (>= {100 * D.TARGET_SHARE:.0f} %)",
        ("vehicle", "fault class", "best controller", "hold share", "misses the target by"),
        tuple((b["vehicle"], b["fault_class"], b["controller"], f"{100 * b['share']:.1f} %",
               "met" if b["miss"] == 0 else f"{100 * b['miss']:.1f} points") for b in result.best()),
    ))
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


__all__ = ["FULL_RUNS", "QUICK_RUNS", "report_section"]

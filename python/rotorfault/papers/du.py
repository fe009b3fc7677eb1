"""Du, Quan, Yang, Cai (JGCD 2015): controllability and the Available Control Authority Index.

The generic machinery is :mod:`rotorfault.analysis` (ACAI, the 9-step test, failure tables) and
:mod:`rotorfault.studies.scan` (the Fig. 4 efficiency grid). This module holds what is Du's
own: the numbers Tables II and III print, each beside ours (:func:`printed_numbers`), which the
tests and the reproduce-all report read.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from ..analysis.airframe import Airframe
from ..analysis.acai import acai_label
from ..analysis.controllability import controllability, failure_table
from ..studies.scan import efficiency_scan
from ._numbers import PaperNumber

if TYPE_CHECKING:
    from ._report import ReportSection

PAPER = "Du et al. (JGCD 2015)"
#: Tables II and III print four decimals: agreement to half a unit in the last place.
TABLE_TOL = 0.5e-4

#: Table II, PNPNPN hexacopter (Table I parameters): no failure, then rotor 1..6 failed.
TABLE_II = {"no failure": 1.4861, **{f"rotor {k} failed": 0.0 for k in range(1, 7)}}
#: Table III, PPNNPN hexacopter.
TABLE_III = {
    "no failure": 1.1295,
    "rotor 1 failed": 0.7221,
    "rotor 2 failed": 0.4510,
    "rotor 3 failed": 0.4510,
    "rotor 4 failed": 0.7221,
    "rotor 5 failed": 0.0,
    "rotor 6 failed": 0.0,
}
_NOTE_EQ13 = (
    "eq. (13) prints 0 although hover is infeasible: the hover wrench lies outside the attainable set "
    "(see the README's decisions; formula='facet-margin' shows the gap)"
)


def _rows(preset: str, table: str, printed: dict[str, float]) -> list[PaperNumber]:
    airframe = Airframe.preset(preset)
    rows = []
    for case, value in printed.items():
        failed = [] if case == "no failure" else [int(case.split()[1])]
        report = controllability(airframe.with_failed_rotors(failed) if failed else airframe)
        margin = controllability(airframe.with_failed_rotors(failed) if failed else airframe, formula="facet-margin")
        note = _NOTE_EQ13 if report.acai == 0.0 and margin.acai < 0.0 else ""
        rows.append(PaperNumber(PAPER, table, f"{acai_label('eq13')}, {preset}, {case}", value, report.acai, TABLE_TOL, note))
    return rows


def printed_numbers() -> list[PaperNumber]:
    """Every ACAI Tables II and III print, beside ours (eq. (13), as the paper computes it)."""
    return _rows("hexa-pnpnpn", "Table II", TABLE_II) + _rows("hexa-ppnnpn", "Table III", TABLE_III)


#: Fig. 4's grid step (the paper's: 26 levels per rotor) and the coarser step of ``--quick``.
FIG4_STEP = 0.04
FIG4_QUICK_STEP = 0.1


def report_section(out: Path, *, quick: bool = False) -> ReportSection:
    """Du's part of ``rotorfault reproduce``: Tables II and III beside ours
    (:func:`printed_numbers`), the failure tables of both hexacopters with up to two failed rotors
    (:func:`rotorfault.failure_table`, as ``rotorfault failures`` prints them) and Fig. 4
    (:func:`rotorfault.efficiency_scan`, as ``rotorfault scan --plot``; ``--quick``: a coarser
    grid), written into ``out``."""
    import time

    from ._report import ReportFigure, ReportSection, ReportTable

    start = time.perf_counter()
    section = ReportSection("du", "Du et al.: controllability and the available control authority index (ACAI)",
                            source="rotorfault.papers.du (rotorfault failures, rotorfault scan)")
    section.numbers = printed_numbers()
    for preset in ("hexa-pnpnpn", "hexa-ppnnpn"):
        table = failure_table(Airframe.preset(preset), max_failed=2)
        headers, rows = table.rows_for_display()
        section.tables.append(ReportTable(
            f"{preset}: every combination of up to 2 failed rotors (rotorfault failures -a {preset} -k 2; "
            "* eq. (13) prints 0 although hover is infeasible)",
            tuple(headers), tuple(tuple(row) for row in rows)))
    step = FIG4_QUICK_STEP if quick else FIG4_STEP
    scan = efficiency_scan(Airframe.preset("hexa-pnpnpn"), (1, 2, 5), step)
    scan.plot(str(out / "du-fig4.png"))
    section.figures.append(ReportFigure(
        "du-fig4.png",
        f"Du Fig. 4: hexa-pnpnpn, efficiencies of rotors 1, 2, 5 swept with step {step:g} ({len(scan.acai):,} points, "
        f"{100 * scan.controllable_fraction:.1f} % controllable){' (--quick: the paper uses 0.04)' if quick else ''}."))
    section.run_time_s = time.perf_counter() - start
    return section


__all__ = ["FIG4_QUICK_STEP", "FIG4_STEP", "PAPER", "TABLE_II", "TABLE_III", "TABLE_TOL", "printed_numbers", "report_section"]

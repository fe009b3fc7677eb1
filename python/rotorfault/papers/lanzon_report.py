"""Lanzon, Freddi and Longhi (JGCD 2014): the report of the paper's flights, behind ``rotorfault
lanzon-report`` (:func:`write_report`) and Lanzon's flights in ``rotorfault reproduce``
(:func:`report_section`): the three-way table, the flights on sensors, the claims, the rotor-inertia
sweep and the Monte Carlo comparison, as tables and figures handed to the one report writer
(:func:`rotorfault.papers._report.write_report_files`). What is flown, and the paper's parameters,
scenarios and claims, are :mod:`rotorfault.papers.lanzon`.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from .._util.tables import Records
from ..control.lanzon import LanzonVehicle
from ..flight.attitude import LEVEL_SPIN_FRACTION, LEVEL_TILT_DEG
from ..flight.outcomes import HOLD_BAND_M, HOLD_SPEED_M_S, WINDOW_S, outcome_text
from ..plotting.paths import plot_lanzon_paths as plot_paths
from ..plotting.verdicts import plot_verdict_sweep
from ..studies.lanzon_robustness import MonteCarloResult
from ._report import markdown_lines
from .lanzon import (
    IZZ_PRINTED,
    IZZ_PROBABLE,
    IZZ_VALUES,
    MOCAP_AT_LOOP_RATE,
    ROTOR_INERTIAS_FULL,
    ROTOR_INERTIAS_QUICK,
    LanzonRun,
    _sweep_cells,
    claims_table,
    flight_claims,
    flight_verdict,
    fly,
    monte_carlo,
    paper_claim,
    rotor_inertia_sweep,
    three_way,
    verdict_changes,
)

if TYPE_CHECKING:
    from ._report import ReportFile, ReportSection, ReportTable


#: The columns of :func:`report_rows` and their types.
REPORT_COLUMNS: tuple[tuple[str, str], ...] = (
    ("scenario", "string"), ("case", "string"), ("case_description", "string"), ("inertia_zz_kg_m2", "float64"),
    ("crossover_rad_s", "float64"), ("limits", "bool"), ("gamma_min", "float64"), ("gamma", "float64"),
    ("achieved_norm", "float64"), ("verdict", "string"), ("outcome", "string"), ("outcome_text", "string"),
    ("lost_at_s", "float64"), ("duration_s", "float64"),
    ("level_after_s", "float64"), ("window_tilt_deg", "float64"), ("window_spin_rad_s", "float64"),
    ("max_altitude_loss_m", "float64"), ("final_error_m", "float64"), ("window_horizontal_error_m", "float64"),
    ("window_altitude_error_m", "float64"), ("min_thrust_n", "float64"), ("max_thrust_n", "float64"),
)


def report_rows(runs: list[LanzonRun]) -> Records:
    """One record per run of the three-way table (:data:`REPORT_COLUMNS`; a sequence of dicts with
    ``to_arrow()`` and ``to_pandas()``)."""
    rows = []
    for run in runs:
        a, p = run.attitude, run.position
        rows.append({
            "scenario": run.scenario.name,
            "case": run.case.label,
            "case_description": run.case.description,
            "inertia_zz_kg_m2": run.vehicle.inertia_zz_kg_m2,
            "crossover_rad_s": run.case.crossover_rad_s,
            "limits": run.case.limits,
            "gamma_min": run.design.gamma_min,
            "gamma": run.design.gamma,
            "achieved_norm": run.design.evidence.achieved_norm,
            "verdict": flight_verdict(run),
            "outcome": run.outcome,
            "outcome_text": outcome_text(run.outcome, run.lost_at_s),
            "lost_at_s": run.lost_at_s,
            "duration_s": run.scenario.duration_s,
            "level_after_s": a.level_after_s,
            "window_tilt_deg": a.window_tilt_deg,
            "window_spin_rad_s": a.window_spin_rad_s,
            "max_altitude_loss_m": a.max_altitude_loss_m,
            "final_error_m": run.final_error_m,
            "window_horizontal_error_m": None if p is None else p.window_horizontal_error_m,
            "window_altitude_error_m": None if p is None else p.window_altitude_error_m,
            "min_thrust_n": float(np.nanmin(run.trajectory.rotor_thrust[:, [0, 2, 3]])),
            "max_thrust_n": float(np.nanmax(run.trajectory.rotor_thrust)),
        })
    return Records(rows, REPORT_COLUMNS, title="Lanzon et al.: three-way flights", kind="lanzon-flights")


def _num(value: Any, digits: int) -> str:
    if value is None:
        return "-"
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, float):
        if not math.isfinite(value):
            return str(value)
        return f"{round(value, digits) + 0.0:.{digits}f}"
    return str(value)


def three_way_table(runs: list[LanzonRun]) -> list[str]:
    """The three-way table as Markdown lines: one row per ``I_zz`` and case, scenarios A and B side
    by side (A: outcome, tilt below 1 deg after, altitude lost; B: outcome, final error)."""
    return markdown_lines(*_three_way_cells(runs))


def _three_way_cells(runs: list[LanzonRun]) -> tuple[tuple[str, ...], tuple[tuple[str, ...], ...]]:
    by_key: dict[tuple[float, str], dict[str, LanzonRun]] = {}
    for run in runs:
        by_key.setdefault((run.vehicle.inertia_zz_kg_m2, run.case.label), {})[run.scenario.name] = run
    columns = ("I_zz (kg m^2)", "case", "gamma", "A: outcome", "A: tilt < 1 deg after (s)", "A: altitude lost (m)",
               "B: outcome", "B: final error (m)", "B: altitude lost (m)")
    rows = []
    for (izz, label), pair in by_key.items():
        a, b = pair.get("A"), pair.get("B")
        any_run = a or b
        assert any_run is not None
        cells = [f"{izz:g}", f"({label}) {any_run.case.description}", f"{any_run.design.gamma:.3f}"]
        if a is not None:
            cells += [outcome_text(a.outcome, a.lost_at_s), _num(a.attitude.level_after_s, 1),
                      _num(a.attitude.max_altitude_loss_m, 1)]
        else:
            cells += ["-", "-", "-"]
        if b is not None:
            cells += [outcome_text(b.outcome, b.lost_at_s), _num(b.final_error_m, 3), _num(b.attitude.max_altitude_loss_m, 1)]
        else:
            cells += ["-", "-", "-"]
        rows.append(tuple(cells))
    return columns, tuple(rows)


def monte_carlo_table(results: list[MonteCarloResult]) -> list[str]:
    """The robustness comparison as Markdown lines."""
    return markdown_lines(*_monte_carlo_cells(results))


def _monte_carlo_cells(results: list[MonteCarloResult]) -> tuple[tuple[str, ...], tuple[tuple[str, ...], ...]]:
    names = {"lanzon": "Lanzon RFL + H-infinity, design (c)", "ke": "Ke uniform passive FTC (ke-hil)"}
    rows = []
    for r in results:
        outcomes = ", ".join(f"{outcome_text(k)} {v}" for k, v in r.counts().items())
        rows.append((names.get(r.controller, r.controller), str(r.runs), f"{r.inertia_zz_kg_m2:g}", f"{100 * r.held_fraction:.1f} %",
                     f"{100 * r.lost_fraction:.1f} %", _num(r.median_final_error_m, 3), _num(r.worst_final_error_m, 3), outcomes))
    return ("controller", "runs", "I_zz (kg m^2)", "holds position", "lost", "median final error (m)", "worst final error (m)",
            "outcomes"), tuple(rows)


def write_report(
    runs: list[LanzonRun],
    out_dir: str | Path,
    *,
    monte_carlo_results: list[MonteCarloResult] | None = None,
    figures: bool = True,
    force: bool = False,
    command: str | None = None,
) -> Path:
    """Writes the report directory ``out_dir``: ``lanzon-report.md`` (the three-way table and
    the Monte Carlo comparison), ``lanzon-report.csv`` (one row per flight), ``monte-carlo.csv``
    (one row per Monte Carlo run), with ``figures`` one time history per flight
    (``<scenario>-<case>-izz-<value>.png``), the Scenario B paths (``paths-3d.png``) and the loop
    shapes of the paper's and our design (``loop-shape-<case>.png``); and ``manifest.json``.
    Written beside ``out_dir`` and swapped in when complete (the one report writer,
    :func:`rotorfault.papers._report.write_report_files`); an existing report is replaced only
    with ``force``."""
    from ._report import write_report_files

    def content(tmp: Path) -> list[ReportFile]:
        if not runs:
            raise ValueError("runs: nothing to report (fly at least one scenario)")
        if figures:
            _draw_report_figures(runs, tmp)
        return _report_files(runs, monte_carlo_results or [], figures=figures)

    out = write_report_files(
        out_dir, content, field_name="out_dir", force=force,
        generator="rotorfault lanzon-report (rotorfault.papers.lanzon_report.write_report)", command=command,
        default_command="rotorfault.papers.lanzon_report.write_report",
    )
    return out / "lanzon-report.md"


def _draw_report_figures(runs: list[LanzonRun], directory: Path) -> None:
    """The figures of ``rotorfault lanzon-report`` (:func:`write_report`) drawn into ``directory``."""
    for run in runs:
        run.plot(str(directory / f"{run.scenario.name}-{run.case.label}-izz-{run.vehicle.inertia_zz_kg_m2:g}.png"))
    b_runs = [run for run in runs if run.scenario.name == "B"]
    if b_runs:
        plot_paths(b_runs, str(directory / "paths-3d.png"))
    seen: set[str] = set()
    for run in runs:
        if run.case.label in ("b", "c") and run.case.label not in seen:
            seen.add(run.case.label)
            fig = run.design.plot_loop_shape(str(directory / f"loop-shape-{run.case.label}.png"))
            del fig


#: The columns of ``monte-carlo.csv``: one row per Monte Carlo run, its five factors, verdict and error.
MONTE_CARLO_CSV_COLUMNS = ("controller", "run", "mass_factor", "inertia_xx_factor", "inertia_zz_factor", "rotational_drag_factor",
                           "rotor_inertia_factor", "outcome", "final_error_m")


def _report_files(runs: list[LanzonRun], mc: list[MonteCarloResult], *, figures: bool) -> list[ReportFile]:
    """The text files of ``rotorfault lanzon-report``: ``lanzon-report.csv`` (:func:`report_rows`),
    ``lanzon-report.md`` and, with Monte Carlo results, ``monte-carlo.csv``."""
    from ._report import CsvTable, MarkdownText

    lines = [
        "# Flying a quadrotor on three rotors (Lanzon et al.): report",
        "",
        "Rotor 2 dead from the start. Scenario A (Table 2): inner loop only, from roll -45 deg, pitch 45 deg;",
        f"'level' keeps the tilt below {LEVEL_TILT_DEG:g} deg and the spin within {100 * LEVEL_SPIN_FRACTION:g} % of "
        f"m g d / k_r over the last {WINDOW_S:g} s.",
        "Scenario B (Table 3): inner and outer loop from (5, 5, 5) m to (0, 0, 1) m (z up); 'holds position'",
        f"keeps within {HOLD_BAND_M[0]:g} m horizontally, {HOLD_BAND_M[1]:g} m vertically and below "
        f"{HOLD_SPEED_M_S:g} m/s over the last {WINDOW_S:g} s (Ke's verdicts).",
        "Cases: (a) the paper's design (100 rad/s crossover) without actuator limits, (b) the same with the",
        "paper's limits (thrust in [0, 5] N, 50 N/s), (c) our 30 rad/s design with the limits. I_zz: Table 1's",
        f"printed {IZZ_PRINTED:g} and the probable {IZZ_PROBABLE:g} kg m^2.",
        "",
        *three_way_table(runs),
    ]
    claims = flight_claims(runs)
    if claims:
        lines += ["", "The paper's flight claims (the paper's design with its limits), each with the whole flight's verdict:", "",
                  *claims_table(claims)]
    if mc:
        r0 = mc[0]
        lines += [
            "",
            f"Robustness: {r0.runs} runs per controller, mass, I_xx = I_yy, I_zz, k_r and I_R each scaled by a",
            f"factor uniform in [{1 - r0.spread:g}, {1 + r0.spread:g}], sensor noise "
            f"{'none' if r0.snr_db is None else f'{r0.snr_db:g} dB SNR'}, Scenario B's start and setpoint, "
            f"{r0.duration_s:g} s, the paper's limits.",
            "",
            *monte_carlo_table(mc),
        ]
    if figures:
        lines += ["", "Figures: `<scenario>-<case>-izz-<I_zz>.png` (one per flight), `paths-3d.png`, "
                  "`loop-shape-b.png` (the paper's design), `loop-shape-c.png` (ours)."]
    files: list[ReportFile] = [CsvTable.from_records("lanzon-report.csv", report_rows(runs)), MarkdownText("lanzon-report.md", tuple(lines))]
    if mc:
        files.append(CsvTable("monte-carlo.csv", MONTE_CARLO_CSV_COLUMNS, tuple(
            (result.controller, i, *(f"{x:.6f}" for x in result.factors[i]), result.outcomes[i],
             f"{float(result.final_error_m[i]):.6f}" if math.isfinite(float(result.final_error_m[i])) else "")
            for result in mc for i in range(result.runs))))
    return files


def sensing_table(truth: list[LanzonRun], sensed: list[LanzonRun]) -> ReportTable:
    """The flights of ``sensed`` beside the same scenario, case and vehicle in ``truth``: outcome
    and final error on each."""
    from ._report import ReportTable

    def key(r: LanzonRun) -> tuple[str, str, float]:
        return (r.scenario.name, r.case.label, r.vehicle.inertia_zz_kg_m2)

    by_key = {key(r): r for r in truth}
    rows = []
    for b in sensed:
        a = by_key[key(b)]
        rows.append((b.scenario.name, b.case.label, f"{b.vehicle.inertia_zz_kg_m2:g}", a.outcome, b.outcome,
                     "same" if a.outcome == b.outcome else "differs", _num(a.final_error_m, 3), _num(b.final_error_m, 3)))
    return ReportTable(
        f"With sensors: the same flights on the truth and on {sensed[0].trajectory.sensed if sensed else 'sensors'} "
        "(rotorfault.Sensing, the IMU at the 1 kHz loop rate; the error-state Kalman filter), side by side",
        ("scenario", "case", "I_zz (kg m^2)", "truth: outcome", "sensors: outcome", "verdict",
         "final error truth (m)", "final error sensors (m)"),
        tuple(rows),
    )


def report_section(out: Path, *, quick: bool = False) -> ReportSection:
    """Lanzon's flights for ``rotorfault reproduce``: the three-way table (the paper's design
    without and with its limits, ours with them; both ``I_zz`` values) from :func:`three_way`, the
    3-D paths and the flight figures of Scenario B, and, in the full mode, a 200-run Monte Carlo
    of design (c) beside Ke's controller (``rotorfault lanzon-report`` runs 1,000); the paper's
    flight claims scored (:func:`flight_claims`), the 3-D paths of each scenario in its own figure
    and Scenario B's verdict against the rotor inertia (:func:`rotor_inertia_sweep`). Every flight
    is the paper's 60 s; ``--quick`` skips the Monte Carlo and sweeps 6 rotor inertias instead of 9."""
    import time

    from ._report import ReportFigure, ReportSection, ReportTable

    start = time.perf_counter()
    section = ReportSection("lanzon-flights", "Lanzon's flights (Scenarios A and B, Figs. 6-10)",
                            source="rotorfault.papers.lanzon (rotorfault lanzon-report)")
    # The paper's 60 s flights in both modes: a verdict is the whole flight's (a 20 s flight of the
    # paper's design still circles where the 60 s one holds), and they cost about 2.5 s in all.
    runs = three_way()
    columns, rows = _three_way_cells(runs)
    section.tables.append(ReportTable(
        "Three ways, rotor 2 dead (60 s flights)"
        + ": (a) the paper's 100 rad/s design without actuator limits, (b) the same design with the paper's "
        "[0, 5] N and 50 N/s, (c) our 30 rad/s design with those limits; for the printed I_zz and for the likely "
        "misprint 1.16e-2", columns, rows))
    section.tables.append(sensing_table(
        runs, [fly(r.scenario, r.case, vehicle=r.vehicle, designed=r.design, duration_s=r.scenario.duration_s,
                   sensing=MOCAP_AT_LOOP_RATE) for r in runs if r.vehicle.inertia_zz_kg_m2 == IZZ_VALUES[0]]))
    # The paper's flight claims on the scoreboard (a claim is confirmed only when the whole-flight
    # verdict is holds: B within 2 m horizontally, 1 m vertically and below 0.5 m/s over the last
    # 5 s, A tilt below 1 deg and spin within 10 % over the last 5 s; ground contact is crashed).
    section.claims = [paper_claim(c) for c in flight_claims(runs)]
    for name in ("A", "B"):
        mine = [run for run in runs if run.scenario.name == name]
        plot_paths(mine, str(out / f"lanzon-paths-{name}.png"))
        section.figures.append(ReportFigure(f"lanzon-paths-{name}.png", f"3-D paths of Scenario {name}'s runs (Lanzon Fig. 8 style)."))
    # 60 s flights in both modes (a 20 s flight still circling is not the verdict of the paper's
    # 60 s flight; most runs at large I_R are lost within seconds): --quick takes fewer I_R.
    points = rotor_inertia_sweep(ROTOR_INERTIAS_QUICK if quick else ROTOR_INERTIAS_FULL,
                                 designs={(r.vehicle.inertia_zz_kg_m2, r.case.label): r.design for r in runs})
    columns, rows = _sweep_cells(points)
    section.tables.append(ReportTable(
        "Scenario B's verdict against the rotor inertia I_R (the paper prints none; ours is 3e-5 kg m^2), both I_zz, "
        "the paper's design (b) and ours (c) with the paper's limits, 60 s flights"
        + (f" (--quick: {len(ROTOR_INERTIAS_QUICK)} values; the full report {len(ROTOR_INERTIAS_FULL)})" if quick else ""),
        columns, rows))
    section.notes += ["Where the verdict changes with I_R: " + s for s in verdict_changes(points)]
    names = {"b": "(b) paper's design, 100 rad/s", "c": "(c) ours, 30 rad/s"}
    plot_verdict_sweep([{"I_zz (kg m^2)": p.inertia_zz_kg_m2, "design": names.get(p.case, p.case), "I_R": p.rotor_inertia_kg_m2,
                         "verdict": p.verdict} for p in points], str(out / "lanzon-rotor-inertia.png"), parameter="I_R",
                       parameter_label="rotor inertia I_R (kg m^2)", series="design", panel="I_zz (kg m^2)",
                       title="Lanzon scenario B, the paper's limits, 60 s: whole-flight verdict against the rotor inertia I_R",
                       mark=(LanzonVehicle().rotor_inertia_kg_m2, "our I_R"))
    section.figures.append(ReportFigure("lanzon-rotor-inertia.png", "Scenario B's verdict against I_R, per I_zz and design."))
    for run in runs:
        if run.scenario.name == "B" and run.vehicle.inertia_zz_kg_m2 == IZZ_VALUES[0]:
            name = f"lanzon-B-{run.case.label}.png"
            run.plot(str(out / name))
            section.figures.append(ReportFigure(name, run.title, small=True))
    if not quick:
        results = [monte_carlo(c, runs=200, duration_s=60.0) for c in ("lanzon", "ke")]
        columns, rows = _monte_carlo_cells(results)
        section.tables.append(ReportTable(
            "Robustness, 200 runs each: mass, inertias, k_r, I_R +-20 %, 15 dB sensor noise, Scenario B", columns, rows))
    else:
        section.notes.append("--quick: no Monte Carlo (rotorfault lanzon-report runs 1,000 runs per controller).")
    section.run_time_s = time.perf_counter() - start
    return section


__all__ = [
    "MONTE_CARLO_CSV_COLUMNS",
    "REPORT_COLUMNS",
    "monte_carlo_table",
    "report_rows",
    "report_section",
    "sensing_table",
    "three_way_table",
    "write_report",
]

"""Commands that reproduce the papers: ``ftc-report`` (Ke), ``vpp-report`` (Wang),
``lanzon-report`` (Lanzon) and ``reproduce`` (all four in one report)."""

from __future__ import annotations

import sys
from typing import Any, cast

import click
from rich.markup import escape
from rich.table import Table
from rich.console import Console

from .._typing import KeLaw
from .app import _report_interruptions, _user_errors, claim_output, cli, console
from .output import CommandOutput, Output, Rows, output_options


@cli.command("ftc-report")
@click.option("--out", "out_dir", default="ftc-report", show_default=True, type=click.Path(file_okay=False), help="Directory for the table and figures (replaced as a whole).")
@click.option("--preset", "preset_name", default="ke-hil", show_default=True, help="Controller preset (gains and vehicle).")
@click.option(
    "--laws", default="feedforward,literal,full-compensation,baseline", show_default=True,
    help="Command laws to compare (comma-separated).",
)
@click.option("--scenarios", "scenario_names", default=None, help="Only these scenarios (comma-separated names; default: all).")
@click.option("--no-figures", is_flag=True, help="Only the table (Markdown and CSV); the report has no figures.")
@click.option("--force", is_flag=True, help="Replace an existing report in --out.")
@output_options
@_user_errors
def ftc_report(out_dir: str, preset_name: str, laws: str, scenario_names: str | None, no_figures: bool, force: bool, output: Output) -> None:
    """Fly every uniform-passive-FTC scenario (Ke et al.) and write a table and figures."""
    from typing import get_args

    from ..control import ke
    from ..papers import ke as ke_paper

    chosen_laws = [law.strip() for law in laws.split(",") if law.strip()]
    if not chosen_laws:
        raise ValueError(f"laws: give at least one of {', '.join(get_args(KeLaw))}")
    for law in chosen_laws:
        if law not in get_args(KeLaw):
            raise ValueError(f"law: must be one of {', '.join(get_args(KeLaw))}, got {law!r}")
    scenarios = ke_paper.scenarios()
    if scenario_names is not None:
        names = [name.strip() for name in scenario_names.split(",") if name.strip()]
        if not names:
            raise ValueError("scenarios: give at least one scenario name")
        scenarios = [ke_paper.scenario(name) for name in names]
    claim_output("out", out_dir, force=force)
    controller_preset = ke.preset(preset_name)
    with _report_interruptions():
        runs = []
        output.status(f"flying {len(scenarios) * len(chosen_laws)} runs")
        for law in chosen_laws:
            for sc in scenarios:
                runs.append(ke_paper.run_scenario(sc, law=cast(KeLaw, law), controller_preset=controller_preset))
        output.status(f"writing the report to {out_dir}")
        command = "rotorfault " + " ".join(sys.argv[1:]) if sys.argv[1:] else "rotorfault ftc-report"
        path = ke_paper.write_report(runs, out_dir, figures=not no_figures, force=force, command=command)
    fields = {"out": str(path), "preset": preset_name, "laws": chosen_laws, "figures": not no_figures}

    def human(out: Output) -> None:
        _print_ftc_table(runs, preset_name, out.console, out)
        out.print(f"report written to {escape(str(path))}")

    output.emit(CommandOutput("ftc-report", fields, [Rows("runs", list(ke_paper.report_rows(runs)))], csv_table="runs", human=human))


@cli.command("vpp-report")
@click.option("--out", "out_dir", default="vpp-report", show_default=True, type=click.Path(file_okay=False), help="Directory for the tables and figures (replaced as a whole).")
@click.option("--quick", is_flag=True, help="20 s flights (a smoke test, not the paper's 60 s).")
@click.option("--force", is_flag=True, help="Replace an existing report in --out.")
@output_options
@_user_errors
def vpp_report(out_dir: str, quick: bool, force: bool, output: Output) -> None:
    """Wang et al.'s VPP quadcopter: the fixed-pitch comparison (hover, controllability,
    stabilisability, ACAI), the feasible trim speeds, and Section 4's three flights with
    propeller 1 failed."""
    from ..papers import wang as wang_paper

    claim_output("out", out_dir, force=force)
    command = "rotorfault " + " ".join(sys.argv[1:]) if sys.argv[1:] else "rotorfault vpp-report"
    with _report_interruptions():
        path = wang_paper.write_report(out_dir, quick=quick, force=force, command=command)
    cases = wang_paper.fixed_pitch_comparison()

    def human(out: Output) -> None:
        for line in wang_paper.comparison_table(cases):
            out.print(escape(line), soft_wrap=True)
        out.print(f"report written to {escape(str(path))}")

    output.emit(CommandOutput("vpp-report", {"out": str(path), "quick": quick}, [Rows("comparison", list(wang_paper.comparison_rows(cases)))],
                              csv_table="comparison", human=human))


@cli.command("lanzon-report")
@click.option("--out", "out_dir", default="lanzon-report", show_default=True, type=click.Path(file_okay=False), help="Directory for the table, figures and CSV (replaced as a whole).")
@click.option("--runs", "mc_runs", default=1000, show_default=True, type=int, help="Monte Carlo runs per controller (0: none).")
@click.option("--quick", is_flag=True, help="20 s flights and 50 Monte Carlo runs per controller (a smoke test, not the paper's 60 s).")
@click.option("--no-figures", is_flag=True, help="Only the tables (Markdown and CSV).")
@click.option("--force", is_flag=True, help="Replace an existing report in --out.")
@output_options
@_user_errors
def lanzon_report(out_dir: str, mc_runs: int, quick: bool, no_figures: bool, force: bool, output: Output) -> None:
    """Fly Lanzon et al.'s two flights three ways (paper's design without and with limits, ours),
    for both I_zz values, run the Monte Carlo comparison with Ke's controller, and write a report."""
    from ..papers import lanzon as lanzon_paper, lanzon_report as lanzon_paper_report

    if mc_runs < 0:
        raise ValueError(f"runs: must be >= 0, got {mc_runs}")
    claim_output("out", out_dir, force=force)
    duration = 20.0 if quick else None
    runs_per = min(mc_runs, 50) if quick else mc_runs
    with _report_interruptions():
        output.status("flying scenarios A and B, cases (a), (b), (c), I_zz 1.16e-3 and 1.16e-2: 12 flights")
        runs = lanzon_paper.three_way(duration_s=duration)
        results = []
        if runs_per:
            mc_duration = 20.0 if quick else 60.0
            for controller in ("lanzon", "ke"):
                results.append(lanzon_paper.monte_carlo(controller, runs=runs_per, duration_s=mc_duration, progress=output.progress))
        output.status(f"writing the report to {out_dir}")
        command = "rotorfault " + " ".join(sys.argv[1:]) if sys.argv[1:] else "rotorfault lanzon-report"
        path = lanzon_paper_report.write_report(runs, out_dir, monte_carlo_results=results, figures=not no_figures, force=force,
                                         command=command)
    monte_carlo = [
        {"controller": r.controller, "runs": r.runs, "spread": r.spread, "duration_s": r.duration_s, "held_fraction": r.held_fraction,
         "lost_fraction": r.lost_fraction, "median_final_error_m": r.median_final_error_m, "worst_final_error_m": r.worst_final_error_m}
        for r in results
    ]

    def human(out: Output) -> None:
        for line in lanzon_paper_report.three_way_table(runs):
            out.print(escape(line), soft_wrap=True)
        if results:
            for line in lanzon_paper_report.monte_carlo_table(results):
                out.print(escape(line), soft_wrap=True)
        out.print(f"report written to {escape(str(path))}")

    output.emit(CommandOutput("lanzon-report", {"out": str(path), "quick": quick, "monte_carlo_runs": runs_per},
                              [Rows("flights", list(lanzon_paper_report.report_rows(runs))), Rows("monte_carlo", monte_carlo)],
                              csv_table="flights", human=human))


def _print_ftc_table(runs: list[Any], preset_name: str, console: Console = console, output: Output | None = None) -> None:
    """The report table on the terminal: one wide table when it fits, otherwise (below 120
    columns) one narrow table per law with the columns that matter (``output``: the command's
    output, for plain tables when not on a terminal)."""
    from rich import box

    from ..papers import ke as ke_paper

    rows = ke_paper.report_rows(runs)

    def outcome(row: dict[str, Any]) -> str:
        colour = {"holds": "green", "circles": "yellow", "drifts": "yellow"}.get(row["verdict"], "red")
        return f"[{colour}]{escape(row['verdict'])}[/{colour}]"

    def num(row: dict[str, Any], column: str, digits: int) -> str:
        return escape(ke_paper.cell(row, column, digits))

    def horizontal(row: dict[str, Any]) -> str:
        if row["max_horizontal_error_m"] is None:
            return num(row, "max_horizontal_error_m", 1)
        return f"{row['max_horizontal_error_m']:.1f} / {row['final_horizontal_error_m']:.1f}"

    title = f"uniform passive FTC ({escape(preset_name)}): {len(runs)} flights"
    if console.width >= 120:
        table = Table(title=title) if output is None else output.table(title=title)
        for column in ("scenario", "law", "Ke", "verdict", "r (rad/s)", "n3z", "max alt. loss (m)", "horiz. max / final (m)"):
            table.add_column(column, justify="left" if column in ("scenario", "law", "verdict", "Ke") else "right")
        for row in rows:
            table.add_row(
                row["scenario"], row["law"], "yes" if row["ke_stabilizable"] else "no", outcome(row),
                num(row, "r_rad_s", 1), num(row, "n3z", 3), num(row, "max_altitude_loss_m", 2), horizontal(row),
            )
        console.print(table)
        return
    console.print(title, highlight=False)
    for law in dict.fromkeys(row["law"] for row in rows):
        table = Table(
            title=f"law {escape(law)}: r (rad/s), altitude loss and horizontal error (m); * Ke: not stabilisable",
            box=box.SIMPLE_HEAD, pad_edge=False, padding=(0, 1),
        )
        table.add_column("scenario", no_wrap=True)
        table.add_column("verdict", no_wrap=True)
        table.add_column("r", justify="right", no_wrap=True)
        table.add_column("alt. loss", justify="right")
        table.add_column("horiz. max/final", justify="right", no_wrap=True)
        for row in rows:
            if row["law"] != law:
                continue
            name = row["scenario"] + ("" if row["ke_stabilizable"] else "*")
            if row["lost_at_s"] is not None:
                # The short form (the impact speed is in the wide table and the report).
                how = row["verdict"] if not row["cause"] or row["cause"] == row["verdict"] else f"{row['verdict']}: {row['cause']}"
                lost = f"[red]{escape(how)}\nat {row['lost_at_s']:.2f} s[/red]"
                table.add_row(name, lost, "lost", "lost", "lost")
                continue
            r = "unsettled" if row["r_rad_s"] is None else num(row, "r_rad_s", 1)
            h = f"{row['max_horizontal_error_m']:.1f}/{row['final_horizontal_error_m']:.1f}"
            table.add_row(name, outcome(row), r, num(row, "max_altitude_loss_m", 1), h)
        console.print(table)


@cli.command("reproduce")
@click.option("--out", "out_dir", default="report", show_default=True, type=click.Path(file_okay=False), help="Directory for index.html and the figures (replaced as a whole).")
@click.option("--quick", is_flag=True, help="Coarser grids and fewer flights (under 2 minutes).")
@click.option("--benches", "bench_dir", default=None, type=click.Path(file_okay=False), help="Directory of bench results (*.json; default: the results that ship with the package).")
@click.option("--force", is_flag=True, help="Replace an existing report in --out.")
@output_options
@_user_errors
def reproduce(out_dir: str, quick: bool, bench_dir: str | None, force: bool, output: Output) -> None:
    """Reproduce every result of the four papers into one static report (index.html + figures)."""
    from ..papers import reproduce as reproduce_

    claim_output("out", out_dir, force=force)
    command = "rotorfault " + " ".join(sys.argv[1:]) if sys.argv[1:] else "rotorfault reproduce"
    with _report_interruptions():
        result = reproduce_.write_reproduce(
            out_dir, quick=quick, force=force, command=command, bench_directory=bench_dir,
            progress=output.status,
        )
    from ..papers import number_rows

    sections, numbers_all, lines = [], [], []
    for section in result.sections:
        parts = [section, *section.parts]
        numbers = [n for part in parts for n in part.numbers]
        board = reproduce_.score(numbers)
        claims = [c for part in parts for c in part.claims]
        pending = [part.title for part in section.parts if not part.landed]
        lines.append(f"{section.key}: {reproduce_.score_text(section)}")
        sections.append({"key": section.key, "title": section.title, "landed": section.landed, "numbers": len(numbers),
                         "reproduced": board["reproduced"], "passed": board["passed"],
                         "claims": len(claims), "claims_confirmed": sum(c.status == "confirmed" for c in claims), "not_landed": pending})
        numbers_all += numbers

    def human(out: Output) -> None:
        for line in lines:
            out.print(escape(line), highlight=False)
        out.print(f"report written to {escape(str(result.path))} in {result.run_time_s:.1f} s")

    output.emit(CommandOutput("reproduce", {"out": str(result.path), "quick": quick, "run_time_s": result.run_time_s},
                              [Rows("sections", sections), Rows("numbers", list(number_rows(numbers_all)))], csv_table="numbers", human=human))

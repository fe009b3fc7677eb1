"""The ``rotorfault`` command line: presets, ACAI, failure tables, efficiency scans, flights and
the uniform-passive-FTC report.

Every user error (bad value, bad type, unreadable file) ends the command with a one-line
``Error: ...`` message on stderr and exit status 1; click's own usage errors exit with 2.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from typing import Any, TypeVar, cast

import click
import numpy as np
from rich.console import Console
from rich.markup import escape
from rich.table import Table

from ._typing import AcaiFormula, KeLaw
from .airframe import Airframe
from .controllability import EQ13_ZERO_NOTE, controllability, failure_table, format_acai
from .scan import efficiency_scan

F = TypeVar("F", bound=Callable[..., Any])

console = Console()


def _user_errors(command: F) -> F:
    """Turns the library's ValueError/TypeError/OSError into click's one-line error."""

    @functools.wraps(command)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        try:
            return command(*args, **kwargs)
        except (ValueError, TypeError, OSError, OverflowError) as exc:
            raise click.ClickException(str(exc)) from None
        except MemoryError:
            raise click.ClickException("out of memory: ask for a smaller problem") from None

    return wrapper  # type: ignore[return-value]


def parse_numbers(field: str, text: str) -> list[float]:
    try:
        return [float(part) for part in text.split(",")]
    except ValueError:
        raise ValueError(f"{field}: expected comma-separated numbers, got {text!r}") from None


def parse_rotors(field: str, text: str) -> list[int]:
    try:
        return [int(part) for part in text.split(",")]
    except ValueError:
        raise ValueError(f"{field}: expected comma-separated rotor numbers, got {text!r}") from None


formula_option = click.option(
    "--formula",
    type=click.Choice(["eq13", "facet-margin"]),
    default="eq13",
    show_default=True,
    help="How an ACAI with hover outside the attainable set is reported (eq13: as Du prints it).",
)

airframe_option = click.option(
    "--airframe", "-a", required=True, help="Preset name (see `rotorfault airframes`) or a TOML file."
)


@click.group()
@click.version_option(package_name="rotorfault")
def cli() -> None:
    """rotorfault: will this multirotor stay controllable when rotors degrade or fail?"""


@cli.command()
@_user_errors
def airframes() -> None:
    """List the preset airframes."""
    table = Table(title="rotorfault presets")
    for column in ("name", "rotors", "mass (kg)", "max thrust (N)", "description"):
        table.add_column(column)
    for name in Airframe.presets():
        a = Airframe.preset(name)
        table.add_row(name, str(a.rotor_count), f"{a.mass_kg:g}", f"{a.max_thrust_n.max():g}", escape(a.description))
    console.print(table)


@cli.command()
@airframe_option
@click.option("--efficiency", help="Rotor efficiencies, comma-separated (default: the airframe's own).")
@click.option("--give-up-yaw", is_flag=True, help="Only thrust, roll and pitch must stay controllable.")
@formula_option
@_user_errors
def acai(airframe: str, efficiency: str | None, give_up_yaw: bool, formula: AcaiFormula) -> None:
    """Run Du's controllability test and print the ACAI."""
    frame = Airframe.load(airframe)
    efficiencies = None if efficiency is None else parse_numbers("efficiency", efficiency)
    report = controllability(frame, efficiencies, give_up_yaw=give_up_yaw, formula=formula)
    table = Table(title=f"{escape(frame.name)}: controllability", show_header=False)
    table.add_column("quantity")
    table.add_column("value")
    table.add_row("efficiency", ", ".join(f"{e:g}" for e in report.efficiency))
    table.add_row("axes", "thrust, roll, pitch" if give_up_yaw else "thrust, roll, pitch, yaw")
    table.add_row("rank C(A, B)", f"{report.controllability_rank} of {report.state_dimension}")
    table.add_row("rank B_f", f"{report.effectiveness_rank} of {report.virtual_control_dimension}")
    table.add_row("ACAI", format_acai(report.acai, report.hover))
    style = "green" if report.controllable else "red"
    table.add_row("verdict", f"[{style}]{report.verdict}[/{style}]")
    console.print(table)
    if format_acai(report.acai, report.hover).endswith("*"):
        console.print(escape(EQ13_ZERO_NOTE))


@cli.command()
@airframe_option
@click.option("--max-failed", "-k", default=1, show_default=True, type=int, help="Largest number of failed rotors.")
@formula_option
@_user_errors
def failures(airframe: str, max_failed: int, formula: AcaiFormula) -> None:
    """Every combination of up to K failed rotors: rank, ACAI (with and without yaw), verdict."""
    frame = Airframe.load(airframe)
    result = failure_table(frame, max_failed=max_failed, formula=formula)
    headers, rows = result.rows_for_display()
    table = Table(title=f"{escape(frame.name)}: up to {max_failed} failed rotor(s) (ACAI: Du et al. Theorem 3)")
    for header in headers:
        table.add_column(header, justify="left" if header == "failed" else "right")
    for case, row in zip(result, rows):
        style = "green" if case.controllable else ("yellow" if case.controllable_without_yaw else "red")
        table.add_row(*row, style=style)
    console.print(table)
    if any(cell.endswith("*") for row in rows for cell in row):
        console.print(escape(EQ13_ZERO_NOTE))
    survivable = sum(case.controllable for case in result)
    spinning = sum(case.controllable_without_yaw and not case.controllable for case in result)
    console.print(
        f"{survivable} of {len(result)} cases controllable; {spinning} more only by giving up yaw "
        "(green: controllable; yellow: only without yaw, i.e. thrust, roll and pitch; red: neither)."
    )


@cli.command()
@airframe_option
@click.option("--rotors", default="1,2,5", show_default=True, help="Rotors whose efficiency is swept (1-based).")
@click.option("--step", default=0.04, show_default=True, type=float, help="Grid spacing in [0, 1].")
@click.option("--give-up-yaw", is_flag=True, help="Only thrust, roll and pitch must stay controllable.")
@formula_option
@click.option("--plot", "plot_path", type=click.Path(dir_okay=False), help="Write a Du Fig. 4 style plot (PNG).")
@_user_errors
def scan(airframe: str, rotors: str, step: float, give_up_yaw: bool, formula: AcaiFormula, plot_path: str | None) -> None:
    """Sweep rotor efficiencies over a grid and report the controllable region (Du Fig. 4)."""
    frame = Airframe.load(airframe)
    swept = parse_rotors("rotors", rotors)
    if plot_path is not None and len(swept) != 3:
        raise ValueError(f"rotors: the Fig. 4 plot needs three swept rotors, got {len(swept)}")
    result = efficiency_scan(frame, swept, step, give_up_yaw=give_up_yaw, formula=formula)
    finite = result.acai[~(result.acai == -math.inf)]
    misleading = int(np.sum((result.acai >= 0.0) & (result.hover_code < 0)))
    console.print(
        f"{escape(frame.name)}: rotors {rotors} swept with step {step:g}: {len(result.acai):,} points, "
        f"{int(result.controllable.sum()):,} controllable ({100 * result.controllable_fraction:.1f}%), "
        f"hover feasible at {int(result.hover_feasible.sum()):,}; "
        f"largest ACAI {finite.max() if finite.size else float('nan'):.4f}"
    )
    if misleading:
        console.print(f"{misleading:,} points where {formula} reads >= 0 although the hover wrench lies outside (see hover_code)")
    if plot_path is not None:
        result.plot(plot_path)
        console.print(f"plot written to {plot_path}")


@cli.command()
@click.argument("scenario_file", type=click.Path(dir_okay=False))
@click.option("--plot", "plot_path", type=click.Path(dir_okay=False), help="Write the time-history figure (PNG).")
@_user_errors
def simulate(scenario_file: str, plot_path: str | None) -> None:
    """Fly a scenario file (airframe, controller, faults, wind, noise, duration)."""
    from .scenario import load_scenario

    scenario = load_scenario(scenario_file)
    run = scenario.run()
    altitude = -run.position[:, 2]
    tilt = np.degrees(np.arccos(np.clip(run.primary_axis[:, 2], -1.0, 1.0)))
    table = Table(title=f"{escape(scenario.name)}: {escape(scenario.simulator.airframe.name)}, {scenario.controller_kind}")
    table.add_column("quantity")
    table.add_column("value", justify="right")
    table.add_row("simulated", f"{run.t[-1]:.3f} s of {scenario.duration_s:g} s")
    table.add_row("faults", ", ".join(f"rotor {f.rotor} -> {f.efficiency:g} at {f.time:g} s" for f in run.faults) or "none")
    table.add_row("final position (N, E, alt)", ", ".join(f"{v:.3f}" for v in (*run.position[-1, :2], altitude[-1])))
    table.add_row("max altitude loss", f"{max(0.0, altitude[0] - altitude.min()):.3f} m")
    table.add_row("max horizontal excursion", f"{np.linalg.norm(run.position[:, :2] - run.position[0, :2], axis=1).max():.3f} m")
    table.add_row("max tilt", f"{tilt.max():.1f} deg")
    table.add_row("outcome", f"[red]{escape(str(run.events[0]))}[/red]" if run.diverged else "[green]no divergence[/green]")
    console.print(table)
    if plot_path is not None:
        run.plot(plot_path)
        console.print(f"plot written to {plot_path}")


@cli.command("ftc-report")
@click.option("--out", "out_dir", default="ftc-report", show_default=True, type=click.Path(file_okay=False), help="Directory for the table and figures.")
@click.option("--preset", "preset_name", default="ke-hil", show_default=True, help="Controller preset (gains and vehicle).")
@click.option(
    "--laws", default="feedforward,literal,full-compensation,baseline", show_default=True,
    help="Command laws to compare (comma-separated).",
)
@click.option("--no-figures", is_flag=True, help="Only the table (Markdown and CSV).")
@_user_errors
def ftc_report(out_dir: str, preset_name: str, laws: str, no_figures: bool) -> None:
    """Fly every uniform-passive-FTC scenario (Ke et al.) and write a table and figures."""
    from rich.progress import Progress

    from .control import ke
    from .papers import ke as ke_paper

    chosen_laws = [law.strip() for law in laws.split(",") if law.strip()]
    controller_preset = ke.preset(preset_name)
    scenarios = ke_paper.scenarios()
    runs = []
    with Progress(console=console, transient=True) as progress:
        task = progress.add_task("flying scenarios", total=len(scenarios) * len(chosen_laws))
        for law in chosen_laws:
            for sc in scenarios:
                runs.append(ke_paper.run_scenario(sc, law=cast(KeLaw, law), controller_preset=controller_preset))
                progress.advance(task)
    table = Table(title=f"uniform passive FTC ({escape(preset_name)}): {len(runs)} flights")
    for column in ("scenario", "law", "Ke", "outcome", "r (rad/s)", "n3z", "max alt. loss (m)", "max horiz. (m)", "final horiz. (m)"):
        table.add_column(column, justify="left" if column in ("scenario", "law", "outcome", "Ke") else "right")
    for row in ke_paper.report_rows(runs):
        colour = {"holds-position": "green", "off-station": "yellow"}.get(row["outcome"], "red")
        table.add_row(
            row["scenario"], row["law"], "yes" if row["ke_stabilizable"] else "no",
            f"[{colour}]{row['outcome_label']}[/{colour}]",
            "" if row["r_rad_s"] is None else f"{row['r_rad_s']:.1f}", "" if row["n3z"] is None else f"{row['n3z']:.3f}",
            f"{row['max_altitude_loss_m']:.2f}", f"{row['max_horizontal_error_m']:.2f}", f"{row['final_horizontal_error_m']:.2f}",
        )
    console.print(table)
    path = ke_paper.write_report(runs, out_dir, figures=not no_figures)
    console.print(f"report written to {escape(str(path))}")


def main() -> None:
    cli()

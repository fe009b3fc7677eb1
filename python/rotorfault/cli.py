"""The ``rotorfault`` command line: presets, ACAI, failure tables, efficiency scans, flights and
the uniform-passive-FTC report.

Every user error (bad value, bad type, unreadable file) ends the command with a one-line
``Error: ...`` message on stderr and exit status 1; click's own usage errors exit with 2.
"""

from __future__ import annotations

import contextlib
import functools
import math
import signal
import sys
from collections.abc import Callable, Iterator
from typing import Any, TypeVar, cast

import click
import numpy as np
from rich.console import Console
from rich.markup import escape
from rich.table import Table

from ._typing import AcaiFormula, KeLaw
from ._output import check_output_file
from .airframe import Airframe, rotor_labels
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
            raise click.ClickException(str(exc).replace("\n", " ")) from None
        except RecursionError:
            raise click.ClickException("input: nested too deeply to read (a TOML file of arrays or tables within tables?)") from None
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
@click.option("--plot", "plot_path", type=click.Path(dir_okay=False), help="Write a Du Fig. 4 style plot (.png, .pdf or .svg).")
@click.option("--force", is_flag=True, help="Replace an existing --plot file or --out output.")
@click.option("--out", "out_path", type=click.Path(), help="Stream the rows to this Parquet dataset directory (chunked, resumable).")
@click.option("--resume", is_flag=True, help="Continue an interrupted --out scan with the same arguments (skips the chunks written).")
@click.option("--dask", "dask_address", help="Run the chunks on a Dask cluster: a scheduler address (tcp://host:8786) or local:N.")
@click.option("--axis", "extra_axes", multiple=True, help="An airframe parameter axis NAME=v1,v2,... (max_thrust_n, mass_kg, drag_torque_ratio_m, arm_length_m, ...); with --out.")
@click.option("--chunk-points", default=1 << 20, show_default=True, type=int, help="Points per chunk (memory and resume granularity) with --out.")
@_user_errors
def scan(
    airframe: str, rotors: str, step: float, give_up_yaw: bool, formula: AcaiFormula, plot_path: str | None, force: bool,
    out_path: str | None, resume: bool, dask_address: str | None, extra_axes: tuple[str, ...], chunk_points: int,
) -> None:
    """Sweep rotor efficiencies over a grid and report the controllable region (Du Fig. 4)."""
    if plot_path is not None:
        check_output_file("plot", plot_path, force=force)
    if out_path is not None:
        _scan_to_parquet(airframe, rotors, step, give_up_yaw, plot_path, force, out_path, resume, dask_address, extra_axes, chunk_points)
        return
    if resume or dask_address or extra_axes:
        raise ValueError("out: --resume, --dask and --axis need --out (a Parquet output)")
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


def _scan_to_parquet(
    airframe: str, rotors: str, step: float, give_up_yaw: bool, plot_path: str | None, force: bool,
    out_path: str, resume: bool, dask_address: str | None, extra_axes: tuple[str, ...], chunk_points: int,
) -> None:
    from .scan import acai_scan

    frame = Airframe.load(airframe)
    swept = parse_rotors("rotors", rotors)
    if not 0.0 < step <= 1.0 or not math.isclose(round(1.0 / step) * step, 1.0, rel_tol=0.0, abs_tol=1e-9):
        raise ValueError(f"step: must lie in (0, 1] and divide 1 evenly (0.04, 0.05, 0.1, ...), got {step}")
    levels = np.linspace(0.0, 1.0, int(round(1.0 / step)) + 1)
    axes: dict[str, Any] = {}
    for item in extra_axes:
        name, sep, values = item.partition("=")
        if not sep:
            raise ValueError(f"axis: expected NAME=v1,v2,..., got {item!r}")
        axes[name.strip()] = parse_numbers(f"axis {name.strip()}", values)
    for r in swept:
        axes[f"efficiency_{r}"] = levels
    if plot_path is not None and (len(swept) != 3 or extra_axes):
        raise ValueError("plot: the Fig. 4 plot needs exactly three swept rotors and no --axis")
    result = acai_scan(
        frame, axes, give_up_yaw=give_up_yaw, out=out_path, resume=resume, force=force,
        backend="dask" if dask_address else "local", dask=dask_address, chunk_points=chunk_points, progress=True,
    )
    ok = result.controllable_count(give_up_yaw=give_up_yaw)
    console.print(
        f"{escape(frame.name)}: {result.total:,} points ({result.computed_chunks} chunks computed, {result.skipped_chunks} already written) "
        f"in {result.seconds:.1f} s; {ok:,} controllable{' giving up yaw' if give_up_yaw else ''} "
        f"({100 * ok / max(result.total, 1):.1f}%); rows in {escape(out_path)}"
    )
    if plot_path is not None:
        result.plot(plot_path, give_up_yaw=give_up_yaw)
        console.print(f"plot written to {plot_path}")


@cli.command()
@airframe_option
@click.option("--parameter", help="Rank again for each value of this airframe parameter (arm_length_m, max_thrust_n, mass_kg, ...).")
@click.option("--values", help="Values of --parameter, comma-separated.")
@click.option(
    "--formula", type=click.Choice(["eq13", "facet-margin"]), default="facet-margin", show_default=True,
    help="ACAI of an infeasible hover: facet-margin (how far outside, negative) or eq13 (Du's 0).",
)
@click.option("--top", default=0, type=int, help="Show only the best N designs (per parameter value; 0: all).")
@_user_errors
def design(airframe: str, parameter: str | None, values: str | None, formula: AcaiFormula, top: int) -> None:
    """Rank every spin-direction assignment of the airframe's frame by failure tolerance."""
    from .design import design_search

    frame = Airframe.load(airframe)
    numbers = parse_numbers("values", values) if values is not None else None
    result = design_search(frame, parameter=parameter, values=numbers, formula=formula)
    if top < 0:
        raise ValueError(f"top: must be 0 (all) or a positive count, got {top}")
    click.echo(result.format(top))
    for value in dict.fromkeys(d.parameter_value for d in result.designs):
        best = result.best(value)
        where = "" if value is None else f" at {parameter} = {value:g}"
        click.echo(
            f"best{where}: {best.spins}, controllable after {best.controllable_single} of {len(best.single)} single failures\n"
            f"  (rotors {', '.join(map(str, best.survivable_single)) or 'none'}), worst single-failure ACAI {best.worst_single:.4f}"
        )


@cli.command()
@click.argument("scenario_file", type=click.Path(dir_okay=False))
@click.option("--plot", "plot_path", type=click.Path(dir_okay=False), help="Write the time-history figure (.png, .pdf or .svg).")
@click.option("--force", is_flag=True, help="Replace an existing --plot file.")
@_user_errors
def simulate(scenario_file: str, plot_path: str | None, force: bool) -> None:
    """Fly a scenario file (airframe, controller, faults, wind, noise, duration)."""
    from .scenario import load_scenario

    if plot_path is not None:
        check_output_file("plot", plot_path, force=force)
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
        run.plot(plot_path, title=scenario.title, setpoints=scenario.setpoints)
        console.print(f"plot written to {escape(plot_path)}")


class _Terminated(BaseException):
    """SIGTERM, raised in the main thread so that partial outputs are cleaned up (a
    BaseException, like KeyboardInterrupt, so no library's `except Exception` swallows it)."""


@cli.command()
@click.option("--airframe", "-a", required=True, help="Preset name, airframe TOML, or a PX4 .params file.")
@click.option("--require", "required", type=click.Choice(["none", "single", "double"]), default="none", show_default=True,
              help="Failure class that must stay hoverable (double includes single); exit status 3 if not.")
@click.option("--json", "json_path", default=None, help="Also write the certificate as JSON to this file ('-': stdout only).")
@click.option("--force", is_flag=True, help="Replace an existing JSON file.")
@_user_errors
def certify(airframe: str, required: str, json_path: str | None, force: bool) -> None:
    """For every single and double rotor failure: hover with all axes, only without yaw, or not at
    all; the ACAI margins, the thrust-to-weight left and which axes an allocator must drop."""
    import json

    from . import certify as cert_module
    from ._output import write_text

    if json_path not in (None, "-"):
        check_output_file("--json", json_path, suffixes=(".json",), force=force)
    frame = Airframe.load(airframe)
    cert = cert_module.certify(frame, max_failed=min(2, frame.rotor_count))
    text = json.dumps(cert.to_dict(), indent=2) + "\n"
    if json_path == "-":
        click.echo(text, nl=False)
    else:
        headers, rows = cert_module.rows_for_display(cert)
        kind = "fully actuated" if cert.fully_actuated else "not fully actuated"
        table = Table(title=f"{escape(frame.name)}: {frame.rotor_count} rotors, {kind}")
        for header in headers:
            table.add_column(header, justify="left" if header in ("failed", "hover", "allocator drops") else "right")
        styles = {"all-axes": "green", "without-yaw": "yellow", "no": "red"}
        for case, row in zip(cert.cases, rows):
            table.add_row(*row, style=styles[case.hover])
        console.print(table)
        if json_path is not None:
            write_text(json_path, text)
    failing = cert.failing(required)
    if failing:
        listed = "; ".join(rotor_labels(c.failed) for c in failing)
        click.echo(f"certificate: FAILED: --require {required}: cannot hover with rotor(s) {listed} failed", err=True)
        sys.exit(3)
    if required != "none" and json_path != "-":
        console.print(f"certificate: every {required} failure (and fewer) leaves a hoverable vehicle")


def _raise_terminated(signum: int, frame: Any) -> None:
    raise _Terminated()


@contextlib.contextmanager
def _report_interruptions() -> Iterator[None]:
    """A report command's work: SIGTERM becomes an exception (so the temporary report directory
    is cleaned up) and SIGTERM or Ctrl-C end with a one-line message saying the previous report is
    unchanged. Outside the main thread (an embedding application) SIGTERM is left alone."""
    previous = signal.getsignal(signal.SIGTERM)
    in_main = True
    try:
        signal.signal(signal.SIGTERM, _raise_terminated)
    except ValueError:
        in_main = False
    try:
        yield
    except _Terminated:
        raise click.ClickException("terminated (SIGTERM): no report written, the previous one is unchanged") from None
    except KeyboardInterrupt:
        raise click.ClickException("interrupted: no report written, the previous one is unchanged") from None
    finally:
        if in_main:
            signal.signal(signal.SIGTERM, previous)


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
@_user_errors
def ftc_report(out_dir: str, preset_name: str, laws: str, scenario_names: str | None, no_figures: bool, force: bool) -> None:
    """Fly every uniform-passive-FTC scenario (Ke et al.) and write a table and figures."""
    from typing import get_args

    from ._output import check_output_directory
    from .control import ke
    from .papers import ke as ke_paper

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
    check_output_directory("out", out_dir, force=force)
    controller_preset = ke.preset(preset_name)
    with _report_interruptions():
        runs = []
        console.print(f"flying {len(scenarios) * len(chosen_laws)} runs", highlight=False)
        for law in chosen_laws:
            for sc in scenarios:
                runs.append(ke_paper.run_scenario(sc, law=cast(KeLaw, law), controller_preset=controller_preset))
        _print_ftc_table(runs, preset_name)
        console.print(f"writing the report to {escape(out_dir)}", highlight=False)
        command = "rotorfault " + " ".join(sys.argv[1:]) if sys.argv[1:] else "rotorfault ftc-report"
        path = ke_paper.write_report(runs, out_dir, figures=not no_figures, force=force, command=command)
    console.print(f"report written to {escape(str(path))}")


@cli.command("vpp-report")
@click.option("--out", "out_dir", default="vpp-report", show_default=True, type=click.Path(file_okay=False), help="Directory for the tables and figures (replaced as a whole).")
@click.option("--quick", is_flag=True, help="20 s flights (a smoke test, not the paper's 60 s).")
@click.option("--force", is_flag=True, help="Replace an existing report in --out.")
@_user_errors
def vpp_report(out_dir: str, quick: bool, force: bool) -> None:
    """Wang et al.'s VPP quadcopter: the fixed-pitch comparison (hover, controllability,
    stabilisability, ACAI), the feasible trim speeds, and Section 4's three flights with
    propeller 1 failed."""
    from ._output import check_output_directory
    from .papers import wang as wang_paper

    check_output_directory("out", out_dir, force=force)
    command = "rotorfault " + " ".join(sys.argv[1:]) if sys.argv[1:] else "rotorfault vpp-report"
    with _report_interruptions():
        path = wang_paper.write_report(out_dir, quick=quick, force=force, command=command)
    for line in wang_paper.comparison_table():
        console.print(escape(line), highlight=False, soft_wrap=True)
    console.print(f"report written to {escape(str(path))}")


@cli.command("lanzon-report")
@click.option("--out", "out_dir", default="lanzon-report", show_default=True, type=click.Path(file_okay=False), help="Directory for the table, figures and CSV (replaced as a whole).")
@click.option("--runs", "mc_runs", default=1000, show_default=True, type=int, help="Monte Carlo runs per controller (0: none).")
@click.option("--quick", is_flag=True, help="20 s flights and 50 Monte Carlo runs per controller (a smoke test, not the paper's 60 s).")
@click.option("--no-figures", is_flag=True, help="Only the tables (Markdown and CSV).")
@click.option("--force", is_flag=True, help="Replace an existing report in --out.")
@_user_errors
def lanzon_report(out_dir: str, mc_runs: int, quick: bool, no_figures: bool, force: bool) -> None:
    """Fly Lanzon et al.'s two flights three ways (paper's design without and with limits, ours),
    for both I_zz values, run the Monte Carlo comparison with Ke's controller, and write a report."""
    from ._output import check_output_directory
    from .papers import lanzon as lanzon_paper

    if mc_runs < 0:
        raise ValueError(f"runs: must be >= 0, got {mc_runs}")
    check_output_directory("out", out_dir, force=force)
    duration = 20.0 if quick else None
    runs_per = min(mc_runs, 50) if quick else mc_runs
    with _report_interruptions():
        console.print("flying scenarios A and B, cases (a), (b), (c), I_zz 1.16e-3 and 1.16e-2: 12 flights", highlight=False)
        runs = lanzon_paper.three_way(duration_s=duration)
        for line in lanzon_paper.three_way_table(runs):
            console.print(escape(line), highlight=False, soft_wrap=True)
        results = []
        if runs_per:
            mc_duration = 20.0 if quick else 60.0
            for controller in ("lanzon", "ke"):
                results.append(lanzon_paper.monte_carlo(controller, runs=runs_per, duration_s=mc_duration, progress=True))
            for line in lanzon_paper.monte_carlo_table(results):
                console.print(escape(line), highlight=False, soft_wrap=True)
        console.print(f"writing the report to {escape(out_dir)}", highlight=False)
        command = "rotorfault " + " ".join(sys.argv[1:]) if sys.argv[1:] else "rotorfault lanzon-report"
        path = lanzon_paper.write_report(runs, out_dir, monte_carlo_results=results, figures=not no_figures, force=force,
                                         command=command)
    console.print(f"report written to {escape(str(path))}")


def _print_ftc_table(runs: list[Any], preset_name: str) -> None:
    """The report table on the terminal: one wide table when it fits, otherwise (below 120
    columns) one narrow table per law with the columns that matter."""
    from rich import box

    from .papers import ke as ke_paper

    rows = ke_paper.report_rows(runs)

    def outcome(row: dict[str, Any]) -> str:
        colour = {"holds-position": "green", "circling": "yellow", "off-station": "yellow"}.get(row["outcome"], "red")
        return f"[{colour}]{escape(row['outcome_label'])}[/{colour}]"

    def num(row: dict[str, Any], column: str, digits: int) -> str:
        return escape(ke_paper.cell(row, column, digits))

    def horizontal(row: dict[str, Any]) -> str:
        if row["max_horizontal_error_m"] is None:
            return num(row, "max_horizontal_error_m", 1)
        return f"{row['max_horizontal_error_m']:.1f} / {row['final_horizontal_error_m']:.1f}"

    title = f"uniform passive FTC ({escape(preset_name)}): {len(runs)} flights"
    if console.width >= 120:
        table = Table(title=title)
        for column in ("scenario", "law", "Ke", "outcome", "r (rad/s)", "n3z", "max alt. loss (m)", "horiz. max / final (m)"):
            table.add_column(column, justify="left" if column in ("scenario", "law", "outcome", "Ke") else "right")
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
        table.add_column("outcome", no_wrap=True)
        table.add_column("r", justify="right", no_wrap=True)
        table.add_column("alt. loss", justify="right")
        table.add_column("horiz. max/final", justify="right")
        for row in rows:
            if row["law"] != law:
                continue
            name = row["scenario"] + ("" if row["ke_stabilizable"] else "*")
            if row["lost_at_s"] is not None:
                lost = f"[red]{escape(row['outcome_label'])} at {row['lost_at_s']:.2f} s[/red]"
                table.add_row(name, lost, "lost", "lost", "lost")
                continue
            r = "unsettled" if row["r_rad_s"] is None else num(row, "r_rad_s", 1)
            h = f"{row['max_horizontal_error_m']:.1f}/{row['final_horizontal_error_m']:.1f}"
            table.add_row(name, outcome(row), r, num(row, "max_altitude_loss_m", 1), h)
        console.print(table)


@cli.command("reproduce")
@click.option("--out", "out_dir", default="report", show_default=True, type=click.Path(file_okay=False), help="Directory for index.html and the figures (replaced as a whole).")
@click.option("--quick", is_flag=True, help="Coarser grids and fewer flights (under 2 minutes).")
@click.option("--benches", "bench_dir", default=None, type=click.Path(file_okay=False), help="Directory of bench results (*.json; default: benches/results of the source tree).")
@click.option("--force", is_flag=True, help="Replace an existing report in --out.")
@_user_errors
def reproduce(out_dir: str, quick: bool, bench_dir: str | None, force: bool) -> None:
    """Reproduce every result of the four papers into one static report (index.html + figures)."""
    from ._output import check_output_directory
    from .papers import reproduce as reproduce_

    check_output_directory("out", out_dir, force=force)
    command = "rotorfault " + " ".join(sys.argv[1:]) if sys.argv[1:] else "rotorfault reproduce"
    with _report_interruptions():
        result = reproduce_.write_reproduce(
            out_dir, quick=quick, force=force, command=command, bench_directory=bench_dir,
            progress=lambda text: console.print(escape(text), highlight=False),
        )
    for section in result.sections:
        numbers = [n for part in [section, *section.parts] for n in part.numbers]
        state = "not landed yet" if not section.landed else f"{sum(n.status == 'pass' for n in numbers)} of {len(numbers)} printed numbers pass"
        pending = [part.title for part in section.parts if not part.landed]
        if pending:
            state += f"; not landed yet: {', '.join(pending)}"
        console.print(f"{escape(section.key)}: {escape(state)}", highlight=False)
    console.print(f"report written to {escape(str(result.path))} in {result.run_time_s:.1f} s")



def main() -> None:
    cli()


@cli.command("campaign")
@click.argument("campaign_file", type=click.Path(dir_okay=False), required=False)
@click.option("--runs", type=int, help="Override the file's run count.")
@click.option("--plot", "plot_path", type=click.Path(dir_okay=False), help="Write histograms and the envelope plot (.png, .pdf or .svg).")
@click.option("--tune", "tune_gains", is_flag=True, help="Robust tuning of Ke's gains on the single and double failure campaign instead.")
@click.option("--quick", is_flag=True, help="With --tune: a small search (12 candidates x 24 scenarios, about a minute).")
@click.option("--out", "out_path", type=click.Path(), help="Stream the per-run rows to this Parquet dataset directory (chunked, resumable; the campaign is in its manifest).")
@click.option("--resume", is_flag=True, help="Continue an interrupted --out campaign with the same campaign (skips the chunks written).")
@click.option("--dask", "dask_address", help="Run the chunks on a Dask cluster: a scheduler address (tcp://host:8786) or local:N.")
@click.option("--force", is_flag=True, help="Replace an existing --plot file or --out output.")
@click.option("--progress/--no-progress", default=True, help="Show a progress bar on standard error.")
@_user_errors
def campaign_command(
    campaign_file: str | None, runs: int | None, plot_path: str | None, tune_gains: bool, quick: bool, out_path: str | None,
    resume: bool, dask_address: str | None, force: bool, progress: bool,
) -> None:
    """Fly a fault campaign (a TOML file of rotorfault.campaign.Campaign fields; default: every
    single failure of Ke's quadcopter) and report survival, worst cases and excursions."""
    from dataclasses import replace

    from .campaign import Campaign, run_campaign, tune, tuning_campaign

    if plot_path is not None:
        check_output_file("plot", plot_path, force=force)
    if out_path is None and (resume or dask_address):
        raise ValueError("out: --resume and --dask need --out (a Parquet output)")
    if tune_gains:
        if out_path is not None:
            raise ValueError("out: --tune writes no Parquet output")
        base = tuning_campaign(runs=24 if quick else 200)
        tuned = tune(base, maxiter=1 if quick else 9, popsize=1, progress=progress)
        console.print(escape(tuned.table()))
        return
    campaign = Campaign() if campaign_file is None else Campaign.from_toml(campaign_file)
    if runs is not None:
        campaign = replace(campaign, runs=runs)
    result = run_campaign(
        campaign, out=out_path, resume=resume, force=force, backend="dask" if dask_address else "local", dask=dask_address, progress=progress,
    )
    if out_path is not None:
        console.print(
            f"{campaign.runs:,} runs ({result.computed_chunks} chunks flown, {result.skipped_chunks} already written) "
            f"in {result.seconds:.1f} s; rows in {escape(out_path)}",
            highlight=False,
        )
    console.print(escape(result.table()))
    if plot_path is not None:
        result.plot(plot_path)
        console.print(f"plot written to {escape(plot_path)}")

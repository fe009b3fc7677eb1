"""Commands about an airframe before it flies: ``airframes``, ``acai``, ``failures``, ``certify``
(the analysis room, and the certificate study)."""

from __future__ import annotations

import sys

import click
from rich.markup import escape
from rich.table import Table

from .._typing import AcaiFormula
from .._util.output import check_output_file
from ..analysis import EQ13_ZERO_NOTE, Airframe, acai_label, controllability, failure_table, format_acai
from ..analysis.airframe import rotor_labels
from .app import _user_errors, airframe_option, cli, console, formula_option, parse_numbers


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
@click.option("--give-up-yaw", is_flag=True, help="Give up yaw: only thrust, roll and pitch must stay controllable.")
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
    table.add_row("axes", "thrust, roll, pitch (yaw given up)" if give_up_yaw else "thrust, roll, pitch, yaw")
    table.add_row("rank C(A, B)", f"{report.controllability_rank} of {report.state_dimension}")
    table.add_row("rank B_f", f"{report.effectiveness_rank} of {report.virtual_control_dimension}")
    table.add_row(acai_label(formula), format_acai(report.acai, report.hover))
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
    """Every combination of up to K failed rotors: rank, ACAI (all axes and giving up yaw), verdict."""
    frame = Airframe.load(airframe)
    result = failure_table(frame, max_failed=max_failed, formula=formula)
    headers, rows = result.rows_for_display()
    table = Table(title=f"{escape(frame.name)}: up to {max_failed} failed rotor(s) ({acai_label(formula)}: Du et al. Theorem 3)")
    for header in headers:
        table.add_column(header, justify="left" if header == "failed" else "right")
    for case, row in zip(result, rows):
        style = "green" if case.controllable else ("yellow" if case.controllable_give_up_yaw else "red")
        table.add_row(*row, style=style)
    console.print(table)
    if any(cell.endswith("*") for row in rows for cell in row):
        console.print(escape(EQ13_ZERO_NOTE))
    survivable = sum(case.controllable for case in result)
    spinning = sum(case.controllable_give_up_yaw and not case.controllable for case in result)
    console.print(
        f"{survivable} of {len(result)} cases controllable; {spinning} more only by giving up yaw "
        "(green: controllable; yellow: only giving up yaw, i.e. thrust, roll and pitch; red: neither)."
    )


@cli.command()
@click.option("--airframe", "-a", required=True, help="Preset name, airframe TOML, or a PX4 .params file.")
@click.option("--require", "required", type=click.Choice(["none", "single", "double"]), default="none", show_default=True,
              help="Failure class that must stay hoverable (double includes single); exit status 3 if not.")
@click.option("--json", "json_path", default=None, help="Also write the certificate as JSON to this file ('-': stdout only).")
@click.option("--force", is_flag=True, help="Replace an existing JSON file.")
@click.option("--spinning", is_flag=True,
              help="Also the best relaxed hover (survivable by spinning: margin, spin rate, carrying rotors); "
                   "--require then accepts a case that hovers statically or by spinning.")
@click.option("--rotational-drag", "rotational_drag", type=float, default=None,
              help="With --spinning: the vehicle's rotational damping k_r (N m s), which sets the spin rate (default 0).")
@_user_errors
def certify(airframe: str, required: str, json_path: str | None, force: bool, spinning: bool,
            rotational_drag: float | None) -> None:
    """For every single and double rotor failure: hover with all axes, only by giving up yaw, or
    not at all; the ACAI (facet margin), the thrust-to-weight left and which axes an allocator must
    drop; with --spinning, beside it, the best relaxed hover (Mueller and D'Andrea)."""
    import json

    from ..flight import Drag
    from ..studies.certify import certify as certify_airframe, rows_for_display
    from .._util.output import write_text

    if rotational_drag is not None and not spinning:
        raise click.UsageError("--rotational-drag: describes the relaxed hover; give it with --spinning")
    drag = None if rotational_drag is None else Drag(rotational_n_m_s=rotational_drag)
    if json_path not in (None, "-"):
        check_output_file("--json", json_path, suffixes=(".json",), force=force)
    frame = Airframe.load(airframe)
    cert = certify_airframe(frame, max_failed=min(2, frame.rotor_count), spinning=spinning, drag=drag)
    text = json.dumps(cert.to_dict(), indent=2) + "\n"
    if json_path == "-":
        click.echo(text, nl=False)
    else:
        headers, rows = rows_for_display(cert)
        kind = "fully actuated" if cert.fully_actuated else "not fully actuated"
        table = Table(title=f"{escape(frame.name)}: {frame.rotor_count} rotors, {kind}")
        for header in headers:
            table.add_column(header, justify="left" if header in ("failed", "hover", "allocator drops", "relaxed hover") else "right")
        styles = {"all-axes": "green", "give-up-yaw": "yellow", "no": "red"}
        for case, row in zip(cert.cases, rows):
            table.add_row(*row, style=styles[case.hover])
        console.print(table)
        if json_path is not None:
            write_text(json_path, text)
    failing = cert.failing_spinning(required) if spinning else cert.failing(required)
    if failing:
        listed = "; ".join(rotor_labels(c.failed) for c in failing)
        how = " nor spin" if spinning else ""
        click.echo(f"certificate: FAILED: --require {required}: cannot hover{how} with rotor(s) {listed} failed", err=True)
        sys.exit(3)
    if required != "none" and json_path != "-":
        how = " (statically or by spinning)" if spinning else ""
        console.print(f"certificate: every {required} failure (and fewer) leaves a hoverable vehicle{how}")

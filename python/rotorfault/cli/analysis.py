"""Commands about an airframe before it flies: ``airframes``, ``acai``, ``failures``, ``certify``
(the analysis room, and the certificate study)."""

from __future__ import annotations

import sys
from typing import Any

import click
from rich import box
from rich.markup import escape

from .._typing import AcaiFormula
from .._util.output import check_output_file
from ..analysis import EQ13_ZERO_NOTE, HOVER_WRENCH_NOTE, Airframe, acai_label, controllability, failure_table, format_acai, hover_wrench_text
from ..allocation import hover_distances
from ..analysis.airframe import rotor_labels
from ..studies.certify import ALL_AXES
from .app import _user_errors, airframe_option, cli, formula_option, load_airframe, mass_option, parse_numbers
from .output import EXIT_REQUIREMENT, CommandOutput, Output, Rows, output_options, records


@cli.command()
@output_options
@_user_errors
def airframes(output: Output) -> None:
    """List the preset airframes."""
    rows: list[dict[str, Any]] = []
    for name in Airframe.presets():
        a = Airframe.preset(name)
        rows.append({"name": name, "rotors": a.rotor_count, "mass_kg": a.mass_kg, "max_thrust_n": float(a.max_thrust_n.max()),
                     "description": a.description})

    def human(out: Output) -> None:
        table = out.table(title="rotorfault presets")
        for column in ("name", "rotors", "mass (kg)", "max thrust (N)", "description"):
            table.add_column(column)
        for row in rows:
            table.add_row(row["name"], str(row["rotors"]), f"{row['mass_kg']:g}", f"{row['max_thrust_n']:g}", escape(row["description"]))
        out.print(table)

    output.emit(CommandOutput("airframes", tables=[Rows("airframes", rows)], csv_table="airframes", human=human))


@cli.command()
@airframe_option
@click.option("--efficiency", help="Rotor efficiencies, comma-separated (default: the airframe's own).")
@click.option("--give-up-yaw", is_flag=True, help="Give up yaw: only thrust, roll and pitch must stay controllable.")
@formula_option
@output_options
@_user_errors
def acai(airframe: str, efficiency: str | None, give_up_yaw: bool, formula: AcaiFormula, output: Output) -> None:
    """Run Du's controllability test and print the ACAI."""
    frame = load_airframe(airframe)
    efficiencies = None if efficiency is None else parse_numbers("efficiency", efficiency)
    report = controllability(frame, efficiencies, give_up_yaw=give_up_yaw, formula=formula)
    fields = {
        "airframe": frame.name, "efficiency": list(report.efficiency), "axes": report.axes, "give_up_yaw": report.give_up_yaw,
        "formula": report.formula, "controllability_rank": report.controllability_rank, "state_dimension": report.state_dimension,
        "effectiveness_rank": report.effectiveness_rank, "virtual_control_dimension": report.virtual_control_dimension,
        "acai": float(report.acai), "hover": report.hover, "controllable": report.controllable, "verdict": report.verdict,
    }

    def human(out: Output) -> None:
        table = out.table(title=f"{escape(frame.name)}: controllability", show_header=False)
        table.add_column("quantity")
        table.add_column("value")
        table.add_row("efficiency", ", ".join(f"{e:g}" for e in report.efficiency))
        table.add_row("axes", "thrust, roll, pitch (yaw given up)" if give_up_yaw else "thrust, roll, pitch, yaw")
        table.add_row("rank C(A, B)", f"{report.controllability_rank} of {report.state_dimension}")
        table.add_row("rank B_f", f"{report.effectiveness_rank} of {report.virtual_control_dimension}")
        table.add_row(acai_label(formula), format_acai(report.acai, report.hover))
        style = "green" if report.controllable else "red"
        table.add_row("verdict", f"[{style}]{escape(report.verdict)}[/{style}]")
        out.print(table)
        if format_acai(report.acai, report.hover).endswith("*"):
            out.print(escape(EQ13_ZERO_NOTE))

    output.emit(CommandOutput("acai", fields, human=human))


@cli.command()
@airframe_option
@click.option("--max-failed", "-k", default=1, show_default=True, type=int, help="Largest number of failed rotors.")
@formula_option
@output_options
@_user_errors
def failures(airframe: str, max_failed: int, formula: AcaiFormula, output: Output) -> None:
    """Every combination of up to K failed rotors: rank, ACAI (all axes and giving up yaw), verdict."""
    frame = load_airframe(airframe)
    result = failure_table(frame, max_failed=max_failed, formula=formula)
    survivable = sum(case.controllable for case in result)
    spinning = sum(case.controllable_give_up_yaw and not case.controllable for case in result)
    fields = {"airframe": frame.name, "max_failed": max_failed, "formula": result.formula, "case_count": len(result),
              "controllable_count": survivable, "give_up_yaw_only_count": spinning}

    def human(out: Output) -> None:
        # The hover wrench's distances are for the table only (one QP per case): not for --format json/csv.
        headers, rows = result.rows_for_display(hover_distances(frame, [case.failed for case in result]))
        # Below 120 columns the rank and "ok" columns are left out so that every cell stays whole (the
        # row's colour and the count below say which cases are controllable).
        narrow = out.console.width < 120
        shown = [k for k, h in enumerate(headers) if not (narrow and (h.startswith("rank ") or h.startswith("ok")))]
        title = f"{escape(frame.name)}: up to {max_failed} failed rotor(s) ({acai_label(formula)}: Du et al. Theorem 3)"
        table = out.table(title=title, box=box.SIMPLE_HEAD, pad_edge=False) if narrow else out.table(title=title)
        for k in shown:
            header = headers[k]
            wrench = header.startswith("hover wrench")
            # Every cell whole (the headers may wrap): the widest value of the column.
            width = max(len(row[k]) for row in rows) if rows else None
            table.add_column(header, justify="left" if header == "failed" or wrench else "right", min_width=width)
        for case, row in zip(result, rows):
            style = "green" if case.controllable else ("yellow" if case.controllable_give_up_yaw else "red")
            table.add_row(*(row[k] for k in shown), style=style)
        out.print(table)
        if narrow:
            out.print("(rank C, rank B_f and Du's verdict per case: in a terminal of 120 columns or more)", highlight=False)
        if any(cell.endswith("*") for row in rows for cell in row):
            out.print(escape(EQ13_ZERO_NOTE))
        out.print(escape(HOVER_WRENCH_NOTE), highlight=False)
        out.print(
            f"{survivable} of {len(result)} cases controllable; {spinning} more only by giving up yaw "
            "(green: controllable; yellow: only giving up yaw, i.e. thrust, roll and pitch; red: neither)."
        )

    output.emit(CommandOutput("failures", fields, [Rows("cases", records(result))], csv_table="cases", human=human))


@cli.command()
@click.option("--airframe", "-a", required=True, help="Preset name, airframe TOML, or a PX4 .params file.")
@mass_option
@click.option("--require", "required", type=click.Choice(["none", "single", "double"]), default="none", show_default=True,
              help="Failure class that must stay hoverable with --require-axes (double includes single); exit status 3 if not.")
@click.option("--require-axes", "required_axes", default=",".join(ALL_AXES), show_default=True,
              help="Axes that must remain after those failures: thrust,roll,pitch,yaw or thrust,roll,pitch (giving up yaw: spinning).")
@click.option("--json", "json_path", default=None, help="Also write the certificate as JSON to this file ('-': stdout only).")
@click.option("--force", is_flag=True, help="Replace an existing JSON file.")
@click.option("--spinning", is_flag=True,
              help="Also the best relaxed hover (survivable by spinning: margin, spin rate, carrying rotors) and whether "
                   "the spin can be entered from hover; --require then accepts a case that hovers statically with all axes "
                   "or by a steady spin not excluded from hover (without --rotational-drag the spin rate is free: a best "
                   "spin at the search limit is searched again below it, at a quarter of it, and that slower spin certified).")
@click.option("--rotational-drag", "rotational_drag", type=float, default=None,
              help="With --spinning: the vehicle's rotational damping k_r (N m s), which sets the spin rate (default 0).")
@output_options
@_user_errors
def certify(airframe: str, required: str, required_axes: str, json_path: str | None, force: bool, spinning: bool,
            rotational_drag: float | None, output: Output) -> None:
    """For every single and double rotor failure: hover with all axes, only by giving up yaw, or
    not at all; where the hover wrench lies (inside, on the boundary, outside and how far), the
    ACAI (facet margin), the thrust-to-weight left and which axes an allocator must drop; with
    --spinning, beside it, the best relaxed hover (Mueller and D'Andrea) and whether it can be
    entered from hover ("spinning solution exists, not reachable from hover" where not)."""
    import json

    from ..flight import Drag
    from ..studies.certify import certify as certify_airframe, parse_axes, rows_for_display
    from .._util.output import write_text

    axes = parse_axes("require_axes", required_axes)
    if rotational_drag is not None and not spinning:
        raise click.UsageError("--rotational-drag: describes the relaxed hover; give it with --spinning")
    drag = None if rotational_drag is None else Drag(rotational_n_m_s=rotational_drag)
    if json_path not in (None, "-"):
        check_output_file("--json", json_path, suffixes=(".json",), force=force)
    if json_path == "-" and output.format != "table":
        raise ValueError("json: --json - writes the certificate on standard output; it cannot be combined with --format json or csv")
    frame = load_airframe(airframe)
    cert = certify_airframe(frame, max_failed=min(2, frame.rotor_count), spinning=spinning, drag=drag)
    text = json.dumps(cert.to_dict(), indent=2) + "\n"
    failing = cert.failing_spinning(required) if spinning else cert.failing(required, axes=axes)
    named = ", ".join(axes)
    holds_how = "statically or by spinning" if spinning else f"with {named}"
    fields = {"airframe": cert.airframe, "rotor_count": cert.rotor_count, "fully_actuated": cert.fully_actuated, "require": required,
              "require_axes": list(axes), "requirement_met": not failing, "failing": [list(c.failed) for c in failing]}

    def human(out: Output) -> None:
        headers, rows = rows_for_display(cert)
        kind = "fully actuated" if cert.fully_actuated else "not fully actuated"
        table = out.table(title=f"{escape(frame.name)}: {frame.rotor_count} rotors, {kind}")
        for header in headers:
            table.add_column(header, justify="left" if header in ("failed", "hover", "allocator drops", "relaxed hover") or header.startswith("hover wrench") else "right")
        styles = {"all-axes": "green", "give-up-yaw": "yellow", "no": "red"}
        for case, row in zip(cert.cases, rows):
            table.add_row(*row, style=styles[case.hover])
        out.print(table)
        out.print(escape(HOVER_WRENCH_NOTE), highlight=False)
        if required != "none" and not failing:
            out.print(f"certificate: every {required} failure (and fewer) leaves a vehicle that hovers {holds_how}")

    if json_path == "-":
        if not output.quiet:
            click.echo(text, nl=False)
    else:
        output.emit(CommandOutput("certify", fields, [Rows("cases", records(cert))], csv_table="cases", human=human))
        if json_path is not None:
            write_text(json_path, text)
    if failing:
        if spinning:
            listed = "; ".join(rotor_labels(c.failed) + _spin_failure_reason(c.relaxed_hover) for c in failing)
            click.echo(f"certificate: FAILED: --require {required} --spinning: cannot hover nor enter a spin from hover with rotor(s) "
                       f"{listed} failed", err=True)
        else:
            listed = "; ".join(f"{rotor_labels(c.failed)} ({c.hover}, all axes {hover_wrench_text(c.hover_wrench, c.distance)})" for c in failing)
            click.echo(f"certificate: FAILED: --require {required} --require-axes {','.join(axes)}: cannot hover with {named} kept "
                       f"with rotor(s) {listed} failed", err=True)
        sys.exit(EXIT_REQUIREMENT)


def _spin_failure_reason(verdict: Any) -> str:
    """Why a failing case's spinning solution does not count (certify's rule, ``survives``)."""
    if verdict is None or verdict.hover != "spinning":
        return ""
    if not verdict.steady:
        return " (spin at the search's rate limit without rotational damping: no steady spin)"
    return " (spinning solution exists, not reachable from hover)"

"""Commands that run studies: ``scan``, ``design``, ``simulate``, ``campaign``."""

from __future__ import annotations

import math
from typing import Any, cast, get_args

import click
import numpy as np
from rich.markup import escape

from .._typing import AcaiFormula, SensorSuiteName
from .._util.output import check_output_file
from .._util.numeric import scaled_norm
from ..analysis import Airframe, acai_label
from ..studies.scan import efficiency_scan
from .app import _user_errors, airframe_option, cli, resumable_interruptions, formula_option, load_airframe, parse_numbers, parse_rotors
from .output import CommandOutput, Output, Rows, output_options, records


def default_rotors(frame: Airframe) -> list[int]:
    """The rotors a scan sweeps when none are named: Du's Fig. 4 choice (1, 2, 5) on an airframe
    with five or more rotors, else the first three (every preset has at least four)."""
    return [1, 2, 5] if frame.rotor_count >= 5 else list(range(1, min(3, frame.rotor_count) + 1))


@cli.command()
@airframe_option
@click.option("--rotors", default=None, help="Rotors whose efficiency is swept (1-based; default: 1,2,5 with five or more rotors, else 1,2,3).")
@click.option("--step", default=0.04, show_default=True, type=float, help="Grid spacing in [0, 1].")
@click.option("--give-up-yaw", is_flag=True, help="Give up yaw: only thrust, roll and pitch must stay controllable.")
@formula_option
@click.option("--plot", "plot_path", type=click.Path(dir_okay=False), help="Write a Du Fig. 4 style plot (.png, .pdf or .svg).")
@click.option("--force", is_flag=True, help="Replace an existing --plot file or --out output.")
@click.option("--out", "out_path", type=click.Path(), help="Stream the rows to this Parquet dataset directory (chunked, resumable).")
@click.option("--resume", is_flag=True, help="Continue an interrupted --out scan with the same arguments (skips the chunks written).")
@click.option("--dask", "dask_address", help="Run the chunks on a Dask cluster: a scheduler address (tcp://host:8786) or local:N.")
@click.option("--axis", "extra_axes", multiple=True, help="An airframe parameter axis NAME=v1,v2,... (max_thrust_n, mass_kg, drag_torque_ratio_m, arm_length_m, ...); with --out.")
@click.option("--chunk-points", default=1 << 20, show_default=True, type=int, help="Points per chunk (memory and resume granularity) with --out.")
@output_options
@_user_errors
def scan(
    airframe: str, rotors: str | None, step: float, give_up_yaw: bool, formula: AcaiFormula, plot_path: str | None, force: bool,
    out_path: str | None, resume: bool, dask_address: str | None, extra_axes: tuple[str, ...], chunk_points: int, output: Output,
) -> None:
    """Sweep rotor efficiencies over a grid and report the controllable region (Du Fig. 4)."""
    if plot_path is not None:
        check_output_file("plot", plot_path, force=force)
    frame = load_airframe(airframe)
    swept = default_rotors(frame) if rotors is None else parse_rotors("rotors", rotors)
    if out_path is not None:
        _scan_to_parquet(frame, swept, step, give_up_yaw, plot_path, force, out_path, resume, dask_address, extra_axes, chunk_points, output)
        return
    if resume or dask_address or extra_axes:
        raise ValueError("out: --resume, --dask and --axis need --out (a Parquet output)")
    if plot_path is not None and len(swept) != 3:
        raise ValueError(f"rotors: the Fig. 4 plot needs three swept rotors, got {len(swept)}")
    result = efficiency_scan(frame, swept, step, give_up_yaw=give_up_yaw, formula=formula, progress=None if output.progress else False)
    finite = result.acai[~(result.acai == -math.inf)]
    misleading = int(np.sum((result.acai >= 0.0) & (result.hover_code < 0)))
    largest = float(finite.max()) if finite.size else math.nan
    if plot_path is not None:
        result.plot(plot_path)
    fields: dict[str, Any] = {
        "airframe": frame.name, "rotors": list(swept), "step": step, "give_up_yaw": give_up_yaw, "formula": formula,
        "point_count": len(result.acai), "controllable_count": int(result.controllable.sum()),
        "controllable_fraction": result.controllable_fraction, "hover_feasible_count": int(result.hover_feasible.sum()),
        "largest_acai": largest, "misleading_count": misleading, "out": None, "plot": plot_path,
    }
    listed = ",".join(map(str, swept))

    def human(out: Output) -> None:
        out.print(
            f"{escape(frame.name)}: rotors {listed} swept with step {step:g}: {len(result.acai):,} points, "
            f"{fields['controllable_count']:,} controllable ({100 * result.controllable_fraction:.1f}%), "
            f"hover feasible at {fields['hover_feasible_count']:,}; largest {acai_label(formula)} {largest:.4f}"
        )
        if misleading:
            out.print(f"{misleading:,} points where {formula} reads >= 0 although the hover wrench lies outside (see hover_code)")
        if plot_path is not None:
            out.print(f"plot written to {escape(plot_path)}")

    output.emit(CommandOutput("scan", fields, [Rows("points", records(result))], csv_table="points", human=human))


def _scan_to_parquet(
    frame: Airframe, swept: list[int], step: float, give_up_yaw: bool, plot_path: str | None, force: bool,
    out_path: str, resume: bool, dask_address: str | None, extra_axes: tuple[str, ...], chunk_points: int, output: Output,
) -> None:
    from ..studies.scan import acai_scan

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
    with resumable_interruptions(out_path):
        result = acai_scan(
            frame, axes, give_up_yaw=give_up_yaw, out=out_path, resume=resume, force=force,
            backend="dask" if dask_address else "local", dask=dask_address, chunk_points=chunk_points, progress=output.progress,
        )
    ok = result.controllable_count(give_up_yaw=give_up_yaw)
    if plot_path is not None:
        result.plot(plot_path, give_up_yaw=give_up_yaw)
    fields: dict[str, Any] = {
        "airframe": frame.name, "rotors": list(swept), "step": step, "give_up_yaw": give_up_yaw, "axes": list(result.names),
        "point_count": result.total, "controllable_count": ok, "controllable_fraction": ok / max(result.total, 1),
        "computed_chunks": result.computed_chunks, "skipped_chunks": result.skipped_chunks, "seconds": result.seconds,
        "out": out_path, "plot": plot_path,
    }

    def human(out: Output) -> None:
        out.print(
            f"{escape(frame.name)}: {result.total:,} points ({result.computed_chunks} chunks computed, {result.skipped_chunks} already written) "
            f"in {result.seconds:.1f} s; {ok:,} controllable{' giving up yaw' if give_up_yaw else ''} "
            f"({100 * ok / max(result.total, 1):.1f}%); rows in {escape(out_path)}"
        )
        if plot_path is not None:
            out.print(f"plot written to {escape(plot_path)}")

    output.emit(CommandOutput("scan", fields, human=human))


@cli.command()
@airframe_option
@click.option("--parameter", help="Rank again for each value of this airframe parameter (arm_length_m, max_thrust_n, mass_kg, ...).")
@click.option("--values", help="Values of --parameter, comma-separated.")
@click.option(
    "--formula", type=click.Choice(["eq13", "facet-margin"]), default="facet-margin", show_default=True,
    help="ACAI of an infeasible hover: facet-margin (how far outside, negative) or eq13 (Du's 0).",
)
@click.option("--top", default=0, type=int, help="Show only the best N designs (per parameter value; 0: all).")
@output_options
@_user_errors
def design(airframe: str, parameter: str | None, values: str | None, formula: AcaiFormula, top: int, output: Output) -> None:
    """Rank every spin-direction assignment of the airframe's frame by failure tolerance."""
    from ..studies.design import design_search

    frame = load_airframe(airframe)
    numbers = parse_numbers("values", values) if values is not None else None
    if top < 0:
        raise ValueError(f"top: must be 0 (all) or a positive count, got {top}")
    result = design_search(frame, parameter=parameter, values=numbers, formula=formula)
    rows = [row for row in records(result) if top <= 0 or row["rank"] <= top]
    best = [result.best(value) for value in dict.fromkeys(d.parameter_value for d in result.designs)]
    fields = {
        "airframe": frame.name, "formula": formula, "parameter": parameter,
        "best": [{"parameter_value": b.parameter_value, "spins": b.spins, "controllable_single": b.controllable_single,
                  "single_failures": len(b.single), "survivable_single_rotors": list(b.survivable_single), "worst_single_acai": b.worst_single}
                 for b in best],
    }

    def human(out: Output) -> None:
        out.print(escape(result.format(top)))
        for b in best:
            where = "" if b.parameter_value is None else f" at {parameter} = {b.parameter_value:g}"
            out.print(
                f"best{where}: {b.spins}, controllable after {b.controllable_single} of {len(b.single)} single failures\n"
                f"  (rotors {', '.join(map(str, b.survivable_single)) or 'none'}), worst single-failure {acai_label(formula)} {b.worst_single:.4f}"
            )

    output.emit(CommandOutput("design", fields, [Rows("designs", rows)], csv_table="designs", human=human))


@cli.command()
@click.argument("scenario_file", type=click.Path(dir_okay=False))
@click.option("--plot", "plot_path", type=click.Path(dir_okay=False), help="Write the time-history figure (.png, .pdf or .svg).")
@click.option("--force", is_flag=True, help="Replace an existing --plot file.")
@output_options
@_user_errors
def simulate(scenario_file: str, plot_path: str | None, force: bool, output: Output) -> None:
    """Fly a scenario file (airframe, controller, faults, wind, noise or sensing, duration) and judge the
    whole flight (holds, drifts, circles, crashed or diverged; the thresholds are printed)."""
    from ..flight.outcomes import VERDICT_MEANINGS
    from ..studies.scenario_file import load_scenario

    if plot_path is not None:
        check_output_file("plot", plot_path, force=force)
    scenario = load_scenario(scenario_file)
    run = scenario.run()
    metrics = scenario.metrics(run)
    if plot_path is not None:
        run.plot(plot_path, title=scenario.title, setpoints=scenario.setpoints)
    altitude = -run.position[:, 2]
    tilt = np.degrees(np.arccos(np.clip(run.primary_axis[:, 2], -1.0, 1.0)))
    fields: dict[str, Any] = {
        "scenario": scenario.name, "airframe": scenario.simulator.airframe.name, "controller": scenario.controller_kind,
        "duration_s": scenario.duration_s, "simulated_s": float(run.t[-1]),
        "faults": [{"rotor": f.rotor, "time_s": f.time, "efficiency": f.efficiency} for f in run.faults],
        "final_position_m": [float(v) for v in run.position[-1]],
        "max_altitude_loss_m": float(max(0.0, altitude[0] - altitude.min())),
        "max_horizontal_excursion_m": float(scaled_norm(run.position[:, :2] - run.position[0, :2], axis=1).max()),
        "max_tilt_deg": float(tilt.max()), "sensed": run.sensed,
        "verdict": metrics.verdict, "outcome": metrics.outcome, "lost_at_s": metrics.lost_at_s,
        "event": None if not run.events else {"kind": run.events[0].kind, "time_s": run.events[0].time_s, "description": run.events[0].description},
        "plot": plot_path,
    }

    def human(out: Output) -> None:
        table = out.table(title=f"{escape(scenario.name)}: {escape(scenario.simulator.airframe.name)}, {scenario.controller_kind}")
        table.add_column("quantity")
        table.add_column("value", justify="right")
        table.add_row("simulated", f"{run.t[-1]:.3f} s of {scenario.duration_s:g} s")
        table.add_row("faults", ", ".join(f"rotor {f.rotor} -> {f.efficiency:g} at {f.time:g} s" for f in run.faults) or "none")
        table.add_row("final position (N, E, alt)", ", ".join(f"{v:.3f}" for v in (*run.position[-1, :2], altitude[-1])))
        table.add_row("max altitude loss", f"{fields['max_altitude_loss_m']:.3f} m")
        table.add_row("max horizontal excursion", f"{fields['max_horizontal_excursion_m']:.3f} m")
        table.add_row("max tilt", f"{tilt.max():.1f} deg")
        table.add_row("flew on", run.sensed)
        if run.estimate is not None:
            finite = np.isfinite(run.estimate_position_error_m)
            table.add_row("estimate error, position RMS", f"{1e3 * np.sqrt(np.mean(run.estimate_position_error_m[finite] ** 2)):.3f} mm")
            table.add_row("estimate error, attitude RMS", f"{np.degrees(np.sqrt(np.mean(run.estimate_attitude_error_rad[finite] ** 2))):.4f} deg")
            counts = run.estimate.counts
            table.add_row("gyro clamped", f"{counts.gyro_saturated_samples} of {counts.imu_samples} IMU samples")
        colour = {"holds": "green", "drifts": "yellow", "circles": "yellow"}.get(metrics.verdict, "red")
        table.add_row("verdict", f"[{colour}]{escape(metrics.verdict_label)}[/{colour}]")
        if run.diverged:
            table.add_row("event", f"[red]{escape(str(run.events[0]))}[/red]")
        out.print(table)
        out.print(f"{metrics.verdict}: {escape(VERDICT_MEANINGS[metrics.verdict])}", highlight=False)
        if plot_path is not None:
            out.print(f"plot written to {escape(plot_path)}")

    output.emit(CommandOutput("simulate", fields, [Rows("trajectory", records(run))], csv_table="trajectory", human=human))


@cli.command("campaign")
@click.argument("campaign_file", type=click.Path(dir_okay=False), required=False)
@click.option("--runs", type=int, help="Override the file's run count (with --suite: runs per cell).")
@click.option("--suite", type=click.Choice(["deciding"]), help="A named suite instead of a file: deciding = issue 30's grid (vehicle x fault class x controller), --runs per cell (default 1000).")
@click.option("--seed", type=int, default=0, show_default=True, help="With --suite: the suite's seed.")
@click.option("--certify/--no-certify", "certify_runs", default=True, show_default=True, help="With --suite: certify each run's own vehicle and fault (static hover, spinning, not survivable) and decide the target over the runs certified survivable.")
@click.option("--sensing", type=click.Choice(["truth", *get_args(SensorSuiteName)]), default=None, help="With --suite: what the controllers fly on: the truth (default), or a sensor suite (rotorfault.Sensing: the IMU at 500 Hz) with the estimator; each run's sensor noise seeded from its draw.")
@click.option("--read", "read_path", type=click.Path(file_okay=False), help="With --suite: read a suite's --out dataset instead of flying; rows without certify's verdict are certified after the fact (no flight).")
@click.option("--plot", "plot_path", type=click.Path(dir_okay=False), help="Write histograms and the envelope plot (.png, .pdf or .svg).")
@click.option("--tune", "tune_gains", is_flag=True, help="Robust tuning of Ke's gains on the single and double failure campaign instead.")
@click.option("--quick", is_flag=True, help="With --tune: a small search (12 candidates x 24 scenarios, about a minute).")
@click.option("--out", "out_path", type=click.Path(), help="Stream the per-run rows to this Parquet dataset directory (chunked, resumable; the campaign is in its manifest).")
@click.option("--resume", is_flag=True, help="Continue an interrupted --out campaign with the same campaign (skips the chunks written).")
@click.option("--dask", "dask_address", help="Run the chunks on a Dask cluster: a scheduler address (tcp://host:8786) or local:N.")
@click.option("--force", is_flag=True, help="Replace an existing --plot file or --out output.")
@click.option("--progress/--no-progress", default=True, help="Show a progress bar on standard error.")
@output_options
@_user_errors
def campaign_command(
    campaign_file: str | None, runs: int | None, suite: str | None, seed: int, certify_runs: bool, sensing: str | None, read_path: str | None, plot_path: str | None, tune_gains: bool, quick: bool, out_path: str | None,
    resume: bool, dask_address: str | None, force: bool, progress: bool, output: Output,
) -> None:
    """Fly a fault campaign (a TOML file of rotorfault.studies.Campaign fields; default: every
    single failure of Ke's quadcopter) and report survival, worst cases and excursions."""
    from dataclasses import replace

    from ..studies.campaign import Campaign, run_campaign
    from ..studies.tuning import TUNED_GAINS, tune, tuning_campaign

    progress = progress and output.progress
    if plot_path is not None:
        check_output_file("plot", plot_path, force=force)
    if out_path is None and (resume or dask_address):
        raise ValueError("out: --resume and --dask need --out (a Parquet output)")
    if sensing is not None and suite is None:
        raise ValueError("sensing: --sensing chooses a --suite's sensing (a campaign file has its own [sensing] table)")
    if tune_gains:
        if out_path is not None:
            raise ValueError("out: --tune writes no Parquet output")
        base = tuning_campaign(runs=24 if quick else 200)
        tuned = tune(base, maxiter=1 if quick else 9, popsize=1, progress=progress)
        gains = [{"gain": n, "table_iv": float(getattr(tuned.baseline, n)), "tuned": float(getattr(tuned.tuned, n))} for n in TUNED_GAINS]
        scores = [{"campaign": key, **{k: float(v) for k, v in score.items()}} for key, score in tuned.scores.items()]
        output.emit(CommandOutput(
            "campaign", {"mode": "tune", "candidates": tuned.candidates, "scenarios": tuned.scenarios},
            [Rows("gains", gains), Rows("scores", scores)], csv_table="gains", human=lambda out: out.print(escape(tuned.table())),
        ))
        return
    if suite is not None:
        if campaign_file is not None or plot_path is not None:
            raise ValueError("suite: --suite replaces the campaign file and takes no --plot")
        _suite_command(suite, 1000 if runs is None else runs, seed, out_path, resume, force, dask_address, progress, output,
                       certify=certify_runs, read_path=read_path, sensing=sensing)
        return
    if read_path is not None:
        raise ValueError("read: --read reads a --suite dataset; give --suite")
    campaign = Campaign() if campaign_file is None else Campaign.from_toml(campaign_file)
    if runs is not None:
        campaign = replace(campaign, runs=runs)
    with resumable_interruptions(out_path):
        result = run_campaign(
            campaign, out=out_path, resume=resume, force=force, backend="dask" if dask_address else "local", dask=dask_address,
            progress=progress,
        )
    if plot_path is not None:
        result.plot(plot_path)
    every = result.survival()[0]
    fields: dict[str, Any] = {
        "mode": "campaign", "runs": campaign.runs, "controller": campaign.controller, "seed": campaign.seed,
        "held": every.held, "survival_rate": every.rate, "survival_low": every.low, "survival_high": every.high,
        "out": out_path, "computed_chunks": result.computed_chunks, "skipped_chunks": result.skipped_chunks, "seconds": result.seconds,
        "plot": plot_path,
    }
    tables = [Rows("survival", list(result.survival_table())), Rows("worst", result.worst(5))]
    if out_path is None:
        tables.append(Rows("rows", records(result)))

    def human(out: Output) -> None:
        if out_path is not None:
            out.print(
                f"{campaign.runs:,} runs ({result.computed_chunks} chunks flown, {result.skipped_chunks} already written) "
                f"in {result.seconds:.1f} s; rows in {escape(out_path)}"
            )
        out.print(escape(result.table()))
        if plot_path is not None:
            out.print(f"plot written to {escape(plot_path)}")

    output.emit(CommandOutput("campaign", fields, tables, csv_table="survival", human=human))


def _suite_command(
    name: str, runs: int, seed: int, out_path: str | None, resume: bool, force: bool, dask_address: str | None, progress: bool, output: Output,
    *, certify: bool, read_path: str | None, sensing: str | None = None,
) -> None:
    """``rotorfault campaign --suite NAME``: a named suite (:data:`rotorfault.studies.deciding.SUITES`),
    flown, or read back (``--read``) and certified after the fact."""
    from dataclasses import replace

    from ..flight import Sensing
    from ..studies.deciding import SUITES, read_deciding, run_deciding

    if read_path is not None:
        if out_path is not None or resume or dask_address:
            raise ValueError("read: --read flies nothing; it takes no --out, --resume or --dask")
        if sensing is not None:
            raise ValueError("sensing: --read reads what the dataset flew on (its manifest); give no --sensing")
        result = read_deciding(read_path, certify=certify, progress=progress)
        suite = result.suite
    else:
        suite = replace(SUITES[name](runs, seed), certify=certify, sensing=None if sensing in (None, "truth") else Sensing(suite=cast(SensorSuiteName, sensing)))
        result = run_deciding(suite, out=out_path, resume=resume, force=force, backend="dask" if dask_address else "local", dask=dask_address,
                              progress=progress)
    fields: dict[str, Any] = {"mode": "suite", "suite": name, "runs_per_cell": suite.runs, "seed": suite.seed,
                              "sensing": "truth" if suite.sensing is None else suite.sensing.suite, "cell_count": len(suite.cells),
                              "runs": suite.total_runs, "seconds": result.seconds, "certify_seconds": result.certify_seconds,
                              "certified": result.certified, "spin_growth_judged": result.spin_growth_judged, "holds_rejudged": result.holds_rejudged,
                              "certify_rule": result.certify_rule,
                              "out": out_path, "read": read_path}
    tables = [Rows("cells", result.cell_rows()), Rows("best", result.best())]
    if result.certified:
        tables += [Rows("decision", result.decision()), Rows("contradictions", result.contradictions())]
    output.emit(CommandOutput("campaign", fields, tables, csv_table="cells", human=lambda out: out.print(escape(result.table()))))

"""Time histories: one flight's states, commands, faults and loss against time (any trajectory;
Lanzon's flights in the paper's frame, Figs. 6-9; Wang's flights with their reference, Figs. 2-7)."""

from __future__ import annotations

import textwrap
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
import numpy.typing as npt

from ..flight.outcomes import outcome_text
from .style import LINE_STYLES, MIN_FONT_PT, at_least_span, finish, legend_outside, new_figure

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from .._util.convert import FloatArray


def plot_trajectory(
    trajectory: Any,
    path: str | None = None,
    *,
    title: str | None = None,
    setpoints: Sequence[tuple[float, npt.ArrayLike]] | None = None,
    verdict: str | None = None,
) -> Figure:
    """Position (with the setpoint, if given as ``(time, NED position)`` steps), roll and pitch,
    yaw, body rates and rotor thrusts of a :class:`rotorfault.Trajectory` against time, with fault
    and loss markers. Yaw is wrapped to +-180 degrees; a run that turns more than one revolution
    (a spinning vehicle) shows the rate of its heading instead, in revolutions per second (its
    wrapped angle would be a saw and its unwrapped one tens of thousands of degrees). A run flown
    on sensors also shows the estimate the controller flew on (thin dotted lines over the truth)
    and a last panel of the estimate's error against the truth (position mm, attitude deg).
    ``title`` says what the run is (default: the faults); the faults, the loss and ``verdict``
    (the flight's verdict in words, :mod:`rotorfault.flight.outcomes`), if any, are always added.
    Saved to ``path`` if given."""
    tr = trajectory
    estimate = tr.estimate
    fig = new_figure(figsize=(10, 12.5 if estimate is None else 15), layout="constrained")
    axes = fig.subplots(5 if estimate is None else 6, 1, sharex=True)
    styles = LINE_STYLES
    euler_deg = np.degrees(tr.euler)
    m = tr.rotor_thrust.shape[1]
    # (data, series names, axis label, smallest y span shown: round-off is not magnified)
    panels: list[tuple[FloatArray, list[str], str, float]] = [
        (tr.position * np.array([1, 1, -1]), ["north", "east", "altitude"], "position (m)\n(altitude = -down)", 1.0),
        (euler_deg[:, :2], ["roll", "pitch"], "roll, pitch (deg)", 2.0),
        _yaw_panel(tr.t, tr.euler[:, 2]),
        (tr.omega, ["p (roll rate)", "q (pitch rate)", "r (yaw rate)"], "body rate (rad/s)", 0.2),
        (tr.rotor_thrust, [f"rotor {i + 1}" for i in range(m)], "rotor thrust (N)", 0.2),
    ]
    estimated: list[FloatArray | None] = [None] * len(panels)
    if estimate is not None:
        e_deg = np.degrees(estimate.euler)
        e_yaw = np.degrees(np.unwrap(estimate.euler[:, 2])) if len(tr.t) else e_deg[:, 2]
        estimated[:4] = [estimate.position * np.array([1, 1, -1]), e_deg[:, :2], e_yaw[:, None], estimate.omega]
    for k, (ax, (data, labels, ylabel, span)) in enumerate(zip(axes, panels)):
        for j, (column, label) in enumerate(zip(data.T, labels)):
            ax.plot(tr.t, column, label=label, linestyle=styles[j % len(styles)], color=f"C{j}", lw=1.3)
        if (seen := estimated[k]) is not None:
            for j, (column, label) in enumerate(zip(seen.T, labels)):
                ax.plot(tr.t, column, label=f"{label} (estimate)", linestyle=":", color=f"C{j}", lw=0.9, alpha=0.9)
        if k == 0 and setpoints:
            _plot_setpoints(ax, tr.t, setpoints, styles)
        at_least_span(ax, data, span)
        ax.set_ylabel(ylabel, fontsize=10)
        ax.grid(True, alpha=0.3)
        ax.tick_params(labelsize=9)
        for fault in tr.faults:
            ax.axvline(fault.time, color="0.35", linestyle=(0, (4, 2)), lw=1.0, label=None)
        for event in tr.events:
            ax.axvline(event.time_s, color="black", linestyle="-", lw=2.0, alpha=0.5)
        legend_outside(ax)
    if estimate is not None:
        _plot_estimate_error(axes[-1], tr)
    axes[-1].set_xlabel("time (s)", fontsize=10)
    lines = [title if title else "rotorfault simulation"]
    if tr.sensed != "truth":
        lines.append(f"flown on: {tr.sensed}" + (" (dotted: the estimate the controller saw)" if estimate is not None else ""))
    if tr.faults:
        lines.append(
            "faults (thin dashed lines): "
            + ", ".join(f"rotor {f.rotor} -> {f.efficiency:g} at {f.time:g} s" for f in tr.faults)
        )
    if tr.events:
        e = tr.events[0]
        lines.append(f"lost at t = {e.time_s:.2f} s (thick line): {e.description}")
    elif len(tr.t):
        lines.append(f"flown for {tr.t[-1]:g} s" + ("" if verdict else " (no setpoint given: no verdict)"))
    if verdict:
        lines.append(f"verdict: {verdict}")
    fig.suptitle("\n".join(textwrap.fill(line, 110) for line in "\n".join(lines).splitlines()), fontsize=11)
    return finish(fig, path)


def _yaw_panel(t: FloatArray, yaw_rad: FloatArray) -> tuple[FloatArray, list[str], str, float]:
    """The yaw panel: the angle wrapped to +-180 degrees, or for a run that turns more than one
    revolution the heading's rate (rev/s, from the unwrapped angle)."""
    unwrapped = np.unwrap(yaw_rad) if len(t) else yaw_rad
    if len(t) > 1 and np.ptp(unwrapped) > 2 * np.pi:
        rate = np.gradient(unwrapped, t) / (2 * np.pi)
        return rate[:, None], ["heading rate (yaw angle turning)"], "yaw rate (rev/s)\n(spinning: > 1 turn)", 0.05
    wrapped = np.degrees((yaw_rad + np.pi) % (2 * np.pi) - np.pi)
    return wrapped[:, None], ["yaw (wrapped to +-180)"], "yaw (deg)", 2.0


def _plot_estimate_error(ax: Any, tr: Any) -> None:
    """The estimate's error against the truth: position (mm, left axis) and attitude (deg, right)."""
    ax.plot(tr.t, 1e3 * tr.estimate_position_error_m, color="C0", lw=1.0, label="position error (mm)")
    ax.set_ylabel("estimate error,\nposition (mm)", fontsize=10)
    ax.grid(True, alpha=0.3)
    ax.tick_params(labelsize=9)
    right = ax.twinx()
    right.plot(tr.t, np.degrees(tr.estimate_attitude_error_rad), color="C3", lw=1.0, linestyle="--", label="attitude error (deg)")
    right.set_ylabel("attitude (deg)", fontsize=10, color="C3")
    right.tick_params(labelsize=9)
    handles = [*ax.get_legend_handles_labels()[0], *right.get_legend_handles_labels()[0]]
    ax.legend(handles=handles, fontsize=max(MIN_FONT_PT, 8.5), loc="upper left", bbox_to_anchor=(1.06, 1.0), frameon=False)


def _plot_setpoints(ax: Any, t: FloatArray, setpoints: Sequence[tuple[float, npt.ArrayLike]], styles: list[Any]) -> None:
    """The setpoint of each position series as a thin step line in its colour, labelled once."""
    if not len(t):
        return
    times = np.array([float(s) for s, _ in setpoints])
    points = np.array([np.asarray(p, dtype=np.float64) for _, p in setpoints]) * np.array([1, 1, -1])
    k = np.clip(np.searchsorted(times, t, side="right") - 1, 0, len(times) - 1)
    every = max(1, len(t) // 12)
    for j, (name, marker) in enumerate(zip(["north", "east", "altitude"], ["x", "+", "1"])):
        # Staggered markers: equal setpoints (east 10 m, altitude 10 m) stay distinguishable.
        ax.plot(t, points[k, j], color=f"C{j}", lw=0.7, linestyle=styles[j], alpha=0.8, marker=marker,
                markevery=(j * every // 3, every), markersize=7, label=f"{name} setpoint")


def plot_lanzon_flight(run: Any, path: str | None = None) -> Figure:
    """Lanzon Figs. 6-9 style for one run: roll and pitch, spin r, position (paper frame, z up,
    with the setpoint) and rotor thrusts. ``run``: a :class:`rotorfault.papers.lanzon.LanzonRun`
    (its trajectory, vehicle, scenario, case, outcome and title). Saved to ``path`` if given."""

    tr = run.trajectory
    paper = np.array([run.vehicle.paper_state(x) for x in np.column_stack(
        [tr.position, tr.velocity, tr.euler, tr.omega])]) if len(tr.t) else np.zeros((0, 12))
    fig = new_figure(figsize=(10, 10.5), layout="constrained")
    axes = fig.subplots(4, 1, sharex=True)
    panels: list[tuple[FloatArray, list[str], str]] = [
        (np.degrees(paper[:, 0:2]), ["roll phi", "pitch theta"], "attitude (deg)"),
        (paper[:, 3:6], ["p", "q", "r (spin)"], "body rates (rad/s)"),
        (paper[:, 6:9], ["x", "y", "z (up)"], "position (m)"),
        (tr.rotor_thrust, [f"rotor {i + 1}" + (" (failed)" if i == 1 else "") for i in range(4)], "rotor thrust (N)"),
    ]
    for k, (ax, (data, labels, ylabel)) in enumerate(zip(axes, panels)):
        for j, (col, label) in enumerate(zip(data.T, labels)):
            ax.plot(tr.t, col, label=label, linestyle=LINE_STYLES[j % 4], color=f"C{j}", lw=1.2)
        if k == 2 and run.scenario.position is not None:
            sp = np.asarray(run.scenario.position) * np.array([1, -1, -1])
            for j in range(3):
                ax.axhline(sp[j], color=f"C{j}", lw=0.7, linestyle=LINE_STYLES[j], alpha=0.7)
        if k == 1:
            ax.axhline(run.vehicle.spin_rate_rad_s, color="0.4", lw=0.7, linestyle=(0, (1, 2)), label="spin set point")
        if k == 3 and run.case.limits:
            for level in (0.0, run.vehicle.max_thrust_n):
                ax.axhline(level, color="0.3", lw=0.7, linestyle=(0, (4, 2)))
        ax.set_ylabel(ylabel, fontsize=10)
        ax.grid(True, alpha=0.3)
        ax.tick_params(labelsize=9)
        for event in tr.events:
            ax.axvline(event.time_s, color="black", lw=2.0, alpha=0.5)
        legend_outside(ax)
    axes[-1].set_xlabel("time (s)", fontsize=10)
    lost = run.lost_at_s
    verdict = outcome_text(run.outcome, lost)
    fig.suptitle(textwrap.fill(f"{run.title}: {verdict}", 110), fontsize=11)
    return finish(fig, path)


def plot_wang_flights(flights: Sequence[Any], path: str | None = None) -> Figure:
    """Figs. 2-7 in one page per scenario, in Wang's frame (z up): the 3-D path against the
    reference (left), position, attitude and propeller commands against time (right), the
    actuator's limits (10,000 rpm, +-0.26 rad) drawn on the command panels. ``flights``:
    :class:`rotorfault.papers.wang.WangFlight` results (their ``paper_states``,
    ``paper_reference``, ``label``, verdict), the first drawn in full, the others dashed in the
    path panel. Saved to ``path`` if given."""

    first = flights[0]
    fig = new_figure(figsize=(13, 9), layout="constrained")
    grid = fig.add_gridspec(4, 2, width_ratios=[1.1, 1.0])
    ax3 = fig.add_subplot(grid[:, 0], projection="3d")
    ref = first.paper_reference
    ax3.plot(ref[:, 0], ref[:, 1], ref[:, 2], color="0.6", lw=2.5, label="reference")
    for k, f in enumerate(flights):
        p = f.paper_states
        label = f"{f.label}: {f.verdict}" + (f" (lost at {f.lost_at_s:.2f} s)" if f.lost else "")
        ax3.plot(p[:, 0], p[:, 1], p[:, 2], color="black" if k == 0 else "0.35", lw=1.2, linestyle="-" if k == 0 else "--", label=label)
    ax3.set_xlabel("x (m)")
    ax3.set_ylabel("y (m)")
    ax3.set_zlabel("z, up (m)")
    ax3.legend(loc="upper left", fontsize=9)
    run = first.trajectory
    states = first.paper_states
    t = run.t
    styles = ["-", "--", ":"]
    ax = fig.add_subplot(grid[0, 1])
    for j, name in enumerate(["x", "y", "z (up)"]):
        ax.plot(t, states[:, j], color=f"C{j}", linestyle=styles[j], label=name)
        ax.plot(t, ref[:, j], color=f"C{j}", lw=0.8, alpha=0.6)
    ax.set_ylabel("position (m)\n(thin: reference)")
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False)
    ax = fig.add_subplot(grid[1, 1], sharex=ax)
    for j, name in enumerate(["roll phi", "pitch theta", "yaw psi"]):
        ax.plot(t, states[:, 6 + j], color=f"C{j}", linestyle=styles[j], label=name)
    ax.plot(t, ref[:, 8], color="C2", lw=0.8, alpha=0.6)
    ax.set_ylabel("attitude (rad)")
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False)
    ax_w = fig.add_subplot(grid[2, 1], sharex=ax)
    ax_a = fig.add_subplot(grid[3, 1], sharex=ax)
    for i in range(1, 4):
        ax_w.plot(t, run.rotor_command[:, 2 * i], color=f"C{i}", linestyle=styles[i - 1], label=f"omega {i + 1}")
        ax_a.plot(t, run.rotor_command[:, 2 * i + 1], color=f"C{i}", linestyle=styles[i - 1], label=f"alpha {i + 1}")
    limits = getattr(first, "limits", None)
    if limits is not None:
        (_, speed_hi), (pitch_lo, pitch_hi) = limits
        ax_w.axhline(speed_hi, color="black", lw=0.9, linestyle=(0, (4, 2)), label="limit (clamped)")
        for level in (pitch_lo, pitch_hi):
            ax_a.axhline(level, color="black", lw=0.9, linestyle=(0, (4, 2)), label="limit (clamped)" if level == pitch_hi else None)
    ax_w.set_ylabel("speed command (rpm,\nthe paper's unit)")
    ax_a.set_ylabel("pitch command (rad)")
    ax_a.set_xlabel("time (s)")
    for a in (ax_w, ax_a):
        a.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False)
    for a in fig.axes[1:]:
        a.grid(True, alpha=0.3)
    verdict = first.metrics.verdict_label if getattr(first, "metrics", None) is not None else first.verdict
    fig.suptitle(
        textwrap.fill(
            f"Wang et al. {first.scenario.title}; VPP quadcopter, propeller 1 failed, {first.label}: {verdict}; final error "
            f"{first.final_error_m:.3f} m, largest tilt {first.max_tilt_rad:.3f} rad; a pitch at its limit "
            f"{100 * first.pitch_limit_share:.1f} % of the time, a speed {100 * first.speed_limit_share:.1f} %", 150),
        fontsize=11,
    )
    return finish(fig, path)


__all__ = ["plot_lanzon_flight", "plot_trajectory", "plot_wang_flights"]

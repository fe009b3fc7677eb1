"""Time histories: one flight's states, commands, faults and loss against time (any trajectory;
Lanzon's flights in the paper's frame, Figs. 6-9; Wang's flights with their reference, Figs. 2-7)."""

from __future__ import annotations

import textwrap
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
import numpy.typing as npt

from ..flight.outcomes import outcome_text
from .style import LINE_STYLES, at_least_span, finish, legend_outside, new_figure

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from .._util.convert import FloatArray


def plot_trajectory(
    trajectory: Any,
    path: str | None = None,
    *,
    title: str | None = None,
    setpoints: Sequence[tuple[float, npt.ArrayLike]] | None = None,
) -> Figure:
    """Position (with the setpoint, if given as ``(time, NED position)`` steps), roll and pitch,
    yaw unwrapped, body rates and rotor thrusts of a :class:`rotorfault.Trajectory` against time,
    with fault and loss markers. ``title`` says what the run is (default: the faults); the faults
    and the loss, if any, are always added. Saved to ``path`` if given."""
    tr = trajectory
    fig = new_figure(figsize=(10, 12.5), layout="constrained")
    axes = fig.subplots(5, 1, sharex=True)
    styles = LINE_STYLES
    euler_deg = np.degrees(tr.euler)
    yaw = np.degrees(np.unwrap(tr.euler[:, 2])) if len(tr.t) else euler_deg[:, 2]
    m = tr.rotor_thrust.shape[1]
    # (data, series names, axis label, smallest y span shown: round-off is not magnified)
    panels: list[tuple[FloatArray, list[str], str, float]] = [
        (tr.position * np.array([1, 1, -1]), ["north", "east", "altitude"], "position (m)\n(altitude = -down)", 1.0),
        (euler_deg[:, :2], ["roll", "pitch"], "roll, pitch (deg)", 2.0),
        (yaw[:, None], ["yaw (unwrapped)"], "yaw (deg)", 2.0),
        (tr.omega, ["p (roll rate)", "q (pitch rate)", "r (yaw rate)"], "body rate (rad/s)", 0.2),
        (tr.rotor_thrust, [f"rotor {i + 1}" for i in range(m)], "rotor thrust (N)", 0.2),
    ]
    for k, (ax, (data, labels, ylabel, span)) in enumerate(zip(axes, panels)):
        for j, (column, label) in enumerate(zip(data.T, labels)):
            ax.plot(tr.t, column, label=label, linestyle=styles[j % len(styles)], color=f"C{j}", lw=1.3)
        if k == 0 and setpoints:
            _plot_setpoints(ax, tr.t, setpoints, styles)
        at_least_span(ax, data, span)
        ax.set_ylabel(ylabel, fontsize=10)
        ax.grid(True, alpha=0.3)
        ax.tick_params(labelsize=9)
        for fault in tr.faults:
            ax.axvline(fault.time, color="0.35", linestyle=(0, (4, 2)), lw=1.0, label=None)
        for event in tr.events:
            ax.axvline(event.time, color="black", linestyle="-", lw=2.0, alpha=0.5)
        legend_outside(ax)
    axes[-1].set_xlabel("time (s)", fontsize=10)
    lines = [title if title else "rotorfault simulation"]
    if tr.faults:
        lines.append(
            "faults (thin dashed lines): "
            + ", ".join(f"rotor {f.rotor} -> {f.efficiency:g} at {f.time:g} s" for f in tr.faults)
        )
    if tr.events:
        e = tr.events[0]
        lines.append(f"lost at t = {e.time:.2f} s (thick line): {e.description}")
    elif len(tr.t):
        lines.append(f"flown for {tr.t[-1]:g} s, not lost")
    fig.suptitle("\n".join(textwrap.fill(line, 110) for line in "\n".join(lines).splitlines()), fontsize=11)
    return finish(fig, path)


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
            ax.axvline(event.time, color="black", lw=2.0, alpha=0.5)
        legend_outside(ax)
    axes[-1].set_xlabel("time (s)", fontsize=10)
    lost = run.lost_at_s
    verdict = outcome_text(run.outcome, lost)
    fig.suptitle(textwrap.fill(f"{run.title}: {verdict}", 110), fontsize=11)
    return finish(fig, path)


def plot_wang_flights(flights: Sequence[Any], path: str | None = None) -> Figure:
    """Figs. 2-7 in one page per scenario: the 3-D path against the reference (left), position,
    attitude and propeller commands against time (right); a fixed-pitch flight, if given, dashed
    in the path panel with where it was lost. ``flights``: :class:`rotorfault.papers.wang.WangFlight`
    results, the first drawn in full. Saved to ``path`` if given."""

    first = flights[0]
    fig = new_figure(figsize=(13, 9), layout="constrained")
    grid = fig.add_gridspec(4, 2, width_ratios=[1.1, 1.0])
    ax3 = fig.add_subplot(grid[:, 0], projection="3d")
    ref = first.reference
    ax3.plot(ref[:, 0], ref[:, 1], -ref[:, 2], color="0.6", lw=2.5, label="reference")
    for k, f in enumerate(flights):
        p = f.trajectory.position
        label = f"{f.vehicle}" + (f" (lost at {f.lost_at_s:.2f} s)" if f.lost else "")
        ax3.plot(p[:, 0], p[:, 1], -p[:, 2], color="black" if k == 0 else "0.35", lw=1.2, linestyle="-" if k == 0 else "--", label=label)
    ax3.set_xlabel("x (m)")
    ax3.set_ylabel("y (m)")
    ax3.set_zlabel("altitude (m)")
    ax3.legend(loc="upper left", fontsize=9)
    run = first.trajectory
    t = run.t
    styles = ["-", "--", ":"]
    ax = fig.add_subplot(grid[0, 1])
    for j, name in enumerate(["x", "y", "altitude"]):
        sign = -1.0 if j == 2 else 1.0
        ax.plot(t, sign * run.position[:, j], color=f"C{j}", linestyle=styles[j], label=name)
        ax.plot(t, sign * ref[:, j], color=f"C{j}", lw=0.8, alpha=0.6)
    ax.set_ylabel("position (m)\n(thin: reference)")
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False)
    ax = fig.add_subplot(grid[1, 1], sharex=ax)
    for j, name in enumerate(["roll", "pitch", "yaw"]):
        ax.plot(t, run.euler[:, j], color=f"C{j}", linestyle=styles[j], label=name)
    ax.plot(t, ref[:, 8], color="C2", lw=0.8, alpha=0.6)
    ax.set_ylabel("attitude (rad)")
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False)
    ax_w = fig.add_subplot(grid[2, 1], sharex=ax)
    ax_a = fig.add_subplot(grid[3, 1], sharex=ax)
    for i in range(1, 4):
        ax_w.plot(t, run.rotor_command[:, 2 * i], color=f"C{i}", linestyle=styles[i - 1], label=f"omega {i + 1}")
        ax_a.plot(t, run.rotor_command[:, 2 * i + 1], color=f"C{i}", linestyle=styles[i - 1], label=f"alpha {i + 1}")
    ax_w.set_ylabel("speed command\n(paper's units)")
    ax_a.set_ylabel("pitch command (rad)")
    ax_a.set_xlabel("time (s)")
    for a in (ax_w, ax_a):
        a.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False)
    for a in fig.axes[1:]:
        a.grid(True, alpha=0.3)
    fig.suptitle(
        f"Wang et al. {first.scenario.title}; VPP quadcopter, propeller 1 failed: final error "
        f"{first.final_error_m:.3f} m, largest tilt {first.max_tilt_rad:.3f} rad", fontsize=11,
    )
    return finish(fig, path)


__all__ = ["plot_lanzon_flight", "plot_trajectory", "plot_wang_flights"]

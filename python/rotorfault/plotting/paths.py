"""Paths: where a vehicle went, in space (Lanzon Fig. 10 style) and on the unit sphere (its
primary axis, Ke Fig. 16 style)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from ..flight.outcomes import outcome_text
from .style import LINE_STYLES, MIN_FONT_PT, finish, new_figure

if TYPE_CHECKING:
    from matplotlib.figure import Figure


def plot_primary_axis(runs: Sequence[Any], path: str | None = None, *, tail_s: float = 10.0) -> Figure:
    """Ke Fig. 16 style: the path of the primary axis ``n3`` (body z in the world, NED) on the
    unit sphere for each run, drawn with ``n3z`` (the world-down component: 1 is level) upward
    and viewed obliquely from above that pole; the whole path thin and dashed, the last
    ``tail_s`` seconds solid and bold, the start a circle, the loss (if any) a cross. Returns the
    figure (not registered with pyplot), saved to ``path`` if given. ``runs``: flown scenarios
    with ``trajectory``, ``metrics`` (:class:`~rotorfault.flight.outcomes.FlightMetrics`),
    ``scenario.name`` and ``law`` (Ke's :class:`~rotorfault.papers.ke.ScenarioRun`)."""
    if not runs:
        raise ValueError("runs: give at least one run to plot")
    count = len(runs)
    cols = min(count, 4)
    rows_ = -(-count // cols)
    fig = new_figure(figsize=(4.4 * cols, 4.6 * rows_ + 0.9), layout="constrained")
    u, v = np.mgrid[0 : 2 * np.pi : 30j, 0 : np.pi : 24j]
    handles: dict[str, Any] = {}
    for k, run in enumerate(runs):
        ax = fig.add_subplot(rows_, cols, k + 1, projection="3d")
        n3 = run.trajectory.primary_axis
        t = run.trajectory.t
        below = bool(np.nanmin(n3[:, 2]) < 0)
        uu, vv = (u, v) if below else (u[:, :13], v[:, :13])
        ax.plot_wireframe(np.cos(uu) * np.sin(vv), np.sin(uu) * np.sin(vv), np.cos(vv), color="0.85", lw=0.4)
        late = t >= t[-1] - tail_s
        whole = ax.plot(n3[:, 0], n3[:, 1], n3[:, 2], color="0.45", lw=0.7, linestyle="--", label="whole flight")
        tail = ax.plot(n3[late, 0], n3[late, 1], n3[late, 2], color="black", lw=1.8, label=f"last {tail_s:g} s")
        start = ax.scatter([n3[0, 0]], [n3[0, 1]], [n3[0, 2]], color="black", marker="o", s=28, label="start")
        handles.update({"whole flight": whole[0], f"last {tail_s:g} s": tail[0], "start": start})
        if run.trajectory.diverged:
            handles["lost"] = ax.scatter([n3[-1, 0]], [n3[-1, 1]], [n3[-1, 2]], color="black", marker="x", s=60, label="lost")
        ax.set_xlim(-1, 1)
        ax.set_ylim(-1, 1)
        ax.set_zlim(-1 if below else 0, 1)
        ax.set_box_aspect((1, 1, 1 if below else 0.5), zoom=0.82)
        ax.view_init(elev=30, azim=-60)
        ax.set_xticks([-1, 0, 1])
        ax.set_yticks([-1, 0, 1])
        ax.set_zticks([-1, 0, 1] if below else [0, 0.5, 1])
        m = run.metrics
        if m.lost_at_s is not None:
            state = m.verdict_label
        elif m.r_rad_s is not None and m.n3z is not None:
            state = f"{m.verdict}, r = {m.r_rad_s:.1f} rad/s, n3z = {m.n3z:.3f}"
        else:
            state = f"{m.verdict}, not settled"
        ax.set_title(f"{run.scenario.name} ({run.law})\n{state}", fontsize=9)
        for name, setter in (("n3x", ax.set_xlabel), ("n3y", ax.set_ylabel), ("n3z", ax.set_zlabel)):
            setter(name, fontsize=9, labelpad=2)
        ax.tick_params(labelsize=MIN_FONT_PT, pad=1)
    fig.suptitle("primary axis n3 on the unit sphere (Ke Fig. 16 style; n3z = 1 is level)", fontsize=11)
    fig.legend(list(handles.values()), list(handles), loc="outside lower center", ncol=len(handles), fontsize=9, frameon=False)
    return finish(fig, path)


def plot_lanzon_paths(runs: Sequence[Any], path: str | None = None) -> Figure:
    """Lanzon Fig. 8 style: the 3-D paths (paper frame, z up) of one scenario's runs, with the
    start (circle), the setpoint (star, when the scenario has one) and any loss (cross). ``runs``:
    :class:`rotorfault.papers.lanzon.LanzonRun` results, all of the same scenario (a run of
    another scenario is refused: each scenario gets its own figure). Saved to ``path`` if given."""

    if not runs:
        raise ValueError("runs: give at least one run to plot")
    names = sorted({run.scenario.name for run in runs})
    if len(names) != 1:
        raise ValueError(f"runs: one scenario per figure, got scenarios {', '.join(names)} (plot each scenario's runs on their own)")
    fig = new_figure(figsize=(8, 7), layout="constrained")
    ax = fig.add_subplot(1, 1, 1, projection="3d")
    for j, run in enumerate(runs):
        p = run.trajectory.position * np.array([1, -1, -1])
        label = f"({run.case.label}) I_zz {run.vehicle.inertia_zz_kg_m2:g}: {outcome_text(run.outcome, run.lost_at_s)}"
        ax.plot(p[:, 0], p[:, 1], p[:, 2], color=f"C{j}", linestyle=LINE_STYLES[j % 4], lw=1.2, label=label)
        ax.scatter([p[0, 0]], [p[0, 1]], [p[0, 2]], color="black", marker="o", s=25)
        if run.trajectory.diverged:
            ax.scatter([p[-1, 0]], [p[-1, 1]], [p[-1, 2]], color=f"C{j}", marker="x", s=60)
    sp = runs[0].scenario.position
    if sp is not None:
        ax.scatter([sp[0]], [-sp[1]], [-sp[2]], color="black", marker="*", s=90, label="setpoint")
    ax.set_xlabel("x (m)", fontsize=9)
    ax.set_ylabel("y (m)", fontsize=9)
    ax.set_zlabel("z, up (m)", fontsize=9)
    ax.tick_params(labelsize=MIN_FONT_PT)
    ax.legend(loc="upper left", fontsize=max(MIN_FONT_PT, 8.5), frameon=False)
    fig.suptitle(f"Lanzon scenario {names[0]}: 3-D paths, {runs[0].scenario.description} (circle: start)", fontsize=11)
    return finish(fig, path)


__all__ = ["plot_lanzon_paths", "plot_primary_axis"]

"""Flight verdicts against a swept parameter (Lanzon's rotor-inertia sweep): where the verdict
of a design changes."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from .style import MIN_FONT_PT, finish, new_figure

if TYPE_CHECKING:
    from matplotlib.figure import Figure

#: One row per verdict, in the order of issue 28 (only ``holds`` is a success).
VERDICT_ORDER = ("holds", "drifts", "circles", "crashed", "diverged")


def plot_verdict_sweep(rows: Sequence[dict[str, Any]], path: str | None = None, *, parameter: str, parameter_label: str,
                       series: str, panel: str, title: str, mark: tuple[float, str] | None = None) -> Figure:
    """One panel per value of ``rows[i][panel]``; in each, one line per value of
    ``rows[i][series]``: the verdict (``rows[i]["verdict"]``, one row of the y axis per verdict)
    against ``rows[i][parameter]`` (x axis, ``parameter_label``), the points joined by dotted lines
    (a verdict is known only where a flight was flown); ``mark``: a value of the parameter drawn as a
    labelled vertical line (e.g. the one the model uses). Saved to ``path`` if given."""
    if not rows:
        raise ValueError("rows: give at least one swept flight to plot")
    unknown = sorted({r["verdict"] for r in rows} - set(VERDICT_ORDER))
    if unknown:
        raise ValueError(f"rows: verdicts {unknown} not among {', '.join(VERDICT_ORDER)}")
    panels = list(dict.fromkeys(r[panel] for r in rows))
    lines = list(dict.fromkeys(r[series] for r in rows))
    fig = new_figure(figsize=(5.2 * len(panels), 3.8), layout="constrained")
    for k, key in enumerate(panels):
        ax = fig.add_subplot(1, len(panels), k + 1)
        for j, name in enumerate(lines):
            pts = sorted((r[parameter], VERDICT_ORDER.index(r["verdict"])) for r in rows if r[panel] == key and r[series] == name)
            if not pts:
                continue
            x, y = np.array(pts, dtype=float).T
            ax.plot(x, y + 0.08 * (j - (len(lines) - 1) / 2), marker="o", lw=1.0, ls=":", label=str(name))
        if mark is not None:
            ax.axvline(mark[0], color="0.4", ls="--", lw=0.8)
            ax.annotate(mark[1], (mark[0], len(VERDICT_ORDER) - 0.8), fontsize=max(MIN_FONT_PT, 8), ha="left",
                        xytext=(3, 0), textcoords="offset points")
        ax.ticklabel_format(axis="x", style="sci", scilimits=(0, 0))
        ax.set_yticks(range(len(VERDICT_ORDER)), VERDICT_ORDER)
        ax.set_ylim(-0.5, len(VERDICT_ORDER) - 0.5)
        ax.set_xlabel(parameter_label, fontsize=9)
        ax.set_title(f"{panel} = {key}", fontsize=10)
        ax.grid(True, alpha=0.3)
        ax.tick_params(labelsize=MIN_FONT_PT)
        ax.legend(fontsize=max(MIN_FONT_PT, 8), frameon=False)
    fig.suptitle(title, fontsize=11)
    return finish(fig, path)


__all__ = ["VERDICT_ORDER", "plot_verdict_sweep"]

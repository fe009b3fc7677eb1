"""The one figure style of the package: every figure is drawn on its own ``Figure`` with an Agg
canvas (no pyplot, no global figure list, the user's backend untouched), saved atomically in the
format its extension names, with text no smaller than :data:`MIN_FONT_PT`, and series that differ
in line style and marker as well as colour (readable in greyscale)."""

from __future__ import annotations

import os
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from .._util.output import FIGURE_SUFFIXES, atomic_path, check_parent

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from .._util.convert import FloatArray

#: No tick label, legend or annotation of a package figure is smaller than this (points).
MIN_FONT_PT = 8.0
#: Line styles of successive series (with the colour cycle ``C0``, ``C1``, ...).
LINE_STYLES: list[Any] = ["-", "--", ":", "-.", (0, (5, 1, 1, 1, 1, 1)), (0, (1, 3)), (0, (8, 2)), (0, (3, 1, 3, 3))]
#: Markers of successive series where lines alone would not tell them apart.
MARKERS = ["o", "s", "^", "v", "D", "P", "X", "*"]


def new_figure(**kwargs: Any) -> Figure:
    """A figure with its own Agg canvas (not registered with pyplot)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(**kwargs)
    FigureCanvasAgg(fig)
    return fig


def save_figure(fig: Figure, path: str | os.PathLike[str], *, dpi: float = 150) -> None:
    """Saves ``fig`` to ``path`` (format from the extension) atomically, through the figure's own
    canvas: the global matplotlib state is not touched."""
    p = Path(path)
    suffix = p.suffix.lower()
    if suffix not in FIGURE_SUFFIXES:
        raise ValueError(f"path: the file name must end in {', '.join(FIGURE_SUFFIXES)}, got {str(p)!r}")
    check_parent("path", p)
    with atomic_path(p) as tmp:
        fig.savefig(tmp, format=suffix[1:], dpi=dpi)


def finish(fig: Figure, path: str | os.PathLike[str] | None) -> Figure:
    """Saves ``fig`` to ``path`` if given and returns it: the last line of every plot function."""
    if path is not None:
        save_figure(fig, path)
    return fig


def legend_outside(ax: Any) -> None:
    """The legend to the right of the axes, without a frame."""
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=max(MIN_FONT_PT, 8.5), frameon=False)


def at_least_span(ax: Any, data: FloatArray, span: float) -> None:
    """Shows at least ``span`` on the y axis, so round-off (1e-11 N, 1e-8 deg) around a constant
    is drawn as the flat line it is, not autoscaled into apparent chatter."""
    finite = data[np.isfinite(data)]
    if finite.size == 0:
        return
    lo, hi = float(finite.min()), float(finite.max())
    if hi - lo < span:
        mid = 0.5 * (lo + hi)
        ax.set_ylim(mid - 0.6 * span, mid + 0.6 * span)
    ax.ticklabel_format(axis="y", useOffset=False)


__all__ = ["LINE_STYLES", "MARKERS", "MIN_FONT_PT", "at_least_span", "finish", "legend_outside", "new_figure", "save_figure"]

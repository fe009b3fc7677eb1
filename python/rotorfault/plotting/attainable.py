"""Attainable sets: closed boundaries of 2-D slices of the attainable virtual-control set."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING

import numpy as np

from .style import LINE_STYLES, MARKERS, finish, new_figure

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from .._util.convert import FloatArray


def plot_slices(
    slices: Mapping[str, FloatArray | None],
    axis_labels: tuple[str, str],
    *,
    title: str,
    bold: Sequence[str] = (),
    path: str | None = None,
) -> Figure:
    """Overlays slice boundaries (``{label: (k, 2) points}``, as
    :func:`rotorfault.allocation.attainable_slice` returns them; ``None``: hover unattainable,
    listed in the legend as such), the cases in ``bold`` drawn thicker, with the hover point (the
    origin of the torques). Saved to ``path`` if given."""
    fig = new_figure(figsize=(9.5, 6.5), layout="constrained")
    ax = fig.add_subplot(1, 1, 1)
    for k, (label, points) in enumerate(slices.items()):
        if points is None:
            ax.plot([], [], " ", label=f"{label}: hover unattainable")
            continue
        closed = np.vstack([points, points[:1]])
        ax.plot(closed[:, 0], closed[:, 1], label=label, lw=2 if label in bold else 1.2,
                linestyle=LINE_STYLES[k % len(LINE_STYLES)], marker=MARKERS[k % len(MARKERS)], markevery=max(1, len(closed) // 8),
                markersize=5, color=f"C{k % 10}")
    ax.plot([0], [0], "k+", ms=12, label="hover (zero torque)")
    ax.set_xlabel(axis_labels[0])
    ax.set_ylabel(axis_labels[1])
    ax.set_title(title)
    ax.axhline(0, color="0.8", lw=0.8)
    ax.axvline(0, color="0.8", lw=0.8)
    ax.legend(fontsize=9, loc="center left", bbox_to_anchor=(1.02, 0.5))
    ax.set_aspect("equal", adjustable="datalim")
    return finish(fig, path)


__all__ = ["plot_slices"]

"""Distributions of many runs: histograms of their excursions and the envelope of the whole set."""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

import numpy as np

from .style import MIN_FONT_PT, finish, new_figure

if TYPE_CHECKING:
    from matplotlib.figure import Figure


def plot_excursions(
    columns: Mapping[str, np.ndarray[Any, Any]],
    survived: np.ndarray[Any, np.dtype[np.bool_]],
    *,
    title: str,
    path: str | None = None,
) -> Figure:
    """Histograms of the runs not lost (largest altitude loss, horizontal error, tilt) and the
    envelope (largest horizontal error against largest altitude loss, lost runs marked), from a
    campaign's summary ``columns`` and its ``survived`` mask. Saved to ``path`` if given."""
    fig = new_figure(figsize=(11, 7.5), layout="constrained")
    axes = fig.subplots(2, 2)
    c = columns
    ok = survived
    panels = [
        (axes[0, 0], "max_altitude_loss_m", "max altitude loss (m)"),
        (axes[0, 1], "max_horizontal_error_m", "max horizontal error (m)"),
        (axes[1, 0], "peak_tilt_rad", "peak tilt (deg)"),
    ]
    for ax, name, label in panels:
        values = c[name][ok] * (180 / math.pi if name == "peak_tilt_rad" else 1)
        ax.hist(values[np.isfinite(values)], bins=30, color="0.45", edgecolor="black", lw=0.5)
        ax.set_xlabel(label)
        ax.set_ylabel("runs not lost")
        ax.grid(True, alpha=0.3)
    ax = axes[1, 1]
    ax.scatter(c["max_horizontal_error_m"][ok], c["max_altitude_loss_m"][ok], s=10, marker="o", facecolors="none", edgecolors="black", label="not lost")
    if (~ok).any():
        ax.scatter(c["max_horizontal_error_m"][~ok], c["max_altitude_loss_m"][~ok], s=18, marker="x", color="0.4", label="lost (up to the loss)")
    ax.axvline(10, color="0.3", linestyle="--", lw=1, label="10 m horizontal")
    ax.axhline(2, color="0.3", linestyle=":", lw=1, label="2 m altitude")
    ax.set_xlabel("max horizontal error (m)")
    ax.set_ylabel("max altitude loss (m)")
    ax.set_title("envelope of excursions", fontsize=10)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=MIN_FONT_PT, frameon=False)
    fig.suptitle(title, fontsize=11)
    return finish(fig, path)


__all__ = ["plot_excursions"]

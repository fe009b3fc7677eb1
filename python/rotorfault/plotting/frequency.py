"""Frequency responses: singular values of linear systems against frequency (Lanzon Fig. 4, the
loop shape of an H-infinity loop-shaping design). Draws singular values the control room
computed (:func:`rotorfault.control.robust.singular_values`); it evaluates no system itself."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
import numpy.typing as npt

from .._util.deprecation import warn
from .style import MIN_FONT_PT, finish, new_figure

if TYPE_CHECKING:
    from matplotlib.figure import Figure


def plot_singular_values_db(
    omega_rad_s: npt.ArrayLike,
    curves: Sequence[tuple[npt.ArrayLike, str, str, str]],
    path: str | None = None,
    *,
    title: str,
    crossover_rad_s: float | None = None,
) -> Figure:
    """Draws each curve ``(singular_values, label, line style, colour)`` in dB against
    ``omega_rad_s`` (rad/s, log axis): ``singular_values`` has one row per frequency and one
    column per singular value (absolute, not dB), as
    :func:`rotorfault.control.robust.singular_values` returns them; ``crossover_rad_s`` marks a
    target crossover. Saved to ``path`` if given."""
    omega = np.asarray(omega_rad_s, dtype=np.float64)
    fig = new_figure(figsize=(7, 4.5), layout="constrained")
    ax = fig.add_subplot()
    for values, label, style, colour in curves:
        db = 20 * np.log10(np.maximum(np.asarray(values, dtype=np.float64), 1e-300))
        for j in range(db.shape[1]):
            ax.semilogx(omega, db[:, j], style, color=colour, label=label if j == 0 else None)
    ax.axhline(0, color="k", lw=0.5)
    if crossover_rad_s is not None:
        ax.axvline(crossover_rad_s, color="0.7", lw=0.8, linestyle=":", label=f"target crossover {crossover_rad_s:g} rad/s")
    ax.set_xlabel("frequency (rad/s)")
    ax.set_ylabel("singular values (dB)")
    ax.set_title(title)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=max(MIN_FONT_PT, 9))
    return finish(fig, path)


def plot_loop_shape(design_: Any, path: str | None = None) -> Figure:
    """Deprecated (issue 26: plotting computes nothing): use ``design.plot_loop_shape(path)`` of
    a :class:`rotorfault.control.lanzon.LanzonDesign`, which computes the singular values in the
    control room and draws them here."""
    warn("rotorfault.plotting.frequency.plot_loop_shape", "LanzonDesign.plot_loop_shape(path)")
    figure: Figure = design_.plot_loop_shape(path)
    return figure


__all__ = ["plot_singular_values_db"]

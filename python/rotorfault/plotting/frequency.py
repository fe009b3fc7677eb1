"""Frequency responses: singular values of linear systems against frequency (Lanzon Fig. 4, the
loop shape of an H-infinity loop-shaping design)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
import numpy.typing as npt

from .style import MIN_FONT_PT, finish, new_figure

if TYPE_CHECKING:
    from matplotlib.figure import Figure


def _singular_values_db(system: Any, omega: np.ndarray[Any, Any]) -> np.ndarray[Any, Any]:
    """Singular values (dB, columns descending) of ``system(j omega)`` at each frequency: the
    response of a python-control system, as drawn."""
    resp = np.asarray(system(1j * omega)).reshape(system.noutputs, system.ninputs, -1)
    sv = np.array([np.linalg.svd(resp[:, :, i], compute_uv=False) for i in range(len(omega))])
    db: np.ndarray[Any, Any] = 20 * np.log10(np.maximum(sv, 1e-300))
    return db


def _draw(curves: Sequence[tuple[Any, str, str, str]], omega: np.ndarray[Any, Any], *, title: str,
          crossover_rad_s: float | None, path: str | None) -> Figure:
    fig = new_figure(figsize=(7, 4.5), layout="constrained")
    ax = fig.add_subplot()
    for system, label, style, colour in curves:
        sv = _singular_values_db(system, omega)
        for j in range(sv.shape[1]):
            ax.semilogx(omega, sv[:, j], style, color=colour, label=label if j == 0 else None)
    ax.axhline(0, color="k", lw=0.5)
    if crossover_rad_s is not None:
        ax.axvline(crossover_rad_s, color="0.7", lw=0.8, linestyle=":", label=f"target crossover {crossover_rad_s:g} rad/s")
    ax.set_xlabel("frequency (rad/s)")
    ax.set_ylabel("singular values (dB)")
    ax.set_title(title)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=max(MIN_FONT_PT, 9))
    return finish(fig, path)


def plot_singular_values(
    plant: Any,
    shaped: Any,
    path: str | None = None,
    *,
    omega: npt.ArrayLike | None = None,
    title: str = "",
) -> Figure:
    """Singular values (dB) of ``plant`` and of the shaped plant ``G W1`` (python-control
    systems), Lanzon's Fig. 4. Saved to ``path`` if given."""
    w = np.logspace(-2, 4, 400) if omega is None else np.asarray(omega, dtype=float)
    return _draw([(plant, "G", "--", "0.5"), (shaped, "G W1", "-", "black")], w, title=title or "open-loop singular values",
                 crossover_rad_s=None, path=path)


def plot_loop_shape(design_: Any, path: str | None = None) -> Figure:
    """Singular values (dB) of the RFL plant ``G`` and of the shaped plant ``G W1`` of a
    :class:`rotorfault.control.lanzon.LanzonDesign` (Lanzon Fig. 4 style), with its target
    crossover. Saved to ``path`` if given."""
    omega = np.logspace(-2, 5, 500)
    return _draw(
        [(design_.vehicle.plant(), "G (plant after RFL)", "--", "0.5"), (design_.synthesis.shaped_plant, "G W1 (shaped plant)", "-", "black")],
        omega, title=f"Lanzon loop shape: gamma = {design_.gamma:.3f} (gamma_min {design_.gamma_min:.3f})",
        crossover_rad_s=design_.crossover_rad_s, path=path,
    )


__all__ = ["plot_loop_shape", "plot_singular_values"]

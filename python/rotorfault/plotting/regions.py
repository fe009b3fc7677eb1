"""Controllable regions: the verdicts of an efficiency scan over three rotors (Du Fig. 4)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt

from .style import finish, new_figure

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from .._util.convert import FloatArray


def plot_region(
    ok: npt.NDArray[np.bool_], levels: FloatArray, rotors: Sequence[int], airframe: str, give_up_yaw: bool, path: str | None
) -> Figure:
    """Du Fig. 4 style: a controllable region on an n x n x n grid of ``levels`` (``ok``: the
    verdict at each grid point, as a scan computed it; ``rotors`` the swept rotors, numbered from
    1). Left: the surface of the region (grid points that are controllable but have an
    uncontrollable neighbour), shaded by the third rotor's efficiency. Other panels: for each pair
    of swept rotors, the lowest efficiency of the third rotor that keeps the vehicle controllable,
    on a colour scale spanning the values that occur; hatched grey where no efficiency of the
    third rotor does ("uncontrollable"), which the scale never confuses with a small value. A scan
    giving up yaw says so in every title. Saved to ``path`` if given."""
    from matplotlib.patches import Patch

    padded = np.pad(ok, 1, constant_values=False)
    interior = np.ones_like(ok)
    for axis in range(3):
        for shift in (-1, 1):
            interior &= np.roll(padded, shift, axis=axis)[1:-1, 1:-1, 1:-1]
    # Faces of the unit cube are part of the region's surface too.
    surface = ok & ~interior
    labels = [f"$\\eta_{{{r}}}$" for r in rotors]
    axes_text = "giving up yaw (thrust, roll, pitch)" if give_up_yaw else "with yaw (thrust, roll, pitch, yaw)"
    fig = new_figure(figsize=(12, 10), layout="constrained")
    fig.suptitle(
        f"{airframe}: controllability {axes_text} as rotors {', '.join(map(str, rotors))} degrade "
        f"(grid step {levels[1] - levels[0]:g}, {ok.size:,} points)",
        fontsize=12,
    )
    ax3 = fig.add_subplot(2, 2, 1, projection="3d")
    i, j, k = np.nonzero(surface)
    if i.size:
        sc = ax3.scatter(levels[i], levels[j], levels[k], c=levels[k], s=3, cmap="viridis", vmin=0, vmax=1)
        fig.colorbar(sc, ax=ax3, shrink=0.6, pad=0.1, label=labels[2])
    ax3.set_xlim(0, 1)
    ax3.set_ylim(0, 1)
    ax3.set_zlim(0, 1)
    ax3.set_xlabel(labels[0])
    ax3.set_ylabel(labels[1])
    ax3.set_zlabel(labels[2])
    ax3.tick_params(labelsize=9)
    ax3.set_title(
        f"surface of the controllable region\n({100 * float(ok.mean()):.1f}% of the grid"
        f"{', giving up yaw' if give_up_yaw else ''})",
        fontsize=10,
    )
    lowest_all = []
    for a, b in ((0, 1), (0, 2), (1, 2)):
        other = 3 - a - b
        along = np.moveaxis(ok, other, -1)
        lowest_all.append(np.where(along.any(axis=-1), levels[np.argmax(along, axis=-1)], np.nan))
    values = np.concatenate([x[np.isfinite(x)] for x in lowest_all])
    vmin, vmax = (float(values.min()), float(values.max())) if values.size else (0.0, 1.0)
    if vmax - vmin < 1e-12:
        vmin, vmax = vmin - 0.05, vmax + 0.05
    for slot, (a, b), lowest in zip((2, 3, 4), ((0, 1), (0, 2), (1, 2)), lowest_all):
        ax = fig.add_subplot(2, 2, slot)
        other = 3 - a - b
        ax.set_facecolor("0.8")
        ax.patch.set_hatch("///")
        ax.patch.set_edgecolor("0.55")
        mesh = ax.pcolormesh(levels, levels, lowest.T, shading="nearest", cmap="viridis", vmin=vmin, vmax=vmax)
        ax.set_xlabel(labels[a])
        ax.set_ylabel(labels[b])
        ax.set_xlim(-0.5 * (levels[1] - levels[0]), 1 + 0.5 * (levels[1] - levels[0]))
        ax.set_ylim(-0.5 * (levels[1] - levels[0]), 1 + 0.5 * (levels[1] - levels[0]))
        ax.tick_params(labelsize=9)
        ax.set_title(f"lowest {labels[other]} that keeps control{' giving up yaw' if give_up_yaw else ''}", fontsize=10)
        ax.set_aspect("equal")
        fig.colorbar(mesh, ax=ax, shrink=0.8, label=f"lowest {labels[other]}")
        ax.legend(
            handles=[Patch(facecolor="0.8", edgecolor="0.55", hatch="///", label="uncontrollable for every " + labels[other])],
            loc="upper center", bbox_to_anchor=(0.5, -0.13), fontsize=9, frameon=False,
        )
    return finish(fig, path)


__all__ = ["plot_region"]

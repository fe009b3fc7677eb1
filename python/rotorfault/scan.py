"""Efficiency-grid scans: the controllable region of Du et al. Fig. 4.

Some rotors' efficiencies sweep a regular grid over [0, 1] while the others keep the airframe's
values; the ACAI is evaluated at every grid point by the parallel Rust batch.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np
import numpy.typing as npt

from ._convert import FloatArray, flag, real, rotor_numbers
from ._progress import chunks
from ._typing import AcaiFormula
from .airframe import Airframe, require_airframe
from .controllability import acai_batch

if TYPE_CHECKING:
    from matplotlib.figure import Figure

#: Points evaluated per batch call; bounds memory and drives the progress bar.
CHUNK_POINTS = 1 << 20
#: Largest grid a scan holds in memory (points, ACAI and efficiencies: about 4 GB for 3 rotors).
MAX_SCAN_POINTS = 100_000_000


@dataclass(frozen=True)
class EfficiencyScan:
    """Result of :func:`efficiency_scan`."""

    airframe: str
    #: Swept rotors, 1-based.
    rotors: tuple[int, ...]
    #: Grid values shared by every swept rotor.
    levels: FloatArray
    #: N x len(rotors) efficiencies of the swept rotors at each point (last rotor fastest).
    points: FloatArray
    #: ACAI at each point (``formula``: how a point with the hover wrench outside reads).
    acai: FloatArray
    give_up_yaw: bool
    #: Where the hover wrench lies at each point (:data:`rotorfault.controllability.HOVER_CODES`:
    #: 1 inside, 0 boundary, -1 outside, -2 rank deficient): eq. (13) prints 0 for some outside
    #: points, this column tells them from boundaries.
    hover_code: npt.NDArray[np.int8] = field(default_factory=lambda: np.zeros(0, dtype=np.int8))
    formula: AcaiFormula = "eq13"

    @property
    def controllable(self) -> np.ndarray[Any, np.dtype[np.bool_]]:
        return self.acai > 0.0

    @property
    def hover_feasible(self) -> np.ndarray[Any, np.dtype[np.bool_]]:
        """The hover wrench is attainable (inside or on the boundary) at each point."""
        return self.hover_code >= 0

    @property
    def controllable_fraction(self) -> float:
        return float(self.controllable.mean())

    def plot(self, path: str | None = None) -> Figure:
        """Du Fig. 4 style: the controllable points in 3-D and their projections."""
        return plot_efficiency_scan(self, path)


def efficiency_scan(
    airframe: Airframe,
    rotors: Sequence[int] = (1, 2, 5),
    step: float = 0.04,
    *,
    give_up_yaw: bool = False,
    formula: AcaiFormula = "eq13",
    progress: bool | None = None,
) -> EfficiencyScan:
    """Sweeps the efficiencies of ``rotors`` (1-based) over ``0, step, ..., 1`` (Du Fig. 4 uses
    rotors 1, 2, 5 of the PNPNPN hexacopter with step 0.04: 26^3 = 17,576 points).

    ``progress`` shows a progress bar (default: only for scans over 10 million points).
    """
    airframe = require_airframe(airframe)
    step = real("step", step)
    give_up_yaw = flag("give_up_yaw", give_up_yaw)
    if not 0.0 < step <= 1.0:
        raise ValueError(f"step: must lie in (0, 1], got {step}")
    swept = rotor_numbers("rotors", rotors, airframe.rotor_count)
    if not swept:
        raise ValueError("rotors: give at least one rotor to sweep")
    if len(set(swept)) != len(swept):
        raise ValueError(f"rotors: each rotor may be swept once, got {swept}")
    count = int(round(1.0 / step))
    if not np.isclose(count * step, 1.0, rtol=0.0, atol=1e-9):
        raise ValueError(f"step: must divide 1 evenly (0.04, 0.05, 0.1, ...), got {step}")
    # The size is checked on integers before anything is allocated.
    total = (count + 1) ** len(swept)
    if total > MAX_SCAN_POINTS:
        raise ValueError(
            f"step, rotors: {count + 1}^{len(swept)} = {total:,} grid points exceed the in-memory "
            f"limit of {MAX_SCAN_POINTS:,}; use a coarser step or fewer rotors"
        )
    levels = np.linspace(0.0, 1.0, count + 1)
    points = np.empty((total, len(swept)))
    grids = np.meshgrid(*([levels] * len(swept)), indexing="ij")
    for column, grid in enumerate(grids):
        points[:, column] = grid.ravel()
    base = airframe.efficiency
    columns = [r - 1 for r in swept]
    result = np.empty(total)
    hover = np.empty(total, dtype=np.int8)
    pieces = chunks(total, CHUNK_POINTS, description=f"ACAI over {total:,} points", show=progress, default_show=total > 10_000_000)
    for start, stop in pieces:
        efficiencies = np.tile(base, (stop - start, 1))
        efficiencies[:, columns] = points[start:stop]
        batch = acai_batch(airframe, efficiencies, give_up_yaw=give_up_yaw, formula=formula, with_hover=True)
        result[start:stop] = batch.acai
        hover[start:stop] = batch.hover_code
    return EfficiencyScan(airframe.name, swept, levels, points, result, give_up_yaw, hover, formula)


def plot_efficiency_scan(scan: EfficiencyScan, path: str | None = None) -> Figure:
    """Du Fig. 4 style. Left: the surface of the controllable region (grid points that are
    controllable but have an uncontrollable neighbour), shaded by the third rotor's efficiency.
    Other panels: for each pair of swept rotors, the lowest efficiency of the third rotor that
    keeps the vehicle controllable, on a colour scale spanning the values that occur; hatched
    grey where no efficiency of the third rotor does ("uncontrollable"), which the scale never
    confuses with a small value. A scan without yaw says so in every title. Needs exactly three
    swept rotors. Returns the figure (not registered with pyplot), saved to ``path`` (``.png``,
    ``.pdf`` or ``.svg``, written atomically) if given."""
    from matplotlib.patches import Patch

    from ._output import new_figure, save_figure

    if len(scan.rotors) != 3:
        raise ValueError(f"scan: the Fig. 4 plot needs three swept rotors, got {len(scan.rotors)}")
    n = len(scan.levels)
    ok = scan.controllable.reshape(n, n, n)
    padded = np.pad(ok, 1, constant_values=False)
    interior = np.ones_like(ok)
    for axis in range(3):
        for shift in (-1, 1):
            interior &= np.roll(padded, shift, axis=axis)[1:-1, 1:-1, 1:-1]
    # Faces of the unit cube are part of the region's surface too.
    surface = ok & ~interior
    labels = [f"$\\eta_{{{r}}}$" for r in scan.rotors]
    axes_text = "without yaw (thrust, roll, pitch)" if scan.give_up_yaw else "with yaw (thrust, roll, pitch, yaw)"
    fig = new_figure(figsize=(12, 10), layout="constrained")
    fig.suptitle(
        f"{scan.airframe}: controllability {axes_text} as rotors {', '.join(map(str, scan.rotors))} degrade "
        f"(grid step {scan.levels[1] - scan.levels[0]:g}, {len(scan.acai):,} points)",
        fontsize=12,
    )
    ax3 = fig.add_subplot(2, 2, 1, projection="3d")
    i, j, k = np.nonzero(surface)
    levels = scan.levels
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
        f"surface of the controllable region\n({100 * scan.controllable_fraction:.1f}% of the grid"
        f"{', without yaw' if scan.give_up_yaw else ''})",
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
        ax.set_title(f"lowest {labels[other]} that keeps control{' without yaw' if scan.give_up_yaw else ''}", fontsize=10)
        ax.set_aspect("equal")
        fig.colorbar(mesh, ax=ax, shrink=0.8, label=f"lowest {labels[other]}")
        ax.legend(
            handles=[Patch(facecolor="0.8", edgecolor="0.55", hatch="///", label="uncontrollable for every " + labels[other])],
            loc="upper center", bbox_to_anchor=(0.5, -0.13), fontsize=9, frameon=False,
        )
    if path is not None:
        save_figure(fig, path)
    return fig

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
    levels = np.linspace(0.0, 1.0, count + 1)
    total = len(levels) ** len(swept)
    if total > MAX_SCAN_POINTS:
        raise ValueError(
            f"step, rotors: {len(levels)}^{len(swept)} = {total:,} grid points exceed the in-memory "
            f"limit of {MAX_SCAN_POINTS:,}; use a coarser step or fewer rotors"
        )
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
    controllable but have an uncontrollable neighbour), coloured by height. Other panels: for
    each pair of swept rotors, the lowest efficiency of the third rotor that keeps the vehicle
    controllable (blank: none does). Needs exactly three swept rotors; saved to ``path`` if given."""
    import matplotlib

    if path is not None:
        matplotlib.use("Agg")
    import matplotlib.pyplot as plt

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
    fig = plt.figure(figsize=(12, 9.5))
    ax3 = fig.add_subplot(2, 2, 1, projection="3d")
    i, j, k = np.nonzero(surface)
    levels = scan.levels
    sc = ax3.scatter(levels[i], levels[j], levels[k], c=levels[k], s=3, cmap="viridis")
    ax3.set_xlabel(labels[0])
    ax3.set_ylabel(labels[1])
    ax3.set_zlabel(labels[2])
    ax3.set_title(f"{scan.airframe}: controllable region\n({100 * scan.controllable_fraction:.1f}% of the grid)")
    fig.colorbar(sc, ax=ax3, shrink=0.6, pad=0.12, label=labels[2])
    for slot, (a, b) in zip((2, 3, 4), ((0, 1), (0, 2), (1, 2))):
        ax = fig.add_subplot(2, 2, slot)
        other = 3 - a - b
        along = np.moveaxis(ok, other, -1)  # axes (a, b, other)
        lowest = np.where(along.any(axis=-1), levels[np.argmax(along, axis=-1)], np.nan)
        mesh = ax.pcolormesh(levels, levels, lowest.T, shading="nearest", cmap="magma_r", vmin=0, vmax=1)
        ax.set_xlabel(labels[a])
        ax.set_ylabel(labels[b])
        ax.set_title(f"lowest {labels[other]} that keeps control (blank: none)")
        ax.set_aspect("equal")
        fig.colorbar(mesh, ax=ax, shrink=0.8, label=labels[other])
    fig.tight_layout()
    if path is not None:
        fig.savefig(path, dpi=110)
    return fig

"""Lanzon, Freddi and Longhi (JGCD 2014), the equations: eq. (26) (the closed loop under the
robust feedback linearisation, linearised at the working point) and the loop shape of Section
III.C, each printed value beside ours as :class:`~rotorfault.papers._numbers.PaperNumber` rows
that the tests and ``rotorfault reproduce`` both read. The controller is
:mod:`rotorfault.control.lanzon`; the paper's flights are :mod:`rotorfault.papers.lanzon` (when it
is in the package, the report shows them too).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from .._util.convert import FloatArray
from ..plotting.frequency import plot_loop_shape
from ._numbers import PaperNumber

if TYPE_CHECKING:
    from ..control.lanzon import LanzonDesign, LanzonVehicle
    from ._report import ReportSection

PAPER = "Lanzon et al. (JGCD 2014)"
#: Central-difference step of the eq. (26) check, and its relative tolerance (the truncation
#: error of a central difference with this step on these magnitudes is far below it).
EQ26_STEP = 1e-6
EQ26_RTOL = 1e-6

#: Section III.C's loop shape: gain at low frequency (dB), crossover (rad/s), slopes (dB/decade).
LOOP_LOW_GAIN_DB = 60.0
LOOP_CROSSOVER_RAD_S = 100.0
LOOP_SLOPE_CROSSOVER_DB_DEC = -20.0
LOOP_SLOPE_HIGH_DB_DEC = -40.0


def eq26_printed(v: LanzonVehicle) -> tuple[FloatArray, FloatArray]:
    """Eq. (26a), (26b) as printed (typed from the paper), at ``v``'s parameters."""
    d, g, m, kr = v.drag_torque_ratio_m, v.gravity_m_s2, v.mass_kg, v.rotational_drag_n_m_s
    ixx, izz, arm = v.inertia_xx_kg_m2, v.inertia_zz_kg_m2, v.arm_length_m
    a = np.array([
        [0, d * g * m / kr, 1, 0, 0],
        [-d * g * m / kr, 0, 0, 1, 0],
        [0, 0, -kr / ixx, d * g * (ixx - izz) * m / (ixx * kr), 0],
        [0, 0, -d * g * (ixx - izz) * m / (ixx * kr), -kr / ixx, 0],
        [0, 0, 0, 0, -kr / izz],
    ])
    b = np.array([[0, 0, 0], [0, 0, 0], [arm / (2 * ixx), 0, -arm / (2 * d * ixx)], [0, 1 / ixx, 0], [0, 0, 1 / izz]])
    return a, b


@dataclass(frozen=True)
class Eq26Check:
    """Eq. (26) three ways: as printed (``a_printed``, ``b_printed``), our closed form
    (:meth:`LanzonVehicle.linearisation`) and the Jacobian of the closed loop ``x' = f(x) + G
    (alpha(x) + beta(x) v)`` by central differences with step ``step`` at the working point
    (``a_fd``, ``b_fd``): an independent check that the RFL produces (26)."""

    a_printed: FloatArray
    b_printed: FloatArray
    a_ours: FloatArray
    b_ours: FloatArray
    a_fd: FloatArray
    b_fd: FloatArray
    step: float


def eq26_check(v: LanzonVehicle | None = None, *, step: float = EQ26_STEP) -> Eq26Check:
    from ..control.lanzon import LanzonVehicle

    vehicle = LanzonVehicle() if v is None else v
    a26, b26 = eq26_printed(vehicle)
    a, b = vehicle.linearisation()

    def closed(x: FloatArray, w: FloatArray) -> FloatArray:
        alpha, beta = vehicle.rfl(x)
        return vehicle.reduced_dynamics(x, alpha + beta @ w)

    z5, z3 = np.zeros(5), np.zeros(3)
    ja = np.column_stack([(closed(step * e, z3) - closed(-step * e, z3)) / (2 * step) for e in np.eye(5)])
    jb = np.column_stack([(closed(z5, step * e) - closed(z5, -step * e)) / (2 * step) for e in np.eye(3)])
    return Eq26Check(a26, b26, a, b, ja, jb, step)


def eq26_numbers(v: LanzonVehicle | None = None) -> list[PaperNumber]:
    """Every non-zero entry of eq. (26) as printed (evaluated at Table 1 and ``k_r = m g d /
    2.7``) beside the finite-difference Jacobian of our closed loop; tolerance ``EQ26_RTOL``
    of the matrix's largest entry (the test's)."""
    check = eq26_check(v)
    rows = []
    for name, printed, ours in (("A_r", check.a_printed, check.a_fd), ("B_r", check.b_printed, check.b_fd)):
        scale = float(np.max(np.abs(printed)))
        for (i, j), value in np.ndenumerate(printed):
            if value != 0:
                rows.append(PaperNumber(PAPER, "eq. (26)", f"{name}[{i + 1},{j + 1}] of the closed loop under RFL (finite differences)",
                                        float(value), float(ours[i, j]), EQ26_RTOL * scale))
    return rows


def _slope_db_per_decade(omega: FloatArray, gain_db: FloatArray, lo: float, hi: float) -> float:
    return float((np.interp(math.log10(hi), np.log10(omega), gain_db) - np.interp(math.log10(lo), np.log10(omega), gain_db))
                 / math.log10(hi / lo))


def loop_shape_numbers(design_: LanzonDesign) -> list[PaperNumber]:
    """Section III.C's loop shape measured on our shaped plant ``G W1`` (largest singular value):
    the gain at 0.01 rad/s (60 dB), the crossover frequency (100 rad/s), the slope over the decade
    ending at the crossover (-20 dB/decade) and over 10^4..10^5 rad/s (-40 dB/decade)."""
    from ..control.robust import singular_values

    omega = np.logspace(-3, 6, 2000)
    gain_db = 20 * np.log10(singular_values(design_.synthesis.shaped_plant, omega)[:, 0])
    below = np.nonzero(gain_db < 0)[0]
    k = int(below[0])
    crossover = float(10 ** np.interp(0.0, [gain_db[k], gain_db[k - 1]], [math.log10(omega[k]), math.log10(omega[k - 1])]))
    low = float(np.interp(-2.0, np.log10(omega), gain_db))
    where = "Section III.C"
    return [
        PaperNumber(PAPER, where, "gain at 0.01 rad/s (dB) of the shaped plant G W1", LOOP_LOW_GAIN_DB, low, 1.0,
                    "" if abs(low - LOOP_LOW_GAIN_DB) <= 1.0 else
                    "the target L is 60 dB; G W1 = G(s) G(s + e)^-1 diag(L) (rotorfault.control.robust.loop_shape_weight) "
                    "shifts the weight's zeros left of the plant's undamped spin modes, which changes the low-frequency "
                    "plateau by the gain of G(0) G(e)^-1"),
        PaperNumber(PAPER, where, "crossover frequency (rad/s) of the shaped plant G W1", LOOP_CROSSOVER_RAD_S, crossover, 10.0,
                    "tolerance 10 %: the paper states the crossover as a design target"),
        PaperNumber(PAPER, where, "slope from crossover/10 to crossover (dB/decade) of the shaped plant G W1", LOOP_SLOPE_CROSSOVER_DB_DEC,
                    _slope_db_per_decade(omega, gain_db, crossover / 10, crossover), 2.0),
        PaperNumber(PAPER, where, "slope over 10^4..10^5 rad/s (dB/decade) of the shaped plant G W1", LOOP_SLOPE_HIGH_DB_DEC,
                    _slope_db_per_decade(omega, gain_db, 1e4, 1e5), 2.0),
    ]


def design_table_rows(design_: LanzonDesign) -> tuple[tuple[str, str], ...]:
    """The inner-loop design and the evidence its synthesis checked (the same on every install)."""
    e = design_.evidence
    return (
        ("gamma_min (Riccati)", f"{design_.gamma_min:.6f}"),
        ("gamma_min (Hankel formula, the check)", f"{e.gamma_min_hankel:.6f}"),
        ("gamma (1.1 gamma_min)", f"{design_.gamma:.6f}"),
        ("achieved four-block norm on the full shaped plant (<= gamma)", f"{e.achieved_norm:.6f}"),
        ("stability margin 1/gamma", f"{design_.stability_margin:.4f}"),
        ("shaped plant states (all kept by the synthesis)", f"{e.synthesis_states} of {e.full_states}"),
        ("slowest closed-loop pole with the plant (real part, 1/s)", f"{e.closed_loop_max_real:.4f}"),
    )


def report_section(out: Path, *, quick: bool = False) -> ReportSection:
    """Lanzon's part of ``rotorfault reproduce``: eq. (26) and the loop shape beside ours, the
    loop-shape figure, and the flights from :mod:`rotorfault.papers.lanzon` when that module is in
    the package (otherwise a "not landed yet" part)."""
    import importlib
    import time

    from ..control.lanzon import design
    from ._report import ReportFigure, ReportSection, ReportTable, not_landed

    start = time.perf_counter()
    section = ReportSection("lanzon", "Lanzon et al.: flying a quadrotor on three rotors by letting it spin",
                            source="rotorfault.papers.lanzon_checks, rotorfault.control.lanzon")
    section.numbers = eq26_numbers()
    ours = design()
    section.numbers += loop_shape_numbers(ours)
    section.tables.append(ReportTable(
        "The inner-loop design (H-infinity loop shaping with rotorfault.control.ncfsyn, the paper's 100 rad/s target)",
        ("quantity", "value"),
        design_table_rows(ours),
    ))
    plot_loop_shape(ours, str(out / "lanzon-loop-shape.png"))
    section.figures.append(ReportFigure("lanzon-loop-shape.png", "Singular values of the plant after RFL and of the shaped plant (Lanzon Fig. 4 style)."))
    try:
        flights_module = importlib.import_module("rotorfault.papers.lanzon")
    except ModuleNotFoundError as exc:
        if exc.name != "rotorfault.papers.lanzon":
            raise
        flights_module = None
    provider = getattr(flights_module, "report_section", None)
    if provider is None:
        section.parts.append(not_landed("lanzon-flights", "Lanzon's flights (Scenarios A and B, Figs. 5-10)",
                                        "rotorfault.papers.lanzon", "the paper's flights and their figures"))
    else:
        section.parts.append(provider(out, quick=quick))
    section.run_time_s = time.perf_counter() - start
    return section


__all__ = [
    "EQ26_RTOL",
    "EQ26_STEP",
    "Eq26Check",
    "PAPER",
    "eq26_check",
    "eq26_numbers",
    "eq26_printed",
    "design_table_rows",
    "loop_shape_numbers",
    "plot_loop_shape",
    "report_section",
]

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
from ..control.robust import singular_values
from ..plotting.frequency import plot_singular_values_db
from ._numbers import PaperNumber

if TYPE_CHECKING:
    from ..control.lanzon import LanzonDesign, LanzonVehicle
    from matplotlib.figure import Figure
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


def eq26_jacobian_numbers(v: LanzonVehicle | None = None) -> list[PaperNumber]:
    """Every non-zero entry of eq. (26) as printed (evaluated at Table 1 and ``k_r = m g d /
    2.7``) beside the finite-difference Jacobian of our closed loop at the working point;
    tolerance ``EQ26_RTOL`` of the matrix's largest entry (the test's).

    Kind: **consistency**, not scored. Any input-affine law with ``d alpha(0) = 0`` and
    ``beta(0) = I`` gives this Jacobian (with the linearisation switched off, ``alpha = 0``,
    ``beta = I``, all 13 still pass): it checks our typing of (26), not that the RFL produces
    it. The scored row is :func:`eq26_numbers` (the closed loop across the flown region)."""
    check = eq26_check(v)
    rows = []
    for name, printed, ours in (("A_r", check.a_printed, check.a_fd), ("B_r", check.b_printed, check.b_fd)):
        scale = float(np.max(np.abs(printed)))
        for (i, j), value in np.ndenumerate(printed):
            if value != 0:
                rows.append(PaperNumber(PAPER, "eq. (26)", f"{name}[{i + 1},{j + 1}] of the closed loop under RFL at x = 0 "
                                        "(finite differences; consistency, not scored)",
                                        float(value), float(ours[i, j]), EQ26_RTOL * scale,
                                        "consistency: passes for any law with d alpha(0) = 0 and beta(0) = I",
                                        kind="consistency"))
    return rows


@dataclass(frozen=True)
class Eq26ClosedLoop:
    """Eq. (26) tested away from hover: at ``samples`` random states ``x`` (uniform in
    ``+-EQ26_STATE_HALF_WIDTH``) and inputs ``v`` (uniform in ``+-EQ26_INPUT_HALF_WIDTH``) the
    closed loop ``x' = f(x) + G (alpha(x) + beta(x) v)`` moves ``x_r = T^-1 phi_c(x)`` (21c)
    at ``d x_r/dt = T^-1 (d phi_c/dx) x'`` (a central difference of ``phi_c`` along ``x'``), which
    exact feedback linearisation makes ``A_r x_r + B_r v`` with eq. (26) as printed.
    ``max_relative_error``: the largest ``|d x_r/dt - (A_r x_r + B_r v)|_inf`` over the samples,
    each divided by the size of its terms (``max(|A_r x_r|, |B_r v|, |d x_r/dt|)``, inf-norms);
    ``worst_state`` and ``worst_input`` where it occurs. ``linearised`` False: the same with the
    linearisation switched off (``alpha = 0``, ``beta = I``), the break test."""

    samples: int
    max_relative_error: float
    worst_state: FloatArray
    worst_input: FloatArray
    linearised: bool


#: The region of the eq. (26) check, half widths of ``[phi, theta, p, q, r - r0]`` (rad, rad/s):
#: the paper's flights start at roll -45 deg, pitch 45 deg (Table 2) and, flown with the paper's
#: design (cases a and b, both scenarios, both I_zz, 60 s, until 0.5 s before a loss), pass
#: through |phi|, |theta| <= 50.4 deg, |p|, |q| <= 44.6 rad/s (case a's first second) and
#: |r - r0| <= 0.63 rad/s: the region covers them (r from 0 to 2 r0).
EQ26_STATE_HALF_WIDTH = (math.radians(55.0), math.radians(55.0), 45.0, 45.0, 2.7)
#: ... and of ``v = [u1, u2, u3]`` (N, N m, N m): a 5 N thrust swing, 5 N on an arm, 5 N times d.
EQ26_INPUT_HALF_WIDTH = (5.0, 5.0 * 0.255, 5.0 * 2.4e-3)
EQ26_SAMPLES = 500
EQ26_SEED = 26
#: Relative tolerance of the closed loop against (26): the central difference's error (step
#: ``EQ26_STEP`` relative to the state) is below 1e-8 of the terms (5.6e-9 measured); switched off, 2.6.
EQ26_CLOSED_LOOP_RTOL = 1e-6


def eq26_closed_loop(
    v: LanzonVehicle | None = None, *, samples: int = EQ26_SAMPLES, seed: int = EQ26_SEED, linearised: bool = True,
) -> Eq26ClosedLoop:
    """The closed loop under the RFL against eq. (26) across the flown region
    (:class:`Eq26ClosedLoop`)."""
    from ..control.lanzon import LanzonVehicle

    vehicle = LanzonVehicle() if v is None else v
    a26, b26 = eq26_printed(vehicle)
    t_inv = np.linalg.inv(vehicle.transform_matrix())
    rng = np.random.default_rng(seed)
    states = rng.uniform(-1.0, 1.0, (samples, 5)) * np.asarray(EQ26_STATE_HALF_WIDTH)
    inputs = rng.uniform(-1.0, 1.0, (samples, 3)) * np.asarray(EQ26_INPUT_HALF_WIDTH)
    worst, at = -1.0, 0
    for k, (x, w) in enumerate(zip(states, inputs)):
        alpha, beta = vehicle.rfl(x) if linearised else (np.zeros(3), np.eye(3))
        xdot = vehicle.reduced_dynamics(x, alpha + beta @ w)
        h = EQ26_STEP * max(1.0, float(np.max(np.abs(x)))) / max(1.0, float(np.max(np.abs(xdot))))
        lhs = t_inv @ (vehicle.brunovsky(x + h * xdot) - vehicle.brunovsky(x - h * xdot)) / (2 * h)
        linear, forced = a26 @ (t_inv @ vehicle.brunovsky(x)), b26 @ w
        scale = max(float(np.max(np.abs(linear))), float(np.max(np.abs(forced))), float(np.max(np.abs(lhs))))
        err = float(np.max(np.abs(lhs - linear - forced))) / scale
        if err > worst:
            worst, at = err, k
    return Eq26ClosedLoop(samples, worst, states[at], inputs[at], linearised)


def eq26_numbers(v: LanzonVehicle | None = None) -> list[PaperNumber]:
    """Eq. (26) where it matters (kind: **reproduced**, scored): the closed loop under the RFL
    equals the printed linear model across the region the paper flies in
    (:func:`eq26_closed_loop`), printed at Table 1's ``I_zz`` and at the probable ``1.16e-2``.
    The paper's claim is exactness (an error of 0); tolerance ``EQ26_CLOSED_LOOP_RTOL``. With the
    linearisation switched off the error is of order 1 and the row fails (tested)."""
    from ..control.lanzon import LanzonVehicle

    base = LanzonVehicle() if v is None else v
    rows = []
    for izz in (base.inertia_zz_kg_m2, 1.16e-2) if v is None else (base.inertia_zz_kg_m2,):
        check = eq26_closed_loop(base.replace(inertia_zz_kg_m2=izz))
        half = EQ26_STATE_HALF_WIDTH
        rows.append(PaperNumber(
            PAPER, "eq. (26)",
            f"closed loop under RFL minus A_r x_r + B_r v, largest relative error over {check.samples} random states "
            f"(|phi|, |theta| <= {math.degrees(half[0]):.0f} deg, |p|, |q| <= {half[2]:g} rad/s, |r - r0| <= {half[4]:g} rad/s: "
            f"the paper's flights) and inputs, I_zz = {izz:g}",
            0.0, check.max_relative_error, EQ26_CLOSED_LOOP_RTOL,
            "reproduced: the RFL makes the nonlinear model (23) the linear (26) away from hover; "
            "with alpha = 0, beta = I this error is of order 1", kind="reproduced"))
    return rows


def _slope_db_per_decade(omega: FloatArray, gain_db: FloatArray, lo: float, hi: float) -> float:
    return float((np.interp(math.log10(hi), np.log10(omega), gain_db) - np.interp(math.log10(lo), np.log10(omega), gain_db))
                 / math.log10(hi / lo))


@dataclass(frozen=True)
class AchievedLoop:
    """The loop the synthesised controller achieves with the plant, ``L = G K`` broken at the
    plant's outputs ``[phi, theta, r - r0]`` (``K = W1 Ks`` of
    :func:`~rotorfault.control.ncfsyn`, negative feedback), measured on its largest singular
    value over ``omega`` (10^-3..10^6 rad/s, 4,000 points): ``low_gain_db`` at 0.01 rad/s,
    ``crossover_rad_s`` where it falls through 0 dB, ``slope_crossover_db_dec`` over the decade
    ending at the crossover, ``slope_high_db_dec`` over 10^4..10^5 rad/s. The margins:
    ``sensitivity_peak`` ``Ms = max sigma((I + L)^-1)`` and the multivariable gain and phase margins
    it guarantees (``1 / (1 - 1/Ms)``, ``2 asin(1 / (2 Ms))``), and ``stability_margin`` the
    normalised coprime factor margin ``1 / ||[I; Ks] (I + Gs Ks)^-1 [I, Gs]||_inf`` of the shaped
    loop, from the same sweep (the synthesis guarantees it is at least ``1/gamma``)."""

    low_gain_db: float
    crossover_rad_s: float
    slope_crossover_db_dec: float
    slope_high_db_dec: float
    sensitivity_peak: float
    gain_margin_db: float
    phase_margin_deg: float
    stability_margin: float


def _crossover(omega: FloatArray, gain_db: FloatArray) -> float:
    below = np.nonzero(gain_db < 0)[0]
    if below.size == 0 or below[0] == 0:
        return math.nan
    k = int(below[0])
    return float(10 ** np.interp(0.0, [gain_db[k], gain_db[k - 1]], [math.log10(omega[k]), math.log10(omega[k - 1])]))


def achieved_loop(design_: LanzonDesign) -> AchievedLoop:
    """Measures :class:`AchievedLoop` of ``design_`` (plant and controller frequency responses
    multiplied, not the target the design was given)."""
    from ..control.realisation import frequency_response
    from ..control.robust import four_block

    omega = np.logspace(-3, 6, 4000)
    g = frequency_response(design_.vehicle.plant(), omega)
    k = frequency_response(design_.controller, omega)
    loop = g @ k
    gain_db = 20 * np.log10(np.linalg.svd(loop, compute_uv=False)[:, 0])
    crossover = _crossover(omega, gain_db)
    eye = np.eye(loop.shape[1])
    ms = float(np.max(np.linalg.svd(np.linalg.inv(eye + loop), compute_uv=False)[:, 0]))
    syn = design_.synthesis
    fb = frequency_response(four_block(syn.shaped_plant, syn.shaped_controller), omega)
    b = 1.0 / float(np.max(np.linalg.svd(fb, compute_uv=False)[:, 0]))
    return AchievedLoop(
        low_gain_db=float(np.interp(-2.0, np.log10(omega), gain_db)),
        crossover_rad_s=crossover,
        slope_crossover_db_dec=_slope_db_per_decade(omega, gain_db, crossover / 10, crossover) if math.isfinite(crossover) else math.nan,
        slope_high_db_dec=_slope_db_per_decade(omega, gain_db, 1e4, 1e5),
        sensitivity_peak=ms,
        gain_margin_db=float(20 * math.log10(1 / (1 - 1 / ms))) if ms > 1 else math.inf,
        phase_margin_deg=float(math.degrees(2 * math.asin(min(1.0, 1 / (2 * ms))))),
        stability_margin=b,
    )


def loop_shape_numbers(design_: LanzonDesign, loop: AchievedLoop | None = None) -> list[PaperNumber]:
    """Section III.C's loop shape (kind: **reproduced**, scored) measured on the achieved loop
    ``G K`` (:func:`achieved_loop`): gain at 0.01 rad/s (60 dB, 1 dB), crossover (100 rad/s,
    10 %), slope over the decade ending at the crossover (-20 dB/decade, 2) and over
    10^4..10^5 rad/s (-40 dB/decade, 2). A design for 80 or 125 rad/s fails the crossover row
    (tested). The paper prints no margin and no gamma: those are in :func:`design_table_rows`."""
    loop = achieved_loop(design_) if loop is None else loop
    where = "Section III.C"
    low = loop.low_gain_db
    return [
        PaperNumber(PAPER, where, "gain at 0.01 rad/s (dB) of the achieved loop G K", LOOP_LOW_GAIN_DB, low, 1.0,
                    "" if abs(low - LOOP_LOW_GAIN_DB) <= 1.0 else
                    "the target L is 60 dB; G W1 = G(s) G(s + e)^-1 diag(L) (rotorfault.control.robust.loop_shape_weight) "
                    "shifts the weight's zeros left of the plant's undamped spin modes, which changes the low-frequency "
                    "plateau by the gain of G(0) G(e)^-1, and Ks adds its own low-frequency gain", kind="reproduced"),
        PaperNumber(PAPER, where, "crossover frequency (rad/s) of the achieved loop G K", LOOP_CROSSOVER_RAD_S,
                    loop.crossover_rad_s, 10.0, "tolerance 10 %", kind="reproduced"),
        PaperNumber(PAPER, where, "slope from crossover/10 to crossover (dB/decade) of the achieved loop G K",
                    LOOP_SLOPE_CROSSOVER_DB_DEC, loop.slope_crossover_db_dec, 2.0, kind="reproduced"),
        PaperNumber(PAPER, where, "slope over 10^4..10^5 rad/s (dB/decade) of the achieved loop G K", LOOP_SLOPE_HIGH_DB_DEC,
                    loop.slope_high_db_dec, 2.0, kind="reproduced"),
    ]


def design_table_rows(design_: LanzonDesign, loop: AchievedLoop | None = None) -> tuple[tuple[str, str], ...]:
    """The inner-loop design and the evidence its synthesis checked (the same on every install)."""
    e = design_.evidence
    loop = achieved_loop(design_) if loop is None else loop
    return (
        ("gamma_min (Riccati)", f"{design_.gamma_min:.6f}"),
        ("gamma_min (Hankel formula, the check)", f"{e.gamma_min_hankel:.6f}"),
        ("gamma (1.1 gamma_min)", f"{design_.gamma:.6f}"),
        ("achieved four-block norm on the full shaped plant (<= gamma)", f"{e.achieved_norm:.6f}"),
        ("stability margin 1/gamma", f"{design_.stability_margin:.4f}"),
        ("shaped plant states (all kept by the synthesis)", f"{e.synthesis_states} of {e.full_states}"),
        ("slowest closed-loop pole with the plant (real part, 1/s)", f"{e.closed_loop_max_real:.4f}"),
        ("achieved loop G K: crossover (rad/s)", f"{loop.crossover_rad_s:.1f}"),
        ("achieved loop: sensitivity peak Ms (the paper prints no margin)", f"{loop.sensitivity_peak:.3f}"),
        ("guaranteed multivariable gain margin (dB) / phase margin (deg) from Ms",
         f"{loop.gain_margin_db:.2f} / {loop.phase_margin_deg:.1f}"),
        ("coprime-factor stability margin of the shaped loop, by frequency sweep (>= 1/gamma)", f"{loop.stability_margin:.4f}"),
    )


def plot_loop_shape(design_: LanzonDesign, path: str | None = None) -> Figure:
    """The report's Fig. 4: singular values (dB) of the RFL plant ``G`` and of the shaped plant
    ``G W1`` of ``design_`` from 1e-2 to 1e5 rad/s, with its target crossover (computed by
    :func:`~rotorfault.control.robust.singular_values`, drawn by :mod:`rotorfault.plotting`).
    Saved to ``path`` if given."""
    omega = np.logspace(-2, 5, 500)
    curves = [(singular_values(design_.vehicle.plant(), omega), "G (plant after RFL)", "--", "0.5"),
              (singular_values(design_.synthesis.shaped_plant, omega), "G W1 (shaped plant)", "-", "black")]
    return plot_singular_values_db(
        omega, curves, path, title=f"Lanzon loop shape: gamma = {design_.gamma:.3f} (gamma_min {design_.gamma_min:.3f})",
        crossover_rad_s=design_.crossover_rad_s,
    )


def report_section(out: Path, *, quick: bool = False) -> ReportSection:
    """Lanzon's part of ``rotorfault reproduce``: eq. (26) and the loop shape beside ours, the
    loop-shape figure, and the flights from :mod:`rotorfault.papers.lanzon` (their report part,
    :mod:`rotorfault.papers.lanzon_report`) when that module is in the package (otherwise a "not
    landed yet" part)."""
    import importlib
    import time

    from ..control.lanzon import design
    from ._report import ReportFigure, ReportSection, ReportTable, not_landed

    start = time.perf_counter()
    section = ReportSection("lanzon", "Lanzon et al.: flying a quadrotor on three rotors by letting it spin",
                            source="rotorfault.papers.lanzon_checks, rotorfault.control.lanzon")
    # Scored: the closed loop across the flown region and the achieved loop (kind reproduced); the
    # 13 Jacobian-at-0 entries check our typing of (26) and pass with the linearisation switched
    # off: shown beside them as consistency rows, not scored.
    section.numbers = eq26_numbers()
    ours = design()
    loop = achieved_loop(ours)
    section.numbers += loop_shape_numbers(ours, loop)
    section.numbers += eq26_jacobian_numbers()
    section.tables.append(ReportTable(
        "The inner-loop design (H-infinity loop shaping with rotorfault.control.ncfsyn, the paper's 100 rad/s target)",
        ("quantity", "value"),
        design_table_rows(ours, loop),
    ))
    plot_loop_shape(ours, str(out / "lanzon-loop-shape.png"))
    section.figures.append(ReportFigure("lanzon-loop-shape.png", "Singular values of the plant after RFL and of the shaped plant (Lanzon Fig. 4 style)."))
    try:
        flights_module = importlib.import_module("rotorfault.papers.lanzon_report")
    except ModuleNotFoundError as exc:
        if exc.name not in ("rotorfault.papers.lanzon", "rotorfault.papers.lanzon_report"):
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
    "EQ26_CLOSED_LOOP_RTOL",
    "EQ26_INPUT_HALF_WIDTH",
    "EQ26_RTOL",
    "EQ26_SAMPLES",
    "EQ26_STATE_HALF_WIDTH",
    "EQ26_STEP",
    "AchievedLoop",
    "Eq26Check",
    "Eq26ClosedLoop",
    "achieved_loop",
    "eq26_closed_loop",
    "eq26_jacobian_numbers",
    "PAPER",
    "eq26_check",
    "eq26_numbers",
    "eq26_printed",
    "design_table_rows",
    "loop_shape_numbers",
    "plot_loop_shape",
    "report_section",
]

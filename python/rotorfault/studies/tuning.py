"""Robust tuning of Ke's gains: a search (scipy's differential evolution) over the gains, every
candidate flown on the same runs. Two searches share the driver (:func:`_search`):

- :func:`tune` (``rotorfault campaign --tune``): five gains of the position and attitude loops,
  minimising the worst excursion over a campaign of total single and double failures, lost runs
  costing most, then checked on a fresh campaign;
- :func:`tune_hold` (``python benches/ke_robust.py``, the ``ke-robust`` preset): also the gains
  :func:`tune` leaves at Table IV (the estimator's filter ``epsilon_s``, the compensation gains
  ``k_rotor`` and ``k_rotor_z``, the yaw-rate gain ``k_r``, the gyroscopic gain ``k_cp`` and the
  allocation weights), over partial and total faults (:func:`rotorfault.studies.hold.fault_set`),
  holding first (:class:`rotorfault.studies.hold.HoldCriteria`: the whole flight after the fault
  within 2 m altitude and 5 m horizontal, never lost), locally or on Dask.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from .._typing import ScanBackend as Backend
from .._util.convert import count, real
from .._util.progress import progress_bar
from ..control.ke import KeGains
from .campaign import Campaign, _pair, run_chunk
from .backends import dask_client
from .hold import FaultCase, HoldComparison, HoldCriteria, compare_holds, fault_set, fly_case, mean_severity

#: Ke gains tuned by default, with their search bounds (Table IV's values lie inside).
TUNED_GAINS: dict[str, tuple[float, float]] = {
    "k_p": (0.1, 2.0),
    "k_v": (0.05, 2.0),
    "accel_limit_m_s2": (0.1, 5.0),
    "k_n3": (1.0, 10.0),
    "k_omega": (5.0, 30.0),
}

#: Search names of the allocation weights ``W = diag(w_f, w_tau_p, w_tau_q, w_tau_r)`` of (33)
#: and the entries each sets (roll and pitch together: the airframe is symmetric). ``w_f`` stays
#: 1: scaling every weight alike changes no allocation.
WEIGHT_NAMES: dict[str, tuple[int, ...]] = {"w_tau_pq": (1, 2), "w_tau_r": (3,)}
#: Names searched in log10 coordinates (bounds spanning decades).
LOG_SCALED = frozenset({"epsilon_s", "k_rotor", "k_rotor_z", "w_tau_pq", "w_tau_r"})
#: The robust search (:func:`tune_hold`): every gain that acts when a rotor degrades, with
#: bounds that hold Table IV's values (k_cp: Remark 4's 0.6; the weights: Table IV's 20 and 0.01)
#: and the rest of the preset fixed (k_vz = 1, k_iz = 0.1, w_f = 1).
ROBUST_GAINS: dict[str, tuple[float, float]] = {
    "k_p": (0.1, 3.0),
    "k_v": (0.05, 3.0),
    "accel_limit_m_s2": (0.1, 8.0),
    "k_n3": (1.0, 12.0),
    "k_omega": (3.0, 30.0),
    "k_r": (0.5, 10.0),
    "k_cp": (0.0, 1.5),
    "epsilon_s": (0.01, 0.1),
    "k_rotor": (1.0, 50.0),
    "k_rotor_z": (0.02, 5.0),
    "w_tau_pq": (1.0, 200.0),
    "w_tau_r": (1e-3, 1.0),
}


@dataclass(frozen=True)
class TuningResult:
    """Table IV (the campaign's own gains) against the tuned gains, each scored on the tuning
    campaign and on a fresh validation campaign: worst altitude loss and horizontal excursion
    over the runs, and how many were lost.

    Examples:

        >>> from rotorfault.studies import Campaign, tune
        >>> campaign = Campaign(runs=2, duration_s=1.0, failures=((1,),), fault_time_s=(0.5, 0.5))
        >>> result = tune(campaign, maxiter=1, popsize=1, bounds={"k_p": (0.5, 2.0)})
        >>> type(result.tuned).__name__, result.scenarios
        ('KeGains', 2)
    """

    baseline: KeGains
    tuned: KeGains
    scores: dict[str, dict[str, float]]
    candidates: int
    scenarios: int

    def table(self) -> str:
        names = list(TUNED_GAINS)
        lines = ["gain                 Table IV      tuned"]
        for n in names:
            lines.append(f"{n:<20} {getattr(self.baseline, n):>8.3f} {getattr(self.tuned, n):>10.3f}")
        lines.append("")
        lines.append("campaign / gains       lost   worst alt loss (m)   worst horizontal (m)")
        for key, s in self.scores.items():
            lines.append(f"{key:<22} {int(s['lost']):>4}   {s['max_altitude_loss_m']:>18.2f}   {s['max_horizontal_error_m']:>20.2f}")
        return "\n".join(lines)


def _score(columns: dict[str, np.ndarray[Any, Any]]) -> dict[str, float]:
    lost = np.isin(columns["verdict"], ("crashed", "diverged"))
    return {
        "lost": float(lost.sum()),
        "max_altitude_loss_m": float(np.max(columns["max_altitude_loss_m"])),
        "max_horizontal_error_m": float(np.max(columns["max_horizontal_error_m"])),
    }


def _objective(score: dict[str, float], runs: int) -> float:
    """Worst-case excursion against the goal (2 m altitude, 10 m horizontal), a lost run costing
    more than any excursion: minimised."""
    excursion = max(score["max_altitude_loss_m"] / 2.0, score["max_horizontal_error_m"] / 10.0)
    return 100.0 * score["lost"] / runs + min(excursion, 50.0)


def _space(bounds: Mapping[str, tuple[float, float]]) -> dict[str, tuple[float, float]]:
    """Checked search bounds: Ke gain names, or :data:`WEIGHT_NAMES` for the allocation weights."""
    known = set(KeGains.FIELDS) - {"weights"} | set(WEIGHT_NAMES)
    space = {}
    for name, pair in bounds.items():
        if name not in known:
            raise ValueError(f"bounds.{name}: unknown Ke gain; known: {', '.join(sorted(known))}")
        lo, hi = _pair(f"bounds.{name}", pair, low=0.0)
        if name in LOG_SCALED and lo <= 0.0:
            raise ValueError(f"bounds.{name}: searched on a log scale, so the low bound must be > 0, got {lo}")
        space[name] = (lo, hi)
    return space


def _gains_of(baseline: KeGains, space: Mapping[str, tuple[float, float]], x: Sequence[float] | np.ndarray[Any, Any]) -> KeGains:
    """The gains at search point ``x`` (log10 coordinates for :data:`LOG_SCALED` names): the
    baseline with the searched values replaced. Raises ``ValueError`` for gains the core refuses."""
    values: dict[str, Any] = {}
    weights = list(baseline.weights)
    for name, v in zip(space, x):
        value = 10.0 ** float(v) if name in LOG_SCALED else float(v)
        if name in WEIGHT_NAMES:
            for k in WEIGHT_NAMES[name]:
                weights[k] = value
        else:
            values[name] = value
    if any(n in WEIGHT_NAMES for n in space):
        values["weights"] = tuple(weights)
    return baseline.replace(**values)


def _point_of(gains: KeGains, space: Mapping[str, tuple[float, float]]) -> list[float]:
    """``gains`` as a search point, clipped into the bounds (DE's ``x0`` must lie inside)."""
    out = []
    for name, (lo, hi) in space.items():
        value = gains.weights[WEIGHT_NAMES[name][0]] if name in WEIGHT_NAMES else float(getattr(gains, name))
        value = min(max(value, lo), hi)
        out.append(float(np.log10(value)) if name in LOG_SCALED else value)
    return out


@dataclass(frozen=True)
class _PointCost:
    """``cost(gains)`` at a search point (picklable, so Dask workers can evaluate it); gains the
    core refuses (e.g. ``k_omega <= 0.5``) cost 1e6."""

    baseline: KeGains
    space: dict[str, tuple[float, float]]
    cost: Callable[[KeGains], float]

    def __call__(self, x: np.ndarray[Any, Any]) -> float:
        try:
            gains = _gains_of(self.baseline, self.space, x)
        except ValueError:
            return 1e6
        return float(self.cost(gains))


#: Maps a point cost over a generation's points: ``mapper(cost, points) -> costs`` in order.
Mapper = Callable[[Callable[[np.ndarray[Any, Any]], float], list[np.ndarray[Any, Any]]], list[float]]


#: Most candidates one search flies, ``(maxiter + 1) x popsize x gains`` (scipy's differential
#: evolution): far above any search worth running (the defaults fly a few hundred), below one that
#: would run for days (popsize 10^6 was accepted and ran on; hostile harness).
MAX_CANDIDATES = 100_000


def _search(
    cost: Callable[[KeGains], float], baseline: KeGains, space: dict[str, tuple[float, float]], *, maxiter: int, popsize: int,
    seed: int, progress: bool | None, description: str, x0: KeGains | None = None, mapper: Mapper | None = None,
) -> tuple[KeGains, int]:
    """Differential evolution over ``space`` from a population that holds ``x0`` (default the
    baseline), so the best candidate scores no worse than it on the same runs: the tuned gains
    and how many candidates were flown. ``cost(gains)`` is minimised, a generation at a time
    through ``mapper`` (default: one after the other), with a progress bar of candidates."""
    from scipy.optimize import differential_evolution  # type: ignore[import-untyped]

    for name, value in (("maxiter", maxiter), ("popsize", popsize), ("seed", seed)):
        if isinstance(value, bool) or not isinstance(value, int) or value < (0 if name != "popsize" else 1):
            raise ValueError(f"{name}: must be an integer >= {0 if name != 'popsize' else 1}, got {value!r}")
    total = (maxiter + 1) * popsize * len(space)
    if total > MAX_CANDIDATES:
        raise ValueError(f"maxiter, popsize: (maxiter + 1) x popsize x {len(space)} gains = {total:,} candidates, more than the "
                         f"{MAX_CANDIDATES:,} one search flies (each candidate is a flight per fault case)")
    point_cost = _PointCost(baseline, dict(space), cost)
    evaluations = [0]
    bounds = [(float(np.log10(lo)), float(np.log10(hi))) if n in LOG_SCALED else (lo, hi) for n, (lo, hi) in space.items()]
    with progress_bar(total, description=description.format(total=total), show=progress) as advance:

        def generation(f: Callable[[np.ndarray[Any, Any]], float], points: Any) -> list[float]:
            batch = [np.asarray(x, dtype=np.float64) for x in points]
            costs = list(map(f, batch)) if mapper is None else mapper(f, batch)
            evaluations[0] += len(batch)
            advance(len(batch))
            return costs

        result = differential_evolution(
            point_cost, bounds, x0=_point_of(baseline if x0 is None else x0, space), maxiter=maxiter, popsize=popsize,
            seed=seed, polish=False, tol=0.0, updating="deferred", workers=generation,
        )
    return _gains_of(baseline, space, result.x), evaluations[0]


def tune(
    campaign: Campaign,
    *,
    validation_seed: int | None = None,
    bounds: Mapping[str, tuple[float, float]] | None = None,
    maxiter: int = 10,
    popsize: int = 5,
    progress: bool | None = None,
) -> TuningResult:
    """Robust tuning of Ke's gains: scipy's differential evolution minimises the worst-case
    excursion (lost runs penalised first) over ``campaign``'s runs, every candidate flown on the
    same runs (common random numbers); then Table IV and the tuned gains are both scored on a
    fresh campaign (``validation_seed``, default ``seed + 1``) they were not tuned on.

    Examples:

        >>> from rotorfault.studies import Campaign, tune
        >>> campaign = Campaign(runs=2, duration_s=1.0, failures=((1,),), fault_time_s=(0.5, 0.5))
        >>> result = tune(campaign, maxiter=1, popsize=1, bounds={"k_p": (0.5, 2.0)})
        >>> result.candidates, sorted(result.scores)
        (10, ['tuning, Table IV', 'tuning, tuned', 'validation, Table IV', 'validation, tuned'])
    """
    if not isinstance(campaign, Campaign):
        raise TypeError(f"campaign: expected rotorfault.studies.Campaign, got {type(campaign).__name__}")
    if campaign.controller == "lqr":
        raise ValueError("campaign.controller: tuning searches Ke's gains; use ke-hil or ke-experiment")
    for name, value in (("maxiter", maxiter), ("popsize", popsize)):
        if count(name, value) < 1:
            raise ValueError(f"{name}: must be >= 1, got {value}")
    if bounds is not None and not isinstance(bounds, Mapping):
        raise TypeError(f"bounds: expected a mapping of Ke gain names to (low, high), got {type(bounds).__name__}")
    space = _space(TUNED_GAINS if bounds is None else bounds)
    if not space:
        raise ValueError("bounds: expected at least one Ke gain to tune")
    baseline = campaign.gains or campaign.vehicle().gains

    def fly(c: Campaign) -> dict[str, np.ndarray[Any, Any]]:
        parts = [run_chunk(c, k) for k in range(c.chunk_count())]
        return {k: np.concatenate([p[k] for p in parts]) for k in parts[0]}

    def cost(gains: KeGains) -> float:
        return _objective(_score(fly(replace(campaign, gains=gains))), campaign.runs)

    tuned, candidates = _search(
        cost, baseline, space, maxiter=maxiter, popsize=popsize, seed=campaign.seed, progress=progress,
        description=f"tuning: {{total}} candidates x {campaign.runs} runs",
    )
    fresh = replace(campaign, seed=campaign.seed + 1 if validation_seed is None else validation_seed)
    scores = {
        "tuning, Table IV": _score(fly(replace(campaign, gains=baseline))),
        "tuning, tuned": _score(fly(replace(campaign, gains=tuned))),
        "validation, Table IV": _score(fly(replace(fresh, gains=baseline))),
        "validation, tuned": _score(fly(replace(fresh, gains=tuned))),
    }
    return TuningResult(baseline, tuned, scores, candidates, campaign.runs)


#: The tuning campaign of issue 13: every single failure and every stabilisable double failure
#: of Ke's quadcopter (adjacent side pairs and opposite pairs, both orders) from hover.
def tuning_campaign(*, runs: int = 200, seed: int = 0, duration_s: float = 25.0) -> Campaign:
    """The campaign :func:`tune` scores gains on: ``runs`` flights of ``duration_s`` (s) with every
    single failure and every ordered pair of failures (the first in 1-4 s, the second 4-8 s
    later), in one chunk; ``seed`` fixes the draws (common random numbers across candidates).

    Examples:

        >>> from rotorfault.studies import tuning_campaign
        >>> campaign = tuning_campaign(runs=10)
        >>> campaign.runs, campaign.duration_s, campaign.controller
        (10, 25.0, 'ke-hil')
    """
    pairs = ((1, 2), (2, 1), (3, 4), (4, 3), (1, 3), (3, 1), (2, 4), (4, 2))
    campaign = Campaign(
        runs=runs, seed=seed, duration_s=duration_s, failures=((1,), (2,), (3,), (4,), *pairs), fault_time_s=(1.0, 4.0), gap_s=(4.0, 8.0),
    )
    return replace(campaign, chunk_size=campaign.runs)  # runs checked by the Campaign first


# -- the hold search: partial and total faults -------------------------------------------------


@dataclass(frozen=True)
class HoldCost:
    """What :func:`tune_hold` minimises for one gain set: the share of ``cases`` that do not
    hold plus a tenth of the mean severity (:meth:`~rotorfault.studies.hold.PostFaultHold.severity`:
    the largest error as a fraction of its band, 10 for a lost run). A case that holds adds at
    most 0.1 / n, one that does not at least 1.1 / n: holding comes first, the margins second."""

    cases: tuple[FaultCase, ...]
    criteria: HoldCriteria
    vehicle: str = "ke-hil"
    duration_s: float = 25.0

    def __call__(self, gains: KeGains) -> float:
        runs = (fly_case(gains, c, vehicle=self.vehicle, duration_s=self.duration_s, criteria=self.criteria) for c in self.cases)
        share, severity = mean_severity(runs, self.criteria)
        return share + 0.1 * severity


@dataclass(frozen=True)
class HoldTuningResult:
    """:func:`tune_hold`'s answer: the tuned gains, what was searched (``bounds``), how many
    candidates, the seed and the seconds it took, and the baseline (``"paper"``) and tuned
    gains flown through the fault set side by side (``comparison``).

    Examples:

        >>> from rotorfault.studies import FaultCase, tune_hold
        >>> result = tune_hold([FaultCase(rotors=(1,), efficiency=0.5, time_s=0.5)], duration_s=1.0, maxiter=1, popsize=1,
        ...                    bounds={"k_p": (0.5, 2.0)})
        >>> list(result.bounds), result.seed
        (['k_p'], 0)
    """

    baseline: KeGains
    tuned: KeGains
    bounds: dict[str, tuple[float, float]]
    candidates: int
    seed: int
    seconds: float
    cost: HoldCost
    comparison: HoldComparison

    def gain_table(self) -> str:
        lines = [f"{'gain':<18} {'paper':>10} {'tuned':>10}   bounds"]
        for name, (lo, hi) in self.bounds.items():
            if name in WEIGHT_NAMES:
                base, new = self.baseline.weights[WEIGHT_NAMES[name][0]], self.tuned.weights[WEIGHT_NAMES[name][0]]
            else:
                base, new = getattr(self.baseline, name), getattr(self.tuned, name)
            lines.append(f"{name:<18} {base:>10.4g} {new:>10.4g}   [{lo:g}, {hi:g}]{' (log scale)' if name in LOG_SCALED else ''}")
        return "\n".join(lines)

    def table(self) -> str:
        return (f"{self.gain_table()}\n\nobjective: paper {self.cost(self.baseline):.4f}, tuned {self.cost(self.tuned):.4f} "
                f"({self.candidates} candidates, seed {self.seed}, {self.seconds:.0f} s)\n\n{self.comparison.table()}")

    def preset_toml(self, name: str, description: str, source: str) -> str:
        """The tuned gains as a controller preset file (``presets/ftc/<name>.toml``) on the
        vehicle the search flew (its ``[vehicle]`` values copied)."""
        from ..control.ke import preset

        vehicle = preset(self.cost.vehicle)
        g = self.tuned
        lines = [f'name = "{name}"', f'description = "{description}"', f'source = "{source}"', f'airframe = "{vehicle.airframe_name}"', "", "[gains]"]
        for field_name in KeGains.FIELDS:
            value = getattr(g, field_name)
            if field_name == "weights":
                lines += ["# W = diag(w_f, w_tau_p, w_tau_q, w_tau_r)", "weights = [" + ", ".join(f"{w:.6g}" for w in value) + "]"]
            else:
                lines.append(f"{field_name} = {float(value):.6g}")
        lines += [
            "", "[vehicle]", f"rotor_time_constant_s = {vehicle.rotor_time_constant_s!r}",
            f"rotational_drag_n_m_s = {vehicle.rotational_drag_n_m_s!r}", f"linear_drag_n_s_m = {vehicle.linear_drag_n_s_m!r}", "",
        ]
        return "\n".join(lines)


def tune_hold(
    cases: Sequence[FaultCase] | None = None,
    *,
    baseline: KeGains | None = None,
    x0: KeGains | None = None,
    bounds: Mapping[str, tuple[float, float]] | None = None,
    criteria: HoldCriteria | None = None,
    vehicle: str = "ke-hil",
    duration_s: float = 25.0,
    maxiter: int = 12,
    popsize: int = 4,
    seed: int = 0,
    backend: Backend = "local",
    dask: Any = None,
    progress: bool | None = None,
) -> HoldTuningResult:
    """Ke's gains tuned to hold through partial and total faults: differential evolution (seeded
    by ``seed``) minimises :class:`HoldCost` over ``cases`` (default
    :func:`~rotorfault.studies.hold.fault_set`: each rotor total and at 20, 40, 60, 80 %), each
    flown from a hover 10 m up on controller preset ``vehicle``'s vehicle for ``duration_s`` and
    judged by ``criteria`` (default: the whole flight after the fault within 2 m altitude and 5 m
    horizontal, never lost). ``bounds`` (default :data:`ROBUST_GAINS`) names the searched gains;
    the others stay ``baseline``'s (default the preset's: Table IV). The first population holds
    ``x0`` (default ``baseline``), so the tuned gains score no worse than it. ``backend="dask"``
    evaluates each generation's candidates on a ``dask.distributed`` cluster (``dask``: a Client,
    an address or ``"local:N"``), ``"local"`` on two threads; both give the same gains.

    Examples:

        >>> from rotorfault.studies import FaultCase, tune_hold
        >>> result = tune_hold([FaultCase(rotors=(1,), efficiency=0.5, time_s=0.5)], duration_s=1.0, maxiter=1, popsize=1,
        ...                    bounds={"k_p": (0.5, 2.0)})
        >>> result.candidates, type(result.tuned).__name__
        (10, 'KeGains')
    """
    import time

    from ..control.ke import preset

    chosen = fault_set() if cases is None else tuple(cases)
    if not chosen or not all(isinstance(c, FaultCase) for c in chosen):
        raise TypeError("cases: expected a non-empty sequence of rotorfault.studies.hold.FaultCase")
    base = preset(vehicle).gains if baseline is None else baseline
    if not isinstance(base, KeGains) or (x0 is not None and not isinstance(x0, KeGains)):
        raise TypeError("baseline, x0: expected rotorfault.control.ke.KeGains")
    if backend not in ("local", "dask"):
        raise ValueError(f"backend: must be 'local' or 'dask', got {backend!r}")
    if backend == "dask" and dask is None:
        raise ValueError("dask: backend='dask' needs a distributed.Client, an address or 'local:N'")
    space = _space(ROBUST_GAINS if bounds is None else bounds)
    crit = HoldCriteria() if criteria is None else criteria
    if not isinstance(crit, HoldCriteria):
        raise TypeError(f"criteria: expected HoldCriteria, got {type(crit).__name__}")
    duration_s = real("duration_s", duration_s)
    if not (math.isfinite(duration_s) and duration_s > 0):
        raise ValueError(f"duration_s: must be finite and > 0, got {duration_s}")
    for case in chosen:  # a bad duration is refused before any search
        if not case.last_fault_s + crit.settle_s < duration_s:
            raise ValueError(f"duration_s: {duration_s:g} s ends before the judging of {case.label} starts")
    # The simulator's own run settings, built once here: a duration past its step limit is refused
    # by name now, not from inside the search's worker threads (where scipy hid it; long hostile run).
    preset(vehicle).simulator()._config(duration_s)
    cost = HoldCost(chosen, crit, vehicle, float(duration_s))
    description = f"hold tuning: {{total}} candidates x {len(chosen)} faults"
    started = time.perf_counter()
    if backend == "local":
        from concurrent.futures import ThreadPoolExecutor

        with ThreadPoolExecutor(max_workers=2) as pool:
            tuned, candidates = _search(
                cost, base, space, maxiter=maxiter, popsize=popsize, seed=seed, progress=progress, description=description, x0=x0,
                mapper=lambda f, xs: list(pool.map(f, xs)),
            )
    else:
        with dask_client(dask) as client:
            tuned, candidates = _search(
                cost, base, space, maxiter=maxiter, popsize=popsize, seed=seed, progress=progress, description=description, x0=x0,
                mapper=lambda f, xs: list(client.gather(client.map(f, xs, pure=False))),  # type: ignore[no-untyped-call]
            )
    seconds = time.perf_counter() - started
    comparison = compare_holds({"paper": base, "tuned": tuned}, chosen, vehicle=vehicle, duration_s=duration_s, criteria=crit)
    return HoldTuningResult(base, tuned, space, candidates, seed, seconds, cost, comparison)


__all__ = [
    "LOG_SCALED",
    "ROBUST_GAINS",
    "TUNED_GAINS",
    "WEIGHT_NAMES",
    "HoldCost",
    "HoldTuningResult",
    "TuningResult",
    "tune",
    "tune_hold",
    "tuning_campaign",
]

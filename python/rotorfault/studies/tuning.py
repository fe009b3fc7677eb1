"""Robust tuning of Ke's gains: a search (scipy's differential evolution) over the gains that
minimises the worst-case excursion of a campaign's runs, lost runs costing most, every candidate
flown on the same runs (common random numbers), then checked on a fresh campaign."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from .._util.convert import count
from .._util.progress import chunks
from ..control.ke import KeGains
from ..flight.outcomes import FLYING
from .campaign import Campaign, _pair, run_chunk

#: Ke gains tuned by default, with their search bounds (Table IV's values lie inside).
TUNED_GAINS: dict[str, tuple[float, float]] = {
    "k_p": (0.1, 2.0),
    "k_v": (0.05, 2.0),
    "accel_limit_m_s2": (0.1, 5.0),
    "k_n3": (1.0, 10.0),
    "k_omega": (5.0, 30.0),
}


@dataclass(frozen=True)
class TuningResult:
    """Table IV (the campaign's own gains) against the tuned gains, each scored on the tuning
    campaign and on a fresh validation campaign: worst altitude loss and horizontal excursion
    over the runs, and how many were lost."""

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
    flying = np.isin(columns["outcome"], FLYING)
    return {
        "lost": float((~flying).sum()),
        "max_altitude_loss_m": float(np.max(columns["max_altitude_loss_m"])),
        "max_horizontal_error_m": float(np.max(columns["max_horizontal_error_m"])),
    }


def _objective(score: dict[str, float], runs: int) -> float:
    """Worst-case excursion against the goal (2 m altitude, 10 m horizontal), a lost run costing
    more than any excursion: minimised."""
    excursion = max(score["max_altitude_loss_m"] / 2.0, score["max_horizontal_error_m"] / 10.0)
    return 100.0 * score["lost"] / runs + min(excursion, 50.0)


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
    fresh campaign (``validation_seed``, default ``seed + 1``) they were not tuned on."""
    from scipy.optimize import differential_evolution  # type: ignore[import-untyped]

    if not isinstance(campaign, Campaign):
        raise TypeError(f"campaign: expected rotorfault.studies.Campaign, got {type(campaign).__name__}")
    if campaign.controller == "lqr":
        raise ValueError("campaign.controller: tuning searches Ke's gains; use ke-hil or ke-experiment")
    for name, value in (("maxiter", maxiter), ("popsize", popsize)):
        if count(name, value) < 1:
            raise ValueError(f"{name}: must be >= 1, got {value}")
    if bounds is not None and not isinstance(bounds, Mapping):
        raise TypeError(f"bounds: expected a mapping of Ke gain names to (low, high), got {type(bounds).__name__}")
    space = dict(TUNED_GAINS if bounds is None else bounds)
    if not space:
        raise ValueError("bounds: expected at least one Ke gain to tune")
    known = set(KeGains.FIELDS)
    for name, pair in space.items():
        if name not in known:
            raise ValueError(f"bounds.{name}: unknown Ke gain")
        _pair(f"bounds.{name}", pair, low=0.0)
    baseline = campaign.gains or campaign.vehicle().gains
    names = list(space)

    def gains_of(x: Sequence[float] | np.ndarray[Any, Any]) -> KeGains:
        values: dict[str, Any] = {n: float(v) for n, v in zip(names, x)}
        return baseline.replace(**values)

    def fly(c: Campaign) -> dict[str, np.ndarray[Any, Any]]:
        parts = [run_chunk(c, k) for k in range(c.chunk_count())]
        return {k: np.concatenate([p[k] for p in parts]) for k in parts[0]}

    evaluations = [0]
    total = (maxiter + 1) * popsize * len(names)
    bar = chunks(total, 1, description=f"tuning: {total} candidates x {campaign.runs} runs", show=progress)

    def cost(x: np.ndarray[Any, Any]) -> float:
        evaluations[0] += 1
        next(bar, None)
        try:
            c = replace(campaign, gains=gains_of(x))
        except ValueError:
            return 1e6  # gains the controller refuses (e.g. k_omega <= 0.5)
        return _objective(_score(fly(c)), campaign.runs)

    result = differential_evolution(
        cost, [space[n] for n in names], x0=[getattr(baseline, n) for n in names], maxiter=maxiter, popsize=popsize,
        seed=campaign.seed, polish=False, tol=0.0, updating="deferred",
    )
    for _ in bar:
        pass
    tuned = gains_of(result.x)
    fresh = replace(campaign, seed=campaign.seed + 1 if validation_seed is None else validation_seed)
    scores = {
        "tuning, Table IV": _score(fly(replace(campaign, gains=baseline))),
        "tuning, tuned": _score(fly(replace(campaign, gains=tuned))),
        "validation, Table IV": _score(fly(replace(fresh, gains=baseline))),
        "validation, tuned": _score(fly(replace(fresh, gains=tuned))),
    }
    return TuningResult(baseline, tuned, scores, evaluations[0], campaign.runs)


#: The tuning campaign of issue 13: every single failure and every stabilisable double failure
#: of Ke's quadcopter (adjacent side pairs and opposite pairs, both orders) from hover.
def tuning_campaign(*, runs: int = 200, seed: int = 0, duration_s: float = 25.0) -> Campaign:
    pairs = ((1, 2), (2, 1), (3, 4), (4, 3), (1, 3), (3, 1), (2, 4), (4, 2))
    campaign = Campaign(
        runs=runs, seed=seed, duration_s=duration_s, failures=((1,), (2,), (3,), (4,), *pairs), fault_time_s=(1.0, 4.0), gap_s=(4.0, 8.0),
    )
    return replace(campaign, chunk_size=campaign.runs)  # runs checked by the Campaign first


__all__ = ["TUNED_GAINS", "TuningResult", "tune", "tuning_campaign"]

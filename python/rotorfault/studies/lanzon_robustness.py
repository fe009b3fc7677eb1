"""Robustness of a controller flying Lanzon's quadrotor with rotor 2 dead (Lanzon, Freddi and
Longhi, JGCD 2014, Section IV: the Monte Carlo study): ``runs`` perturbed vehicles (mass,
``I_xx = I_yy``, ``I_zz``, ``k_r``, ``I_R`` each scaled by a factor drawn uniformly from
``[1 - spread, 1 + spread]``), each flown from a start to a setpoint with its own sensor noise,
through the study engine (:func:`rotorfault.studies.engine.run_chunks`), each judged by the
windowed verdicts of :func:`rotorfault.flight.outcomes.flight_metrics`. The paper's scenario,
vehicle and design case are chosen by :func:`rotorfault.papers.lanzon.monte_carlo`."""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any, Literal

import numpy as np

from .._util.convert import FloatArray, count, real
from .._util.tables import Column, Tabular
from ..control.ke import UniformPassiveFtc
from ..control.lanzon import DesignCase, LanzonController, LanzonDesign, LanzonVehicle
from ..flight import Noise, RotorFault, State, simulate_batch
from ..flight.outcomes import flight_metrics
from ..flight.scenarios import FlightScenario
from .engine import run_chunks
from .storage import pyarrow_module

MonteCarloController = Literal["lanzon", "ke"]


@dataclass(frozen=True)
class MonteCarloResult(Tabular):
    """A Monte Carlo batch: ``runs`` perturbed vehicles (mass, ``I_xx = I_yy``, ``I_zz``,
    ``k_r``, ``I_R`` each scaled by a factor drawn uniformly from ``[1 - spread, 1 + spread]``)
    with sensor noise at ``snr_db``, flown from Scenario B's start to its setpoint for
    ``duration_s``. ``outcomes`` holds Ke's windowed verdict per run, ``final_error_m`` the
    distance from the setpoint at the end (NaN: lost), ``factors`` the draws (runs x 5).
    ``to_arrow()`` / ``to_pandas()``: one row per run (its draws, outcome and final error)."""

    controller: str
    runs: int
    spread: float
    snr_db: float | None
    duration_s: float
    inertia_zz_kg_m2: float
    outcomes: tuple[str, ...]
    final_error_m: FloatArray
    factors: FloatArray

    @property
    def held_fraction(self) -> float:
        """The fraction of runs that reach and hold the setpoint (``holds-position``)."""
        return sum(o == "holds-position" for o in self.outcomes) / self.runs

    @property
    def lost_fraction(self) -> float:
        return sum(o not in ("holds-position", "off-station", "circling") for o in self.outcomes) / self.runs

    @property
    def worst_final_error_m(self) -> float:
        """The largest final distance from the setpoint among the runs not lost (inf: all lost)."""
        finite = self.final_error_m[np.isfinite(self.final_error_m)]
        return float(np.max(finite)) if finite.size else math.inf

    @property
    def median_final_error_m(self) -> float:
        finite = self.final_error_m[np.isfinite(self.final_error_m)]
        return float(np.median(finite)) if finite.size else math.inf

    def _table_columns(self) -> list[Column]:
        draws = ("mass_scale", "inertia_xx_scale", "inertia_zz_scale", "rotational_drag_scale", "rotor_inertia_scale")
        columns: list[Column] = [("run", "int64", np.arange(self.runs, dtype=np.int64))]
        columns += [(name, "float64", self.factors[:, k]) for k, name in enumerate(draws)]
        return columns + [("outcome", "string", list(self.outcomes)), ("final_error_m", "float64", self.final_error_m)]

    def _table_title(self) -> str:
        return f"Monte Carlo: {self.runs} runs of {self.controller}, spread {self.spread:g}"

    def _table_metadata(self) -> dict[str, Any]:
        return {"kind": "lanzon-monte-carlo", "controller": self.controller, "spread": self.spread, "snr_db": self.snr_db,
                "duration_s": self.duration_s, "inertia_zz_kg_m2": self.inertia_zz_kg_m2}

    def counts(self) -> dict[str, int]:
        out: dict[str, int] = {}
        for o in self.outcomes:
            out[o] = out.get(o, 0) + 1
        return dict(sorted(out.items(), key=lambda kv: -kv[1]))


def robustness(
    controller: MonteCarloController,
    *,
    runs: int,
    spread: float,
    snr_db: float | None,
    duration_s: float,
    nominal: LanzonVehicle,
    case: DesignCase,
    start: State,
    judged: FlightScenario,
    seed: int = 0,
    progress: bool | None = None,
) -> MonteCarloResult:
    """Robustness of ``controller`` with rotor 2 dead: ``"lanzon"`` (design ``case``, designed
    once on ``nominal``) or ``"ke"`` (Ke's :class:`~rotorfault.UniformPassiveFtc`, ``ke-hil``
    gains, on the same vehicle with the same limits), from ``start`` to the setpoint of
    ``judged`` (the scenario its windowed verdict is judged against) for ``duration_s``. Each
    run's vehicle differs, so each goes to :func:`~rotorfault.simulate_batch` with its own
    simulator; the runs go through the study engine (the local backend: two chunks at a time on
    threads, the core releases the GIL); run ``i`` uses noise seed ``seed + i``."""
    if controller not in ("lanzon", "ke"):
        raise ValueError(f"controller: expected 'lanzon' or 'ke', got {controller!r}")
    n = count("runs", runs)
    if n < 1:
        raise ValueError(f"runs: must be >= 1, got {n}")
    spread = real("spread", spread)
    if not 0 <= spread < 1:
        raise ValueError(f"spread: must lie in [0, 1), got {spread}")
    seed = count("seed", seed)
    duration = real("duration_s", duration_s)
    # The draws: one generator for the whole batch, row i for run i (as since the study was
    # written; the campaigns' per-run generators would draw other numbers).
    factors = np.random.default_rng(seed).uniform(1 - spread, 1 + spread, size=(n, 5))
    task = _MonteCarloTask(controller, nominal, case, case.design(nominal) if controller == "lanzon" else None, factors, snr_db,
                           seed, duration, start, judged)
    # Two runs at a time (the core releases the GIL): two chunks in flight, each at most half the runs.
    chunk_rows = max(1, min(max(8, n // 50), -(-n // 2)))
    result = run_chunks(
        task, total_rows=n, chunk_rows=chunk_rows, schema=_monte_carlo_schema(), kind="lanzon-monte-carlo",
        arguments={"controller": controller, "runs": n, "spread": spread, "snr_db": None if snr_db is None else real("snr_db", snr_db),
                   "duration_s": duration,
                   "inertia_zz_kg_m2": float(nominal.inertia_zz_kg_m2), "case": case.label, "seed": seed},
        progress=progress, description=f"{n:,} {controller} runs",
    )
    assert result.table is not None  # gathered in memory (no ``out``)
    columns = result.table.to_pydict()
    return MonteCarloResult(controller, n, spread, snr_db, duration, float(nominal.inertia_zz_kg_m2),
                            tuple(columns["outcome"]), np.array(columns["final_error_m"], dtype=np.float64), factors)


def _monte_carlo_schema() -> Any:
    """The rows of one Monte Carlo chunk: the run, Ke's windowed verdict code, the final distance
    from the setpoint (m; NaN: lost)."""
    pa = pyarrow_module()

    return pa.schema([pa.field("run", pa.int64()), pa.field("outcome", pa.string()), pa.field("final_error_m", pa.float64())])


@dataclass(frozen=True)
class _MonteCarloTask:
    """The runs of one chunk of :func:`monte_carlo` (the study engine's task): run ``i`` flies the
    nominal vehicle scaled by ``factors[i]`` (mass, ``I_xx = I_yy``, ``I_zz``, ``k_r``, ``I_R``)
    with noise seed ``seed + i``, rotor 2 dead, from ``start`` to the setpoint of ``judged``."""

    controller: str
    nominal: LanzonVehicle
    case: DesignCase
    designed: LanzonDesign | None
    factors: FloatArray
    snr_db: float | None
    seed: int
    duration_s: float
    start: State
    judged: FlightScenario

    def __call__(self, spec: Any) -> Any:
        pa = pyarrow_module()

        runs = [self.run(i) for i in range(spec.start, spec.stop)]
        return pa.Table.from_arrays(
            [pa.array(range(spec.start, spec.stop), pa.int64()), pa.array([o for o, _ in runs], pa.string()),
             pa.array([e for _, e in runs], pa.float64())], schema=_monte_carlo_schema())

    def run(self, i: int) -> tuple[str, float]:
        """Run ``i``: Ke's windowed verdict code and the final distance from the setpoint (NaN: lost)."""
        setpoint = self.judged.setpoints[-1][1]  # where the run must end (its last setpoint)
        nominal, f = self.nominal, self.factors[i]
        v = nominal.replace(mass_kg=nominal.mass_kg * f[0], inertia_xx_kg_m2=nominal.inertia_xx_kg_m2 * f[1],
                            inertia_zz_kg_m2=nominal.inertia_zz_kg_m2 * f[2],
                            rotational_drag_n_m_s=nominal.rotational_drag_n_m_s * f[3],
                            rotor_inertia_kg_m2=nominal.rotor_inertia_kg_m2 * f[4])
        noise = None if self.snr_db is None else Noise(snr_db=self.snr_db, seed=self.seed + i)
        sim = v.simulator(limits=self.case.limits if self.controller == "lanzon" else True, noise=noise)
        ctrl: Any
        if self.controller == "lanzon":
            assert self.designed is not None
            ctrl = LanzonController(self.designed, position=setpoint, outer_loop=self.case.outer_loop)
        else:
            ctrl = UniformPassiveFtc(sim.airframe, gains="ke-hil", position=setpoint)
        batch = simulate_batch(sim, [self.start], self.duration_s, controllers=[ctrl], faults=[[RotorFault(2, 0.0)]],
                               record_every=20)
        tr = batch.trajectories[0]
        m = flight_metrics(tr, replace(self.judged, duration_s=self.duration_s))
        err = math.nan if tr.diverged else float(np.linalg.norm(tr.position[-1] - np.asarray(setpoint)))
        return m.outcome, err


__all__ = ["MonteCarloController", "MonteCarloResult", "robustness"]

"""Sampling: what run ``i`` of a campaign flies. Each run draws its own values from a generator
seeded by ``(seed, i)``, so any run can be re-flown alone and a campaign cut into chunks gives
the same rows however it is cut.

Decisions (README, "Fault campaigns"):
- a thrust-coefficient error scales each rotor's thrust by a factor in ``[1 - thrust_rel, 1]``
  (rotor efficiency, which cannot exceed 1: a rotor stronger than its model is not modelled); a
  failure to efficiency ``e`` then leaves ``factor * e``;
- a ramped failure is a staircase of :data:`RAMP_STEPS` equal steps over ``ramp_s`` (exact fault
  times in the core; no continuous ramp);
- a gust is a ``1 - cos`` pulse of ``gust_duration_s`` through the simulator's wind profile,
  sampled at :data:`GUST_POINTS` points and interpolated linearly.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..analysis.airframe import Airframe
from .._util.deprecation import renamed_attribute, warn
from ..flight import Drag, FixedPitchActuator, Noise, RotorFault, Sensing

#: Steps of a ramped failure's staircase.
RAMP_STEPS = 10
#: Points of a gust's wind profile.
GUST_POINTS = 9

#: One failure pattern: rotors (1-based) failing one after another, in this order.
FailureSet = tuple[int, ...]


@functools.lru_cache(maxsize=8)
def _airframe(name: str) -> Airframe:
    return Airframe.preset(name)


@functools.lru_cache(maxsize=8)
def rotor_count(airframe_name: str) -> int:
    """Rotors of a preset airframe (cached: every draw asks)."""
    return Airframe.preset(airframe_name).rotor_count


@dataclass(frozen=True)
class RunDraw:
    """One run's draws, the one record of every campaign: what run ``index`` flies (:func:`draw`
    for a :class:`~rotorfault.studies.campaign.Campaign`,
    :meth:`~rotorfault.studies.deciding.DecidingCampaign.draw` for the deciding campaign).

    ``failed``: the rotors that fail (numbered from 1), in order, each at its time in
    ``fault_times_s`` (s) to ``efficiency`` times its thrust factor (``thrust_scale``, one per
    rotor), at once or over ``ramp_s`` (s); the wind (m/s, north and east), a ``1 - cos`` gust of
    peak ``gust_m_s`` from ``gust_start_s`` (s); the vehicle's factors (mass, inertia, drag
    torque, rotor lag); ``seed`` the campaign's seed, ``duration_s`` the run's length (s) and
    ``noise_seed`` the run's sensor-noise seed (None: the campaign draws no noise).

    Examples:

        >>> from rotorfault.studies import Campaign
        >>> d = Campaign(runs=4, seed=1).sample(2)
        >>> d.index, len(d.failed) == len(d.fault_times_s), d.duration_s
        (2, True, 30.0)
    """

    index: int
    seed: int
    failed: FailureSet
    fault_times_s: tuple[float, ...]
    efficiency: float
    ramp_s: float
    wind_m_s: tuple[float, float]
    gust_m_s: tuple[float, float]
    gust_start_s: float
    mass_scale: float
    inertia_scale: tuple[float, float, float]
    thrust_scale: tuple[float, ...]
    drag_torque_scale: float
    lag_scale: float
    duration_s: float
    noise_seed: int | None = None

    @property
    def fault_time_s(self) -> float:
        """The first failure's time, s."""
        return self.fault_times_s[0]

    pattern = renamed_attribute("pattern", "failed")

    def __setstate__(self, state: dict[str, Any]) -> None:
        # A RunSpec pickled before the one draw record had no duration (the campaign's was not
        # kept): NaN says so instead of an object whose repr and == raise.
        state = {"duration_s": math.nan, "noise_seed": None, **state}
        object.__setattr__(self, "__dict__", state)

    def faults(self, campaign: Any = None) -> list[RotorFault]:
        """The fault schedule: each failed rotor drops from its thrust factor to ``factor *
        efficiency`` at once, or over ``ramp_s`` in :data:`RAMP_STEPS` steps (``campaign`` is not
        needed: the draws hold everything)."""
        out = []
        for rotor, t in zip(self.failed, self.fault_times_s):
            start = self.thrust_scale[rotor - 1]
            target = start * self.efficiency
            if self.ramp_s <= 0:
                out.append(RotorFault(rotor, t, target))
                continue
            for k in range(RAMP_STEPS):
                level = start + (target - start) * (k + 1) / RAMP_STEPS
                out.append(RotorFault(rotor, t + self.ramp_s * k / RAMP_STEPS, level))
        return out

    def told_faults(self) -> list[RotorFault]:
        """What a controller told of the failure knows: the rotors, the times and the nominal
        efficiency (not the run's thrust-coefficient error)."""
        return [RotorFault(r, t, self.efficiency) for r, t in zip(self.failed, self.fault_times_s)]

    def vehicle_parts(self, vehicle: Any) -> tuple[Airframe, FixedPitchActuator, Drag]:
        """``vehicle`` (its ``airframe`` and nominal lag and drags) with this run's factors."""
        return scaled_parts(vehicle.airframe, vehicle, self)

    def failed_vehicle(self, vehicle: Any) -> tuple[Airframe, FixedPitchActuator, Drag]:
        """The run's vehicle after its failure (what it must survive): its perturbed parts with
        each failed rotor at its thrust factor times the drawn efficiency (:meth:`faults`)."""
        airframe, actuator, drag = self.vehicle_parts(vehicle)
        efficiency = np.array(self.thrust_scale, dtype=np.float64)
        for f in self.faults():
            efficiency[f.rotor - 1] = f.efficiency
        return airframe.with_efficiency(efficiency), actuator, drag


def __getattr__(name: str) -> Any:
    if name == "RunSpec":  # the campaign's old name of the one draw record
        warn("rotorfault.studies.sampling.RunSpec", "rotorfault.studies.sampling.RunDraw")
        return RunDraw
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def draw(campaign: Any, index: int, rotors: int) -> RunDraw:
    """Run ``index``'s draws from ``campaign`` (a :class:`~rotorfault.studies.campaign.Campaign`)
    for a vehicle of ``rotors`` rotors: the same whatever else is drawn (one generator per
    run, seeded by ``(seed, index)``)."""
    if not 0 <= index < campaign.runs:
        raise ValueError(f"index: must lie in [0, {campaign.runs}), got {index}")
    rng = np.random.default_rng((campaign.seed, index))

    def u(pair: tuple[float, float]) -> float:
        return float(rng.uniform(pair[0], pair[1]))

    pattern = campaign.failures[int(rng.integers(len(campaign.failures)))]
    times = []
    t = u(campaign.fault_time_s)
    for k in range(len(pattern)):
        if k:
            t += u(campaign.gap_s)
        times.append(t)
    efficiency = u(campaign.efficiency)
    ramp = u(campaign.ramp_s)
    wind_speed, wind_dir = u(campaign.wind_m_s), float(rng.uniform(0, 2 * math.pi))
    gust_peak, gust_dir = u(campaign.gust_m_s), float(rng.uniform(0, 2 * math.pi))
    gust_start = float(rng.uniform(0, max(campaign.duration_s - campaign.gust_duration_s, 0.0)))
    m = rotors

    def scale(rel: float) -> float:
        return float(rng.uniform(1 - rel, 1 + rel))

    return RunDraw(
        index=index,
        seed=campaign.seed,
        failed=pattern,
        fault_times_s=tuple(times),
        efficiency=efficiency,
        ramp_s=ramp,
        wind_m_s=(wind_speed * math.cos(wind_dir), wind_speed * math.sin(wind_dir)),
        gust_m_s=(gust_peak * math.cos(gust_dir), gust_peak * math.sin(gust_dir)),
        gust_start_s=gust_start,
        mass_scale=scale(campaign.mass_rel),
        inertia_scale=(scale(campaign.inertia_rel), scale(campaign.inertia_rel), scale(campaign.inertia_rel)),
        thrust_scale=tuple(float(v) for v in rng.uniform(1 - campaign.thrust_rel, 1.0, size=m)),
        drag_torque_scale=scale(campaign.drag_torque_rel),
        lag_scale=scale(campaign.lag_rel),
        duration_s=float(campaign.duration_s),
        noise_seed=int(rng.integers(2**63)),
    )


def perturbed_vehicle(vehicle: Any, spec: RunDraw) -> tuple[Airframe, FixedPitchActuator, Drag]:
    """The vehicle run ``spec`` flies: ``vehicle`` (an :class:`~rotorfault.control.ke.FtcPreset`)
    with the run's mass, inertia, drag-torque, thrust and lag factors."""
    return scaled_parts(_airframe(vehicle.airframe_name), vehicle, spec)


def scaled_parts(a: Airframe, nominal: Any, draws: Any) -> tuple[Airframe, FixedPitchActuator, Drag]:
    """Airframe ``a`` with a run's factors (``draws``: ``index``, ``mass_scale``, ``inertia_scale``,
    ``drag_torque_scale``, ``thrust_scale``, ``lag_scale``), the actuator with the scaled lag of
    ``nominal.rotor_time_constant_s`` and ``nominal``'s drags: what every campaign's run flies."""
    airframe = Airframe(
        a.arm_angle_rad,
        a.arm_length_m,
        a.spin_sign,
        a.max_thrust_n,
        a.mass_kg * draws.mass_scale,
        a.inertia_kg_m2 * np.array(draws.inertia_scale),
        a.drag_torque_ratio_m * draws.drag_torque_scale,
        min_thrust_n=a.min_thrust_n,
        efficiency=np.array(draws.thrust_scale),
        gravity_m_s2=a.gravity_m_s2,
        name=f"{a.name} (run {draws.index})",
    )
    actuator = FixedPitchActuator(time_constant_s=nominal.rotor_time_constant_s * draws.lag_scale)
    drag = Drag(rotational_n_m_s=nominal.rotational_drag_n_m_s, linear_n_s_m=nominal.linear_drag_n_s_m)
    return airframe, actuator, drag


def gust_profile(spec: RunDraw, gust_duration_s: float) -> list[tuple[float, tuple[float, float, float]]]:
    """The run's ``1 - cos`` gust as a wind profile of :data:`GUST_POINTS` points (none without a gust)."""
    if spec.gust_m_s == (0.0, 0.0):
        return []
    points = []
    for k in range(GUST_POINTS):
        phase = k / (GUST_POINTS - 1)
        shape = 0.5 * (1 - math.cos(2 * math.pi * phase))
        points.append((spec.gust_start_s + phase * gust_duration_s, (spec.gust_m_s[0] * shape, spec.gust_m_s[1] * shape, 0.0)))
    return points


def sensor_noise(noise_std: tuple[float, float, float, float] | None, spec: RunDraw) -> Noise | None:
    """The run's sensor noise (its own seed), or None without ``noise_std``."""
    return None if noise_std is None else Noise(std=noise_std, seed=_noise_seed(spec))


def run_sensing(sensing: Sensing | None, spec: RunDraw) -> Sensing | None:
    """The run's sensing: the campaign's with its seed plus the run's drawn seed (mod 2**64), or
    None without sensing."""
    return None if sensing is None else seeded_sensing(sensing, _noise_seed(spec))


def seeded_sensing(sensing: Sensing, drawn_seed: int) -> Sensing:
    """``sensing`` with its seed plus a run's drawn seed, mod 2**64 (the one rule of every study)."""
    return sensing.replace(seed=(sensing.seed + drawn_seed) % 2**64)


def _noise_seed(spec: RunDraw) -> int:
    if spec.noise_seed is None:
        raise ValueError(f"noise_seed: run {spec.index} drew no sensor-noise seed (its campaign flies without noise)")
    return spec.noise_seed


__all__ = ["GUST_POINTS", "RAMP_STEPS", "FailureSet", "RunDraw", "draw", "gust_profile", "perturbed_vehicle",
           "rotor_count", "run_sensing", "scaled_parts", "seeded_sensing", "sensor_noise"]

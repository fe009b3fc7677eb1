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
class RunSpec:
    """One run's draws (:func:`draw`, :meth:`Campaign.sample <rotorfault.studies.campaign.Campaign.sample>`)."""

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
    noise_seed: int

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


def draw(campaign: Any, index: int, rotors: int) -> RunSpec:
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

    return RunSpec(
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
        noise_seed=int(rng.integers(2**63)),
    )


def perturbed_vehicle(vehicle: Any, spec: RunSpec) -> tuple[Airframe, FixedPitchActuator, Drag]:
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


def gust_profile(spec: RunSpec, gust_duration_s: float) -> list[tuple[float, tuple[float, float, float]]]:
    """The run's ``1 - cos`` gust as a wind profile of :data:`GUST_POINTS` points (none without a gust)."""
    if spec.gust_m_s == (0.0, 0.0):
        return []
    points = []
    for k in range(GUST_POINTS):
        phase = k / (GUST_POINTS - 1)
        shape = 0.5 * (1 - math.cos(2 * math.pi * phase))
        points.append((spec.gust_start_s + phase * gust_duration_s, (spec.gust_m_s[0] * shape, spec.gust_m_s[1] * shape, 0.0)))
    return points


def sensor_noise(noise_std: tuple[float, float, float, float] | None, spec: RunSpec) -> Noise | None:
    """The run's sensor noise (its own seed), or None without ``noise_std``."""
    return None if noise_std is None else Noise(std=noise_std, seed=spec.noise_seed)


def run_sensing(sensing: Sensing | None, spec: RunSpec) -> Sensing | None:
    """The run's sensing: the campaign's with its seed plus the run's drawn seed (mod 2**64), or
    None without sensing."""
    return None if sensing is None else sensing.replace(seed=(sensing.seed + spec.noise_seed) % 2**64)


__all__ = ["GUST_POINTS", "RAMP_STEPS", "FailureSet", "RunSpec", "draw", "gust_profile", "perturbed_vehicle",
           "rotor_count", "run_sensing", "scaled_parts", "sensor_noise"]

"""What a flight is flown with besides the airframe: the rotor actuators (fixed or variable
pitch), aerodynamic drag, the papers' sensor noise and the sensors with the estimator
(:data:`Sensing`). Defaults come from the core's ``Default`` (read once)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from .. import _rfcore
from .._util.convert import count, float_array, real
from .._util.deprecation import dataclass_compat

#: Aerodynamic damping and rotor inertia (the papers give none; all default to 0): the core's
#: class, used directly (keyword-only; defaults from the core's ``Default``; types checked by the
#: bindings, values once, by the core; frozen, ``replace(**changes)``, ``FIELDS``):
#: ``linear_n_s_m`` (``k_t``: force ``-k_t (v - wind)``, N s/m, Lanzon's Stokes drag),
#: ``quadratic_n_s2_m2`` (force ``-c |v - wind| (v - wind)``), ``rotational_n_m_s`` (``k_r``: torque
#: ``-k_r omega``, sets a spinning vehicle's yaw rate), ``rotor_inertia_kg_m2`` (``I_R``: rotor
#: inertia about its axis, the gyroscopic moment of Lanzon eq. (5)).
Drag = _rfcore.Drag
dataclass_compat(Drag)


#: What the controller flies on when it flies on sensors: the core's class, used directly
#: (keyword-only; defaults from the core's ``Sensing::default()``; values checked by the core,
#: errors naming ``sensing.<field>``; frozen, ``replace(**changes)``, ``FIELDS``, ``SUITES``,
#: ``IMUS``): ``suite`` (``"mocap"``: ICM-42688-P + OptiTrack PrimeX 13 + DShot rotor speeds;
#: ``"gnss"``: u-blox NEO-M8N + ST LIS3MDL instead of mocap; ``"rtk"``: the ZED-F9P), ``imu``
#: (``"icm-42688-p"``, ``"mpu-6000"``), ``imu_rate_hz`` (default 500, an ICM-42688-P output data
#: rate), ``position_rate_hz`` (``None``: the suite's 240 / 5 / 10 Hz), ``gyro_range_rad_s``
#: (``None``: the part's +-2000 deg/s; a what-if for spins past it) and ``seed`` (run ``i`` of a
#: batch uses ``seed + i``). The estimator (an error-state Kalman filter with latency
#: compensation, ``crates/rfcore/src/flight/estimation``) is matched to the sensors; the profiles
#: and their datasheet sources are in ``crates/rfcore/src/flight/sensors/README.md``.
Sensing = _rfcore.Sensing


def sensing_with_offset(sensing: Any, offset: int) -> Any:
    """``sensing`` with its seed moved on by ``offset`` (run ``i`` of a batch sent in chunks)."""
    if offset == 0:
        return sensing
    if sensing.seed + offset >= 2**64:
        raise ValueError("sensing.seed: must be below 2**64 for every run of the batch (seed + run index)")
    return sensing.replace(seed=sensing.seed + offset)


#: Rotors commanded in thrust (N): the core's class, used directly (keyword-only; defaults from the
#: core's ``Lag::none()``; types checked by the bindings, values once, by the core's
#: ``FixedPitch::check_parameters``, when it is made; frozen, ``replace(**changes)``, ``FIELDS``):
#: first-order lag ``time_constant_s`` (s; Ke Table III: 0.025), rate limit ``rate_limit_n_s``
#: (N/s; Lanzon: 50; ``math.inf``: none), thrust saturation from the airframe;
#: ``thrust_coefficient_n_s2`` (N s^2, ``f = k_f omega^2``) gives rotor speed for the gyroscopic
#: moment (0: not modelled). The positional form of the former dataclass still works for one
#: release, with a ``DeprecationWarning``.
FixedPitchActuator = _rfcore.FixedPitchActuator
dataclass_compat(FixedPitchActuator)


#: Variable-pitch propellers (Wang et al. eq. (3)), commanded per rotor in speed and pitch
#: (interleaved ``[omega_1, alpha_1, omega_2, ...]``): thrust ``k1 omega^2 alpha``, torque
#: ``k2 omega^2 + k3 omega^2 alpha^2 + k4 omega alpha``. The core's class, used directly
#: (keyword-only; ``k`` four coefficients, ``speed_bounds`` and ``pitch_bounds`` ``(lower, upper)``
#: required; types checked by the bindings, values once, by the core's
#: ``VariablePitch::check_parameters``, when it is made; frozen, ``replace(**changes)``,
#: ``FIELDS``). The speed and pitch channels have their own first-order lag and rate limit (a
#: motor's speed loop and a pitch servo are different hardware). Defaults (the core's
#: ``VariablePitchLags::default()``): Wang's "first-order transfer function ... cut-off frequency
#: 10 Hz" for both, ``time_constant_s = 1 / (2 pi 10)`` s, and no rate limit (the paper gives
#: none). ``speed_rate_limit_per_s`` is in speed units per second, ``pitch_rate_limit_rad_s`` in
#: rad/s, ``speed_to_rad_s`` converts the speed unit to rad/s for the gyroscopic moment (0: not
#: modelled). The positional form of the former dataclass still works for one release, with a
#: ``DeprecationWarning``.
VariablePitchActuator = _rfcore.VariablePitchActuator
dataclass_compat(VariablePitchActuator)


@dataclass(frozen=True)
class Noise:
    """Additive Gaussian sensor noise on the 12 measured state components (position, velocity,
    Euler angles, body rates), standard deviation ``10^(-snr_db / 20) |x_i| + std_i``.

    ``snr_db`` is a per-sample signal-to-noise ratio (Wang et al.'s scenarios use 15 dB; they do
    not say how signal power is measured, and per sample is the causal reading). ``std`` adds an
    absolute floor: 12 values, or 4 (position m, velocity m/s, angle rad, rate rad/s). Seeded and
    reproducible on every platform; in a batch, run ``i`` uses ``seed + i``.

    Why it lives in Python (issue 26): it is not a copy of a core type but the papers' way of
    stating noise (a signal-to-noise ratio in dB, a floor per kind of state), which
    :meth:`_core` turns into the core's one form, ``SensorNoise`` (a relative and a per-component
    absolute standard deviation), for each batch chunk's seed; the core checks that form.

    Examples:

        >>> import rotorfault as rf
        >>> sim = rf.Simulator(rf.Airframe.preset("quad-x"), noise=rf.Noise(snr_db=15.0, seed=1))
        >>> run = sim.run(rf.State(position=(0, 0, -1)), 0.1)
        >>> run.measured.shape, bool((run.measured[:, 2] != run.position[:, 2]).all())
        ((41, 12), True)
    """

    snr_db: float | None = None
    std: npt.ArrayLike | None = None
    seed: int = 0

    def _core(self, seed_offset: int = 0) -> _rfcore.SensorNoise:
        relative = 0.0
        if self.snr_db is not None:
            snr_db = real("noise.snr_db", self.snr_db)
            try:
                relative = 10.0 ** (-snr_db / 20.0)
            except OverflowError:  # the core refuses what is not finite; a float cannot hold this one
                raise ValueError(f"noise.snr_db: {snr_db} dB gives a noise scale too large for a float") from None
        if self.std is None:
            absolute = np.zeros(12)
        else:
            absolute = float_array("noise.std", self.std, 1)
            if absolute.shape == (4,):
                absolute = np.repeat(absolute, 3)
            if absolute.shape != (12,):
                raise ValueError(f"noise.std: expected 4 or 12 entries, got {absolute.shape[0]}")
        seed = count("noise.seed", self.seed)
        if seed + seed_offset >= 2**64:
            raise ValueError("noise.seed: must be below 2**64")
        return _rfcore.SensorNoise(relative_std=relative, absolute_std=[float(v) for v in absolute], seed=seed + seed_offset)


__all__ = ["Drag", "FixedPitchActuator", "Noise", "Sensing", "VariablePitchActuator", "sensing_with_offset"]

"""Can a vehicle enter its spinning relaxed hover from hover? (issue 30). A relaxed hover
(:func:`rotorfault.analysis.relaxed_hover`) is a periodic solution a linear feedback holds; it
says nothing of how the vehicle gets there after the failure, level and not yet spinning. This
module's test is an *obstruction*: a bound, under the assumptions below, that no thrust history of
the remaining rotors spins the vehicle up to the solution's yaw rate before the tilt passes a
stated limit; where it excludes nothing, entry is not promised either.

Assumptions (outside them nothing is excluded): thrusts that cannot reverse, ``J_x = J_y``, no
rotor inertia. Neglected within them (a review's list, not yet bounded): the tilt read as the
planar sum of the roll/pitch angles (a bending path reaches less true tilt than its projection:
two 1.11 rad legs at right angles project to 90 degrees, tilt 78.6), and rotational damping,
which on Ke's quadcopter acts faster on roll (``J_x / k_r`` 2 s) than on yaw (3.7 s), lowering the
ratio by about 7 % over 0.3 s. Where the bound excludes entry with a wide margin (Ke's
quadcopter: at most 2.33 rad/s by 90 degrees against 18.19 needed) these do not decide it.

The argument (body axes FRD, principal inertia ``J``; rotor ``i``'s roll/pitch angular
acceleration per newton ``G_i = (L_i / J_x, M_i / J_y)``, its yaw angular acceleration per newton
``H_i = N_i / J_z``, both from the effectiveness matrix). From rest and level, while the body has
turned little, the rates are integrals of the accelerations: ``w_xy(t) = sum_i G_i W_i(t)``,
``r(t) = sum_i H_i W_i(t)`` with ``W_i = int_0^t T_i >= 0``; the tilt and the yaw angle are their
integrals again, with weights ``V_i = int_0^t (t - s) T_i(s) ds >= 0``. If a horizontal direction
``c`` has ``c . G_i >= rho |H_i|`` for every remaining rotor (the rotors' roll/pitch-to-yaw ratio:
every newton that yaws the vehicle also tilts it towards ``c``), then
``tilt >= c . sum_i G_i V_i >= rho sum_i |H_i| V_i >= rho int_0^t |r|``: the tilt is at least
``rho`` times the yaw angle turned. The spin itself needs that yaw angle: with at most
``alpha = sum_i max(0, s H_i) T_max,i`` of angular acceleration in the solution's direction
``s``, the yaw rate ``r*`` is reached only after turning ``int |r| >= r*^2 / (2 alpha)``
(the fastest spin-up, constant ``alpha``, turns the least). So the tilt when the spin is
reached is at least ``rho r*^2 / (2 alpha)``.

What the linear step neglects, bounded rather than ignored: once the body turns, each rotor's
acceleration is no longer along its initial direction. The body's own yaw turns it by at most the
yaw angle ``Psi = int |r|``; the gyroscopic term ``(J_z - J_xy) r w_xy`` turns the roll/pitch
rates by at most ``gamma Psi`` (``gamma = max |J_z - J_x| / J_y, |J_z - J_y| / J_x``). Every
contribution is therefore within ``delta = (1 + gamma) Psi`` of where it started, and the ratio
becomes ``rho(delta) = min_i |G_i| cos(phi_i + delta) / |H_i|`` (``phi_i``: the angle from ``c`` to
``G_i``), decreasing in ``delta``; the tilt bound is ``F(Psi) = int_0^Psi rho((1 + gamma) x) dx``,
kept only while ``rho > 0``. The decision: the tilt is at least
``F(min(Psi_need, Psi_0))`` before the spin reaches ``r*`` (``Psi_need = r*^2 / (2 alpha)``,
``Psi_0`` where ``rho`` reaches 0); if that is at least the tilt limit, the relaxed hover is not
reachable from hover. ``F`` is summed on 4,000 right endpoints (a lower sum: ``rho`` decreases),
``c`` is the best of 3,600 directions (any direction gives a valid bound).

Also bounded, not neglected: the rotors' own angular momentum. Changing a rotor's speed (a
failed rotor stopping too) moves at most ``I_R Omega_max`` (``Omega_max = sqrt(T_max / k_f)``)
into the body's yaw without any thrust: the needed spin is ``r*`` less that, over ``J_z``.
Neglected: rotational damping (it slows the roll and the yaw alike; over the fraction of a second
the obstruction takes on Ke's quadcopter, ``J / k_r`` is 2-4 s) and the rotor lag (it only
restricts the thrust histories, so the bound holds).

The tilt limit: 90 degrees, the simulator's (``rotorfault.DivergenceLimits().max_tilt_rad``:
past it a flight is lost), :data:`ENTRY_TILT_LIMIT_RAD`. The threshold is the physics' own, not
fitted: the bound is checked against flights on every preset (``tests/studies/test_agreement.py``),
on a Ke quadcopter whose rotors yaw more than they roll (``k_mu`` 0.08 m, arm 0.06 m), where it
excludes nothing and the relaxed hover LQR does enter the spin from hover, and on Ke's own, where it
excludes entry and no controller enters.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .. import _rfcore
from .._util.convert import real
from .airframe import Airframe, require_airframe
from .relaxed_hover import FixedPitchActuatorLike, RelaxedHoverSettings, RelaxedHoverSolution, _vehicle_settings

#: The tilt the entry must stay below (rad): the simulator's divergence limit (module notes).
ENTRY_TILT_LIMIT_RAD = math.pi / 2
#: Directions ``c`` tried (the best kept) and right endpoints of the tilt bound's sum.
DIRECTIONS = 3600
STEPS = 4000


@dataclass(frozen=True)
class EntryFromHover:
    """The evidence of :func:`entry_from_hover` (module notes): ``reachable`` is ``False`` only
    where the bound (under its assumptions) shows that the tilt passes ``tilt_limit_rad`` before the spin reaches
    ``spin_rate_needed_rad_s``; ``True`` says the bound excludes nothing.

    - ``spin_rate_needed_rad_s``: the body-z rate of the relaxed hover, less what the rotors'
      angular momentum can give (rad/s);
    - ``spin_up_time_s``: the shortest spin-up, at the remaining rotors' largest yaw
      acceleration ``alpha`` (s; inf if they cannot yaw that way);
    - ``roll_to_yaw_ratio``: ``rho``, roll/pitch angular acceleration in the direction ``c`` per
      unit of yaw angular acceleration, the smallest over the remaining rotors (0 where some
      rotors yaw without tilting the vehicle one way: no obstruction);
    - ``tilt_before_spin_rad``: the least tilt reached before the spin does (rad; the bound
      ``F``, capped where the turned directions stop tilting);
    - ``spin_rate_at_tilt_limit_rad_s``: the fastest spin reachable before the tilt reaches the
      limit (rad/s; inf where the bound never reaches it).

    Examples:

        >>> import rotorfault as rf
        >>> quad = rf.Airframe.preset("ke-quadcopter").with_failed_rotors([1, 2])
        >>> best = rf.relaxed_hover(quad, drag=rf.Drag(rotational_n_m_s=2.8e-3)).best
        >>> entry = rf.analysis.entry_from_hover(quad, best)
        >>> entry.reachable, round(entry.roll_to_yaw_ratio, 2), round(entry.spin_rate_at_tilt_limit_rad_s, 2)
        (False, 9.89, 2.33)
    """

    reachable: bool
    tilt_limit_rad: float
    spin_rate_needed_rad_s: float
    spin_up_time_s: float
    roll_to_yaw_ratio: float
    tilt_before_spin_rad: float
    spin_rate_at_tilt_limit_rad_s: float


def entry_from_hover(
    airframe: Airframe,
    solution: RelaxedHoverSolution,
    settings: RelaxedHoverSettings | None = None,
    *,
    drag: _rfcore.Drag | None = None,
    actuator: FixedPitchActuatorLike | None = None,
    tilt_limit_rad: float = ENTRY_TILT_LIMIT_RAD,
) -> EntryFromHover:
    """Whether ``solution`` (a relaxed hover of ``airframe``, its failed rotors at efficiency 0)
    can be entered from level hover at rest without the tilt passing ``tilt_limit_rad`` (rad,
    default 90 degrees, the simulator's limit): the obstruction of the module notes. The rotor
    inertia and thrust coefficient are read as :func:`relaxed_hover` reads them (``settings``,
    or ``drag`` and ``actuator``). A static solution is reachable: it is hover.

    Examples:

        >>> import rotorfault as rf
        >>> quad = rf.Airframe.preset("ke-quadcopter").with_failed_rotors([1])
        >>> best = rf.relaxed_hover(quad, drag=rf.Drag(rotational_n_m_s=2.8e-3)).best
        >>> entry = rf.analysis.entry_from_hover(quad, best)
        >>> entry.reachable, entry.roll_to_yaw_ratio, round(entry.spin_up_time_s, 2)
        (True, 0.0, 0.54)
    """
    airframe = require_airframe(airframe)
    if not isinstance(solution, RelaxedHoverSolution):
        raise TypeError(f"solution: expected rotorfault.RelaxedHoverSolution, got {type(solution).__name__}")
    settings = _vehicle_settings(settings, drag, actuator)
    limit = real("tilt_limit_rad", tilt_limit_rad)
    if not 0.0 < limit <= math.pi:
        raise ValueError(f"tilt_limit_rad: must be in (0, pi], got {limit!r}")
    wrench = np.asarray(airframe.wrench_matrix(), dtype=float)
    if len(solution.thrust_n) != wrench.shape[1]:
        raise ValueError(f"solution: has {len(solution.thrust_n)} rotor thrusts, the airframe {wrench.shape[1]} rotors")
    inertia = np.asarray(airframe.inertia_kg_m2, dtype=float)
    rate = np.asarray(solution.body_rate_rad_s, dtype=float)
    # What the rotors' angular momentum can put into the yaw without thrust (module notes).
    free = 0.0
    if settings.rotor_inertia_kg_m2 > 0.0:
        omega_max = np.sqrt(np.asarray(airframe.max_thrust_n, dtype=float) / settings.thrust_coefficient_n_s2)
        free = float(settings.rotor_inertia_kg_m2 * omega_max.sum() / inertia[2])
    needed = max(0.0, abs(float(rate[2])) - free)
    sign = 1.0 if rate[2] >= 0.0 else -1.0
    if solution.kind == "static" or needed == 0.0:
        return EntryFromHover(True, limit, needed, 0.0, 0.0, 0.0, math.inf)
    live = np.any(wrench != 0.0, axis=0)
    if not _within_assumptions(airframe, inertia, live, settings.rotor_inertia_kg_m2):
        reach = _alpha(airframe, wrench, inertia, live, sign)
        return EntryFromHover(True, limit, needed, needed / reach if reach > 0.0 else math.inf, 0.0, 0.0, math.inf)
    accel = wrench[3:6, live] / inertia[:, None]
    roll_pitch, yaw = accel[:2], accel[2]
    alpha = float(np.sum(np.maximum(0.0, sign * yaw) * np.asarray(airframe.max_thrust_n, dtype=float)[live]))
    spin_up = needed / alpha if alpha > 0.0 else math.inf
    angles = np.linspace(0.0, 2.0 * math.pi, DIRECTIONS, endpoint=False)
    directions = np.stack([np.cos(angles), np.sin(angles)], axis=1)
    size = np.linalg.norm(roll_pitch, axis=0)
    phi = np.arccos(np.clip(directions @ roll_pitch / np.where(size > 0.0, size, 1.0), -1.0, 1.0))
    ratios = _ratio(size, phi, yaw)
    best = int(np.argmax(ratios))
    rho = float(ratios[best])
    if alpha == 0.0:  # no remaining rotor yaws the solution's way: the spin is never reached
        return EntryFromHover(False, limit, needed, spin_up, max(rho, 0.0), 0.0, 0.0)
    # Rounding of a ratio that is 0 (two rotors' accelerations exactly opposite) counts as 0.
    scale = float(np.max(size)) / float(np.max(np.abs(yaw)))
    if not rho > 1e-9 * scale:  # some rotors yaw without tilting one way: nothing is excluded
        return EntryFromHover(True, limit, needed, spin_up, 0.0, 0.0, math.inf)
    gamma = max(abs(inertia[2] - inertia[0]) / inertia[1], abs(inertia[2] - inertia[1]) / inertia[0])
    psi_need = needed * needed / (2.0 * alpha)
    # Where the first rotor's turned acceleration stops tilting towards c: the bound ends there.
    psi_zero = float(np.min(math.pi / 2 - phi[best][size > 0.0])) / (1.0 + gamma)
    psi_end = min(psi_need, psi_zero)
    step = psi_end / STEPS
    psi = step * np.arange(1, STEPS + 1)
    turned = np.maximum(_ratio(size, phi[best][None, :] + (1.0 + gamma) * psi[:, None], yaw), 0.0)
    tilt = np.cumsum(turned) * step  # right endpoints of a decreasing function: a lower sum
    tilt_before = float(tilt[-1])
    at = int(np.searchsorted(tilt, limit))
    spin_at_limit = math.sqrt(2.0 * alpha * float(psi[at])) if at < STEPS else math.inf
    return EntryFromHover(not tilt_before >= limit, limit, needed, spin_up, rho, tilt_before, spin_at_limit)


def _within_assumptions(airframe: Airframe, inertia: np.ndarray, live: np.ndarray, rotor_inertia_kg_m2: float) -> bool:
    """The obstruction's derivation holds (module notes): the remaining rotors' thrusts cannot
    reverse (``W_i >= 0``), ``J_x = J_y`` (else ``(J_x - J_y) p q / J_z`` adds a yaw acceleration
    ``alpha`` does not bound) and no rotor inertia (its gyroscopic moment turns the roll/pitch
    rates by an angle the yaw angle does not bound). Elsewhere nothing is excluded (a reviewer's
    counterexample: Ke's quadcopter with reversible rotors spins up twice as fast)."""
    reversible = bool(np.any(np.asarray(airframe.min_thrust_n, dtype=float)[live] < 0.0))
    symmetric = abs(inertia[0] - inertia[1]) <= 1e-12 * max(inertia[0], inertia[1])
    return not reversible and symmetric and rotor_inertia_kg_m2 == 0.0


def _alpha(airframe: Airframe, wrench: np.ndarray, inertia: np.ndarray, live: np.ndarray, sign: float) -> float:
    """The largest yaw angular acceleration in the direction ``sign`` (rad/s^2), each live
    rotor's thrust anywhere within its bounds (reversible rotors included)."""
    yaw = sign * wrench[5, live] / inertia[2]
    high = np.asarray(airframe.max_thrust_n, dtype=float)[live]
    low = np.asarray(airframe.min_thrust_n, dtype=float)[live]
    return float(np.sum(np.maximum(yaw * high, yaw * low)))


def _ratio(size: np.ndarray, phi: np.ndarray, yaw: np.ndarray) -> np.ndarray:
    """``min_i |G_i| cos(phi_i) / |H_i|`` per row of ``phi`` (angles past pi count as pi); a rotor
    that tilts without yawing keeps the bound only if it tilts towards ``c`` (else -inf)."""
    along = size * np.cos(np.minimum(phi, math.pi))
    magnitude = np.abs(yaw)
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.where(magnitude > 0.0, along / magnitude, np.where(along >= 0.0, math.inf, -math.inf))
    return np.asarray(ratio.min(axis=1))


__all__ = ["DIRECTIONS", "ENTRY_TILT_LIMIT_RAD", "STEPS", "EntryFromHover", "entry_from_hover"]

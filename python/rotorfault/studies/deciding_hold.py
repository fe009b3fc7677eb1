"""The deciding campaign's hold rule (issue 30), in one place: what the flights judge
(:func:`rotorfault.studies.deciding.run_rows`) and what a stored dataset is re-judged by
(:func:`rotorfault.studies.deciding.read_deciding`), from the stored columns and the run's seeded
draws, without flying.

A run *holds* when it is not lost, stays within :data:`HOLD_ALTITUDE_M` of the set point's altitude
and :data:`HOLD_HORIZONTAL_M` of it horizontally from :data:`SETTLE_S` after the failure to the
end, and its yaw rate is not spinning up. The spin rule is physics, per run: the body yaw dynamics
``I_zz r' = tau_z - k_r r`` settle a spin with the time constant ``tau = I_zz / k_r`` (the run's
own ``I_zz``: the nominal times its drawn inertia factor; ``k_r`` the vehicle's rotational damping,
:func:`spin_settle_time_constant_s`). A run's spin growth ``G`` (mean |r| over the window's last
span minus the span before, the core's ``window_spin_growth_rad_s``; ``final``: the last span's
mean) may be at most :func:`spin_growth_limit_rad_s`, the largest of:

- :data:`SPIN_GROWTH_MIN_RAD_S`: a spin's wind- and noise-driven wander is not a spin-up;
- the failure's own settle: a first-order settle from rest at the failure, ``r = r_f (1 -
  e^(-t/tau))``, still grows between the two spans by :func:`spin_settle_growth_share` of the last
  span's mean; allowed with the margin :data:`SPIN_SETTLE_MARGIN`;
- a later change of the yaw moment that has nearly settled: a first-order settle through the two
  span means ends ``G / (e^(L/tau) - 1)`` above the last (L: the span), whenever it started; a spin
  predicted to end within :data:`SPIN_SETTLED_SHARE` of its last mean is settled (this allowance
  at most :data:`SPIN_SETTLED_CAP_SHARE` of the last mean, below a linear spin-up's 22.2 %: with a
  short tau, e.g. the Lanzon quadrotor's 0.41 s, a moment change has settled long before the
  window, so growth there is a moment still changing).

Without damping (``k_r = 0``, the PX4 x500 model) nothing settles a spin and the yaw rate grows
without bound under any moment left: both settle terms are 0 and only the minimum is allowed.

A spin that settles must also settle inside the flight: the first-order end through the two span
means, ``|final| + G / (e^(L/tau) - 1)`` (:func:`predicted_spin_end_rad_s`), must stay below the
body rate at which the campaign's flights count a vehicle as lost (:data:`SPIN_END_LIMIT_RAD_S`,
the simulator's default ``DivergenceLimits.max_rate_rad_s``); a spin heading past it is lost after
the window, not held. (Measured on the full campaign flown on 50b54a6: 24 of the hexacopter runs
the settle allowance admits head past 200 rad/s.)

Why these numbers. Spans of 5 s starting 15 s after the failure (the campaign's window): the
failure's settle share is 2.0 % for tau = 5 s, 7.7 % for 10 s, 14.1 % for 21 s (the hexacopters:
0.0599 kg m^2 / 0.0028 N m s), 15.4 % for 26 s (+20 % inertia); a linear spin-up ``r = a t`` (a
constant moment, no damping) grows by 22.2 % whatever ``a``. Measured on the full campaign flown on
50b54a6 (65,000 runs): hexa-ppnnpn's INDI runs in the position band grow by 0.60 to 1.10 times the
share of their own tau (median 0.94): a 25 % margin holds them all and still refuses a linear
spin-up for any tau up to 40 s (1.25 x 17.7 % = 22.1 %; above that a settle and a linear spin-up
look alike within 25 s). 5 % for "settled" is the core's own settle band (``steady_spin_rad_s``:
within 5 % of the window mean); on Ke's quadcopter (tau 3-4.5 s, its failure's settle long over
15 s later) it allows growth of 10-22 % of the final spin, a moment change the spin follows within
seconds; on the hexacopters 1.3 %, so it adds nothing to the failure's settle there.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from .._util.deprecation import removed_call_form
from ..flight import DivergenceLimits
from ..flight.outcomes import FLYING

#: The hold thresholds of the issue, and when the judging starts after the failure.
HOLD_ALTITUDE_M = 1.0
HOLD_HORIZONTAL_M = 3.0
SETTLE_S = 5.0
#: The smallest spin growth that counts, rad/s: a spin's wind- and noise-driven wander (a few
#: tenths of a rad/s) is not a spin-up.
SPIN_GROWTH_MIN_RAD_S = 1.0
#: How much more than a first-order settle's growth a spin may grow (module notes: measured 1.10
#: at most on the hexacopters' settling spins; a linear spin-up is 1.44 times the share at tau =
#: 26 s).
SPIN_SETTLE_MARGIN = 0.25
#: A spin predicted (first order, its own tau, from the two spans) to end within this share of
#: its last span's mean is settled (the core's settle band for ``steady_spin_rad_s``).
SPIN_SETTLED_SHARE = 0.05
#: The most the settled term allows, as a share of the last span's mean: below a linear spin-up's
#: 22.2 %. Why a cap: the term grows as e^(L/tau), and for a short tau (the Lanzon quadrotor's
#: 0.41 s) a moment change long before the window has settled by then, so growth between the
#: spans means the moment is still changing (a spin-up), not a settle.
SPIN_SETTLED_CAP_SHARE = 0.20
#: The body rate at which the campaign's flights count a vehicle as lost (rad/s): a settling spin
#: whose first-order end lies at or beyond it is lost after the window, not held.
SPIN_END_LIMIT_RAD_S: float = DivergenceLimits().max_rate_rad_s


def _time_constants_s(value: Any, name: str) -> np.ndarray[Any, np.dtype[np.float64]]:
    """Settle time constants (s) as float64, each > 0 (inf: no rotational damping), else a
    ``ValueError`` naming ``name``."""
    tau = np.asarray(value, dtype=np.float64)
    if np.any(np.isnan(tau)) or np.any(tau <= 0.0):
        raise ValueError(f"{name}: must be > 0 (inf: no rotational damping), got {tau[np.isnan(tau) | (tau <= 0)].ravel()[:3]}")
    return tau


def spin_settle_growth_share(time_constant_s: Any, since_failure_s: float, span_s: float) -> np.ndarray[Any, np.dtype[np.float64]]:
    """The growth of a first-order settle ``r = r_f (1 - e^(-t/tau))`` (t: time since the failure,
    s; ``time_constant_s``: tau, s, one per run) from the span of ``span_s`` seconds starting
    ``since_failure_s`` after the failure to the next span, as a share of the later span's mean:
    ``(tau/L) e^(-a/tau) (1 - e^(-L/tau))^2 / (1 - (tau/L) e^(-(a+L)/tau) (1 - e^(-L/tau)))``
    (a = ``since_failure_s``, L = ``span_s``). ``inf`` (no rotational damping: nothing settles the
    spin) gives 0. ``ValueError`` for a time constant that is not > 0 or spans that are not
    finite and > 0 (``since_failure_s`` >= 0).

    Examples:

        >>> from rotorfault.studies.deciding_hold import spin_settle_growth_share
        >>> [round(float(s), 4) for s in spin_settle_growth_share([5.0, 21.0, 26.0, float("inf")], 15.0, 5.0)]
        [0.0201, 0.1406, 0.1545, 0.0]
    """
    tau = _time_constants_s(time_constant_s, "time_constant_s")
    if not (math.isfinite(since_failure_s) and since_failure_s >= 0.0):
        raise ValueError(f"since_failure_s: must be finite and >= 0, got {since_failure_s}")
    if not (math.isfinite(span_s) and span_s > 0.0):
        raise ValueError(f"span_s: must be finite and > 0, got {span_s}")
    finite = np.isfinite(tau)
    t = np.where(finite, tau, 1.0)
    # expm1 keeps a long time constant's share exact (1 - e^(-L/tau) is tiny there).
    drop = -np.expm1(-span_s / t)
    growth = (t / span_s) * np.exp(-since_failure_s / t) * drop**2
    last = 1.0 - (t / span_s) * np.exp(-(since_failure_s + span_s) / t) * drop
    return np.where(finite, growth / last, 0.0)


def spin_settle_time_constant_s(inertia_zz_kg_m2: float, rotational_drag_n_m_s: float) -> float:
    """The yaw spin's settle time constant ``I_zz / k_r`` (s) of a vehicle with yaw inertia
    ``inertia_zz_kg_m2`` (kg m^2) and rotational damping ``rotational_drag_n_m_s`` (N m s); ``inf``
    without damping (``k_r = 0``: a spin never settles).

    Examples:

        >>> from rotorfault.studies.deciding_hold import spin_settle_time_constant_s
        >>> round(spin_settle_time_constant_s(0.0599, 0.0028), 2), spin_settle_time_constant_s(0.04, 0.0)
        (21.39, inf)
    """
    if not (math.isfinite(inertia_zz_kg_m2) and inertia_zz_kg_m2 > 0.0):
        raise ValueError(f"inertia_zz_kg_m2: must be finite and > 0, got {inertia_zz_kg_m2}")
    if not (math.isfinite(rotational_drag_n_m_s) and rotational_drag_n_m_s >= 0.0):
        raise ValueError(f"rotational_drag_n_m_s: must be finite and >= 0, got {rotational_drag_n_m_s}")
    return inertia_zz_kg_m2 / rotational_drag_n_m_s if rotational_drag_n_m_s > 0.0 else math.inf


def spin_growth_limit_rad_s(
    final_spin_rad_s: Any, settle_time_constant_s: Any, since_failure_s: float, span_s: float,
) -> np.ndarray[Any, np.dtype[np.float64]]:
    """The largest spin growth that still holds, rad/s, per run (module notes): ``max(
    SPIN_GROWTH_MIN_RAD_S, (1 + SPIN_SETTLE_MARGIN) x spin_settle_growth_share(tau) x |final|,
    min(SPIN_SETTLED_SHARE x (e^(span/tau) - 1), SPIN_SETTLED_CAP_SHARE) x |final|)``,
    ``final_spin_rad_s`` the mean |yaw rate|
    over the window's last span (rad/s), ``settle_time_constant_s`` the run's tau (s; inf:
    undamped, only the minimum), the spans as :func:`spin_settle_growth_share` takes them (NaN
    final stays NaN).

    Examples:

        >>> from rotorfault.studies.deciding_hold import spin_growth_limit_rad_s
        >>> [round(float(x), 2) for x in spin_growth_limit_rad_s([63.0, 63.0, 40.0], [21.0, float("inf"), 3.7], 15.0, 5.0)]
        [11.07, 1.0, 5.73]
    """
    final = np.abs(np.asarray(final_spin_rad_s, dtype=np.float64))
    tau = np.asarray(settle_time_constant_s, dtype=np.float64)
    share = spin_settle_growth_share(tau, since_failure_s, span_s)
    # G / (e^(L/tau) - 1) <= settled share x final, as a bound on G; 0 without damping (tau inf).
    settled = np.minimum(SPIN_SETTLED_SHARE * np.expm1(span_s / tau), SPIN_SETTLED_CAP_SHARE)
    return np.where(np.isnan(final), np.nan,
                    np.maximum(SPIN_GROWTH_MIN_RAD_S, np.maximum((1.0 + SPIN_SETTLE_MARGIN) * share, settled) * final))


def predicted_spin_end_rad_s(
    window_spin_growth_rad_s: Any, final_spin_rad_s: Any, settle_time_constant_s: Any, span_s: float,
) -> np.ndarray[Any, np.dtype[np.float64]]:
    """Where a first-order settle through the window's two span means ends, rad/s: ``|final| + G /
    (e^(L/tau) - 1)`` (G: the growth between the spans, rad/s; final: the last span's mean |yaw
    rate|, rad/s; tau: the run's settle time constant, s; L: ``span_s``). Undamped (tau inf) the
    spin has no end; its growth is judged by the minimum alone, so the end is taken as ``|final|``.

    Examples:

        >>> from rotorfault.studies.deciding_hold import predicted_spin_end_rad_s
        >>> [round(float(x), 1) for x in predicted_spin_end_rad_s([8.8, 8.8, 0.5], [63.0, 180.0, 40.0], [21.0, 21.0, float("inf")], 5.0)]
        [95.7, 212.7, 40.0]
    """
    growth = np.asarray(window_spin_growth_rad_s, dtype=np.float64)
    final = np.abs(np.asarray(final_spin_rad_s, dtype=np.float64))
    tau = _time_constants_s(settle_time_constant_s, "settle_time_constant_s")
    finite = np.isfinite(tau)
    rest = np.where(finite, growth / np.expm1(span_s / np.where(finite, tau, 1.0)), 0.0)
    return final + rest


@removed_call_form(
    5, "its fixed spin allowance is gone, and the rule now needs each run's settle time constant and the window's spans",
    "rotorfault.studies.deciding.judge_holds(..., settle_time_constant_s) (the campaign's spans; the time constant: "
    "deciding.run_settle_time_constant_s or spin_settle_time_constant_s)")
def holds(
    outcome: Any, window_altitude_m: Any, window_horizontal_m: Any, window_spin_growth_rad_s: Any, window_final_spin_rad_s: Any,
    settle_time_constant_s: Any, since_failure_s: float, span_s: float,
) -> np.ndarray[Any, np.dtype[np.bool_]]:
    """The hold verdict per run: not lost, within both thresholds (m) throughout the hold window,
    and not spinning up: the yaw-rate magnitude's growth over the window's last span (rad/s, the
    core's ``window_spin_growth_rad_s``) at most :func:`spin_growth_limit_rad_s` of the last
    span's mean |yaw rate| (rad/s) and the run's settle time constant (s), and a settle that ends
    below :data:`SPIN_END_LIMIT_RAD_S` (:func:`predicted_spin_end_rad_s`). NaN values (a lost
    run's, or a growth not measured) never hold.

    Examples:

        >>> from rotorfault.studies.deciding_hold import holds
        >>> # a hexacopter's settling spin (14 % growth, tau 21 s) holds; the same growth undamped does not
        >>> holds(["holds-position"] * 2, [0.4] * 2, [1.0] * 2, [8.8] * 2, [63.0] * 2, [21.0, float("inf")], 15.0, 5.0).tolist()
        [True, False]
    """
    alt = np.asarray(window_altitude_m, dtype=np.float64)
    hor = np.asarray(window_horizontal_m, dtype=np.float64)
    growth = np.asarray(window_spin_growth_rad_s, dtype=np.float64)
    limit = spin_growth_limit_rad_s(window_final_spin_rad_s, settle_time_constant_s, since_failure_s, span_s)
    with np.errstate(invalid="ignore"):
        end = predicted_spin_end_rad_s(growth, window_final_spin_rad_s, settle_time_constant_s, span_s)
        return (np.isin(np.asarray(outcome), FLYING) & (alt <= HOLD_ALTITUDE_M) & (hor <= HOLD_HORIZONTAL_M)
                & (growth <= limit) & (end < SPIN_END_LIMIT_RAD_S))


__all__ = ["HOLD_ALTITUDE_M", "HOLD_HORIZONTAL_M", "SETTLE_S", "SPIN_END_LIMIT_RAD_S", "SPIN_GROWTH_MIN_RAD_S", "SPIN_SETTLED_CAP_SHARE", "SPIN_SETTLED_SHARE", "SPIN_SETTLE_MARGIN", "holds",
           "predicted_spin_end_rad_s", "spin_growth_limit_rad_s", "spin_settle_growth_share", "spin_settle_time_constant_s"]

"""Ke et al.'s uniform passive fault-tolerant controller and its design (Ke, Cai, Quan; IEEE TIE).

One controller and one set of gains fly the vehicle fault-free and through one, two and three
rotor failures, without fault detection or switching: the controller never sees rotor efficiency.
The controller itself runs in Rust (:class:`UniformPassiveFtc`); this module holds it, its gain
presets and the stability analysis of Ke's Section III-D (the N matrix, Table II). The scenarios,
metrics and report of the paper's reproduction are in :mod:`rotorfault.papers.ke`.

Decisions on the paper's gaps (also in the README):

- the control command (18) as printed leaves a steady virtual-control deficit
  (``u_1 = k/(k+1) u_d1`` without a fault, eq. (43)); the default ``law="feedforward"`` adds the
  filtered desired virtual control, which removes the deficit, keeps the partial compensation of
  a fault and leaves the stability matrix ``I + k_rotor N`` of (25) unchanged. ``law="literal"``
  is (18) as printed, ``"full-compensation"`` Remark 5's (29), ``"baseline"`` a conventional
  cascade into the pseudo-inverse;
- Ke gives no aerodynamic rotational damping, which sets the spin rate: the presets carry a linear
  damping ``rotational_drag_n_m_s`` chosen so the steady spins land in the range of Ke's
  experiments.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import get_args

import numpy as np
import numpy.typing as npt

from .. import _rfcore
from .._util.convert import FloatArray, float_array, real
from .._util.deprecation import dataclass_compat
from .._typing import KeLaw
from ..analysis.airframe import Airframe, require_airframe
from ..allocation import Allocator
from ..flight import DivergenceLimits, Drag, FixedPitchActuator, Sensing, Simulator

#: Rows of the virtual control Ke's N matrix uses: thrust, roll, pitch (E_1).
E1_ROWS = (0, 1, 2)


#: Ke Table IV (HIL column by default) plus ``k_cp`` of Remark 4 and the remedy's altitude integral
#: ``k_iz`` (not in the paper; equal to the ``ke-hil`` preset): the core's class, used directly
#: (issue 26: no Python mirror). Keyword-only, defaults from the core's ``Default``; types checked
#: by the bindings, values once, by the core's ``check``, when the gains are made: ``epsilon_s``,
#: ``k_rotor``, ``k_rotor_z``, ``k_p``, ``k_v``, ``k_n3``, ``accel_limit_m_s2`` > 0, ``k_vz`` and
#: ``k_omega`` > 0.5 (Theorem 1), ``weights`` four entries ``(w_f, w_p, w_q, w_r)``. Frozen,
#: comparable, hashable and picklable; ``gains.replace(k_v=0.5)`` gives a validated copy and
#: ``KeGains.FIELDS`` the names (``dataclasses.replace`` and ``dataclasses.fields`` still work,
#: with a ``DeprecationWarning``, for one release).
KeGains = _rfcore.KeGains
dataclass_compat(KeGains)


class FtcPreset(_rfcore.FtcPreset):
    """A controller preset file (``presets/ftc/*.toml``): gains and the vehicle values that go with
    them (rotor lag from Ke Table III, the rotational damping Ke does not give).

    The core's preset itself (issue 26: no field-by-field copy): keyword-only, every field required
    (``name``, ``description``, ``source``, ``airframe_name``, ``gains`` a :class:`KeGains`,
    ``rotor_time_constant_s`` s, ``rotational_drag_n_m_s`` N m s, ``linear_drag_n_s_m`` N s/m),
    checked by the core's ``FtcPreset::check`` (the rules a preset file obeys);
    ``FtcPreset.from_toml_str(text, origin)`` parses a file (``origin`` prefixes error
    messages). Frozen, comparable, hashable, picklable; ``preset.replace(gains=...)`` gives a
    checked copy (``dataclasses.replace`` still works, with a ``DeprecationWarning``, for one
    release). This subclass adds only what reads it in Python: the :class:`~rotorfault.Airframe`
    preset (:attr:`airframe`) and the :class:`Simulator` the values make."""

    __slots__ = ()

    @property
    def airframe(self) -> Airframe:
        """The airframe preset the gains were designed for (``airframe_name``)."""
        return Airframe.preset(self.airframe_name)

    def simulator(
        self,
        *,
        dt_s: float | None = None,
        substeps: int | None = None,
        limits: DivergenceLimits | None = None,
        sensing: Sensing | None = None,
    ) -> Simulator:
        """The preset's vehicle at Ke's 400 Hz control rate (the simulator's default; ``dt_s`` and
        ``substeps`` override it): rotor lag and rotational damping; the controller flies on the
        truth, or on ``sensing`` (sensors and the estimator)."""
        timing = {k: v for k, v in (("dt_s", dt_s), ("substeps", substeps)) if v is not None}
        return Simulator(
            self.airframe,
            **timing,  # type: ignore[arg-type]
            actuator=FixedPitchActuator(time_constant_s=self.rotor_time_constant_s),
            drag=Drag(rotational_n_m_s=self.rotational_drag_n_m_s, linear_n_s_m=self.linear_drag_n_s_m),
            limits=limits,
            sensing=sensing,
        )


dataclass_compat(FtcPreset)


def _ftc_dir() -> Path:
    return Path(str(resources.files("rotorfault") / "presets" / "ftc"))


def presets() -> list[str]:
    """Names of the shipped controller presets (``ke-hil``, ``ke-experiment``: Table IV;
    ``ke-robust``: tuned to hold through partial and total faults, not the paper's)."""
    return sorted(p.stem for p in _ftc_dir().glob("*.toml"))


def preset(name: str = "ke-hil") -> FtcPreset:
    """A shipped controller preset by name."""
    if not isinstance(name, str):
        raise TypeError(f"preset: expected a preset name (str), got {type(name).__name__}")
    if name not in presets():
        raise ValueError(f"preset: unknown controller preset {name!r}; available: {', '.join(presets())}")
    return FtcPreset.from_toml_str((_ftc_dir() / f"{name}.toml").read_text(encoding="utf-8"), name)


# -- the controller ------------------------------------------------------------------------------

Setpoint = tuple[float, npt.ArrayLike]


class UniformPassiveFtc:
    """Ke et al.'s uniform passive fault-tolerant controller, run in Rust at the simulator's
    control rate (Ke: 400 Hz). One controller, one set of gains, fault-free and through one, two
    and three rotor failures; it never reads rotor efficiency.

    ``gains``: a :class:`KeGains` or a controller preset name (``"ke-hil"``, default;
    ``"ke-experiment"``). ``law``: ``"feedforward"`` (default, the documented remedy for the
    steady deficit of eq. (18)), ``"literal"`` (eq. (18) as printed), ``"full-compensation"``
    (Remark 5, eq. (29)) or ``"baseline"`` (conventional: desired virtual control straight into
    the pseudo-inverse, no estimation, no QP). ``setpoints``: ``[(time_s, (north, east, down))]``
    held from their time on (NED, m), or give one ``position`` (NED, m).

    Examples:

        >>> import rotorfault as rf
        >>> ke = rf.Airframe.preset("ke-quadcopter")
        >>> sim = rf.Simulator(ke)
        >>> ftc = rf.UniformPassiveFtc(ke, position=(0, 0, -10))
        >>> run = sim.run(rf.State(position=(0, 0, -10)), 3.0, controller=ftc, faults=[rf.RotorFault(1, 1.0, efficiency=0.5)])
        >>> run.events, round(float(abs(run.position[-1] - (0, 0, -10)).max()), 2)
        ([], 3.34)
    """

    LAWS: tuple[KeLaw, ...] = get_args(KeLaw)

    def __init__(
        self,
        airframe: Airframe,
        *,
        gains: KeGains | str = "ke-hil",
        law: KeLaw = "feedforward",
        position: npt.ArrayLike = (0.0, 0.0, 0.0),
        setpoints: Sequence[Setpoint] | None = None,
    ) -> None:
        self.airframe = require_airframe(airframe)
        if isinstance(gains, str):
            gains = preset(gains).gains
        if not isinstance(gains, KeGains):
            raise TypeError(f"gains: expected rotorfault.control.ke.KeGains or a preset name, got {type(gains).__name__}")
        if not isinstance(law, str):
            raise TypeError(f"law: expected a string, got {type(law).__name__}")
        if law not in self.LAWS:
            raise ValueError(f"law: expected one of {', '.join(map(repr, self.LAWS))}, got {law!r}")
        self.gains = gains
        self.law: KeLaw = law
        if setpoints is None:
            setpoints = [(0.0, position)]
        if isinstance(setpoints, (str, bytes)) or not hasattr(setpoints, "__iter__"):
            raise TypeError("setpoints: expected a sequence of (time_s, (north, east, down))")
        parsed = []
        for k, item in enumerate(setpoints):
            if not hasattr(item, "__len__") or len(item) != 2:
                raise TypeError(f"setpoints[{k}]: expected (time_s, (north, east, down))")
            point = float_array(f"setpoints[{k}].position", item[1], 1)
            if point.shape != (3,):
                raise ValueError(f"setpoints[{k}].position: expected 3 entries (north, east, down), got {point.shape[0]}")
            parsed.append((real(f"setpoints[{k}].time", item[0]), (float(point[0]), float(point[1]), float(point[2]))))
        self.setpoints = tuple(parsed)
        self.core(1.0 / 400.0)  # validates gains, airframe and setpoints now

    @property
    def u_trim(self) -> FloatArray:
        """Hover thrusts on the nominal matrix: where the actuators start."""
        nominal = self.airframe.with_efficiency(np.ones(self.airframe.rotor_count))
        hover = np.array([nominal.hover_thrust_n, 0.0, 0.0, 0.0])
        commands: FloatArray = Allocator(nominal, weights=self.gains.weights).allocate(hover).commands
        return commands

    def core(self, dt_s: float) -> _rfcore.UniformPassiveFtc:
        return _rfcore.UniformPassiveFtc(
            self.airframe._core,
            law=self.law,
            setpoints=list(self.setpoints),
            dt_s=float(dt_s),
            gains=self.gains,
        )

    def replay(self, times: npt.ArrayLike, states: npt.ArrayLike, *, dt_s: float = 1.0 / 400.0) -> FloatArray:
        """The commands this controller (from its reset state) gives for a recorded history of
        what it measured: ``times`` (N) and ``states``, either N x 12 state vectors (position,
        velocity, roll pitch yaw, body rates: :attr:`Trajectory.measured`, converted to a state
        exactly as the simulator converts a measurement) or N x 13 (position, velocity,
        quaternion w x y z, body rates). No rotor efficiency enters: the passivity check.

        Replay what the controller saw. With sensor noise that is ``tr.measured`` (the true
        states differ from it by the noise, and so do their commands: by 5.2 N at 30 dB in
        ``tests/control/test_ftc.py``)::

            commands = controller.replay(tr.t, tr.measured)           # with noise
            states = np.hstack([tr.position, tr.velocity, tr.quaternion, tr.omega])
            commands = controller.replay(tr.t, states)                # without noise

        Both reproduce ``tr.rotor_command`` bit for bit for a run recorded with
        ``record_every=1`` (at the simulator's ``dt_s``, passed here), but for a diverged run's
        last row when replaying true states (the flight computed no command there: NaN). ``times`` must be spaced
        by ``dt_s`` (the filters assume one call per control period), except the last interval,
        which may be shorter: a run's shortened final step or its located divergence. A last
        row that is entirely NaN (a divergence row of ``tr.measured``, where no command was
        computed) gives a NaN command row, as recorded."""
        t = float_array("times", times, 1)
        x = float_array("states", states, 2)
        period = real("dt_s", dt_s)
        if x.shape[0] != t.size:
            raise ValueError(f"states: expected one row per time ({t.size}), got {x.shape[0]}")
        # The filters assume one call per control period: a thinned recording (record_every > 1)
        # would replay with the wrong dynamics. The last interval may be shorter (a shortened
        # final step ends the run at duration_s; a divergence is located within its step).
        gaps = np.diff(t)
        tol = 1e-9 * max(period, 1.0)
        if gaps.size and (np.abs(gaps[:-1] - period).max(initial=0.0) > tol or not 0.0 < gaps[-1] <= period + tol):
            raise ValueError(
                f"times: must be spaced by the control period dt_s = {period} s (record with record_every=1); "
                "only the last interval may be shorter"
            )
        unreplayed = x.shape[0] > 0 and bool(np.all(np.isnan(x[-1])))
        replayed = x[:-1] if unreplayed else x
        out: FloatArray = _rfcore.replay(self.core(period), t[: len(replayed)], replayed, 4)
        if unreplayed:
            out = np.vstack([out, np.full((1, out.shape[1]), np.nan)])
        return out


# -- Section III-D: stability analysis --------------------------------------------------------


def n_matrix(airframe: Airframe, efficiency: npt.ArrayLike) -> FloatArray:
    """Ke's ``N = (E_1 M) Lambda (E_1 M)^+`` (3 x 3) with ``M`` the airframe's nominal
    effectiveness matrix and ``Lambda = diag(efficiency)`` (Ke's health matrix): how the rotors
    turn a commanded thrust/roll/pitch into what the vehicle receives under pseudo-inverse
    allocation (24)."""
    if not isinstance(airframe, Airframe):
        raise TypeError(f"airframe: expected an Airframe, got {type(airframe).__name__}")
    lam = float_array("efficiency", efficiency, 1)
    nominal = airframe.with_efficiency(np.ones(airframe.rotor_count))
    frame = nominal.with_efficiency(lam)  # validates efficiency: one per rotor, in [0, 1]
    e1m = nominal.effectiveness_matrix()[list(E1_ROWS)]
    e1m_lambda = frame.effectiveness_matrix()[list(E1_ROWS)]
    out: FloatArray = e1m_lambda @ np.linalg.pinv(e1m)
    return out


ComplexArray = npt.NDArray[np.complex128]


def n_eigenvalues(airframe: Airframe, efficiency: npt.ArrayLike) -> ComplexArray:
    """Eigenvalues of :func:`n_matrix` (Table II), sorted by real part then imaginary part."""
    values = np.linalg.eigvals(n_matrix(airframe, efficiency)).astype(np.complex128)
    order = np.lexsort((values.imag, values.real))
    out: ComplexArray = values[order]
    return out


@dataclass(frozen=True)
class StabilityCheck:
    """Ke's linear checks for one efficiency vector (Ke's health matrix, ``diag(efficiency)``):
    ``thrust_feedback`` is (25), ``Re eig(I + k_rotor N) > 0`` (the uniform controller);
    ``full_compensation`` is (32), ``Re eig(N) > 0`` (Remark 5's controller, which fails with two
    or three failures)."""

    efficiency: tuple[float, ...]
    eigenvalues: ComplexArray
    k_rotor: float
    thrust_feedback: bool
    full_compensation: bool


def stability_check(airframe: Airframe, efficiency: npt.ArrayLike, *, k_rotor: float = 2.0) -> StabilityCheck:
    k = real("k_rotor", k_rotor)
    if not (math.isfinite(k) and k > 0):
        raise ValueError(f"k_rotor: must be > 0 and finite, got {k}")
    eig = n_eigenvalues(airframe, efficiency)
    tol = 1e-12
    return StabilityCheck(
        tuple(float(v) for v in float_array("efficiency", efficiency, 1)),
        eig,
        k,
        bool(np.all((1.0 + k * eig).real > tol)),
        bool(np.all(eig.real > tol)),
    )


__all__ = [
    "E1_ROWS",
    "FtcPreset",
    "KeGains",
    "StabilityCheck",
    "UniformPassiveFtc",
    "n_eigenvalues",
    "n_matrix",
    "preset",
    "presets",
    "stability_check",
]

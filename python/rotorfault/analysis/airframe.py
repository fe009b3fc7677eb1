"""The multirotor airframe.

Frame convention (the same for every analysis in rotorfault): body FRD (x forward, y right,
z down). Rotor ``i`` sits at arm angle ``phi_i`` measured from body x towards body y (clockwise
seen from above) at distance ``r_i``; its thrust gives roll torque ``-r_i sin(phi_i) f_i``, pitch
torque ``r_i cos(phi_i) f_i`` and yaw torque ``w_i k_mu f_i`` with ``w_i = +1`` for a rotor spinning
anticlockwise seen from above, ``-1`` clockwise: Du et al. eqs. (5)-(6) and (17).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from importlib import resources
from os import PathLike
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from .. import _rfcore
from .._util.convert import FloatArray, float_array, real, rotor_numbers
from .._typing import Spin

_SPIN_WORDS = {
    "cw": -1.0,
    "clockwise": -1.0,
    "ccw": 1.0,
    "acw": 1.0,
    "anticlockwise": 1.0,
    "counterclockwise": 1.0,
}


def _spin_signs(spin: Any) -> FloatArray:
    """Spin directions as ``w_i`` (+1 anticlockwise, -1 clockwise); words or numbers accepted."""
    if isinstance(spin, (str, bytes)):
        raise TypeError("spin: expected one direction per rotor, got a single string")
    items = list(spin) if isinstance(spin, Iterable) else None
    if items is None:
        raise TypeError(f"spin: expected a sequence of 'cw'/'ccw' or +1/-1, got {type(spin).__name__}")
    if items and all(isinstance(s, str) for s in items):
        signs = []
        for i, word in enumerate(items):
            sign = _SPIN_WORDS.get(word.strip().lower())
            if sign is None:
                raise ValueError(
                    f"spin[{i}] (rotor {i + 1}): must be 'cw' (clockwise) or 'ccw' "
                    f"(anticlockwise), got {word!r}"
                )
            signs.append(sign)
        return np.asarray(signs, dtype=np.float64)
    return float_array("spin", items, 1)


def _preset_dir() -> Path:
    return Path(str(resources.files("rotorfault") / "presets"))


def _rotor_limits_and_body(
    m: int,
    max_thrust_n: npt.ArrayLike,
    min_thrust_n: npt.ArrayLike | None,
    efficiency: npt.ArrayLike | None,
    mass_kg: float,
    inertia_kg_m2: npt.ArrayLike,
    drag_torque_ratio_m: float,
    gravity_m_s2: float,
) -> tuple[Any, ...]:
    """The arguments both core constructors end with (checked here for types and shapes, in this
    order, by the core for values): thrust limits and efficiencies of ``m`` rotors (defaults 0 N
    and 1), mass, inertia, drag torque ratio and gravity."""
    return (
        float_array("max_thrust_n", max_thrust_n, 1),
        np.zeros(m) if min_thrust_n is None else float_array("min_thrust_n", min_thrust_n, 1),
        np.ones(m) if efficiency is None else float_array("efficiency", efficiency, 1),
        real("mass_kg", mass_kg),
        float_array("inertia_kg_m2", inertia_kg_m2, 1),
        real("drag_torque_ratio_m", drag_torque_ratio_m),
        real("gravity_m_s2", gravity_m_s2),
    )


class Airframe:
    """A multirotor: rotor geometry, thrust limits, rotor efficiencies and mass properties.

    Immutable: methods that change something (``with_efficiency``) return a new airframe, and the
    array properties return fresh read-only copies.

    Parameters
    ----------
    arm_angle_rad : arm angle of each rotor from body x towards body y, rad (Du's ``phi_i``).
    arm_length_m : distance of each rotor from the centre of mass, m (``r_i``).
    spin : per rotor ``"cw"``/``"ccw"`` (seen from above) or ``-1``/``+1`` (Du's ``w_i``).
    max_thrust_n : maximum thrust of each rotor, N (``K_i``).
    mass_kg : vehicle mass, kg.
    inertia_kg_m2 : principal moments of inertia ``(Jx, Jy, Jz)``, kg m^2.
    drag_torque_ratio_m : reaction torque per unit thrust ``k_mu``, m (>= 0).
    min_thrust_n : minimum thrust of each rotor, N (default 0; negative for reversible rotors).
    efficiency : rotor efficiencies (Du's ``eta_i``) in [0, 1] (default 1: healthy; 0: failed).
    gravity_m_s2 : gravitational acceleration, m/s^2 (default 9.81).
    name : a label used in reports.

    Examples:

        >>> import rotorfault as rf
        >>> hexa = rf.Airframe.preset("hexa-ppnnpn")
        >>> hexa.rotor_count, hexa.mass_kg
        (6, 1.535)
        >>> hexa.with_efficiency([0, 1, 1, 1, 1, 1]).efficiency.tolist()
        [0.0, 1.0, 1.0, 1.0, 1.0, 1.0]
    """

    __slots__ = ("_core", "_allocators")  # _allocators: rotorfault.allocation's cache (immutable airframe)
    _core: _rfcore.Airframe

    def __init__(
        self,
        arm_angle_rad: npt.ArrayLike,
        arm_length_m: npt.ArrayLike,
        spin: Sequence[Spin | str] | npt.ArrayLike,
        max_thrust_n: npt.ArrayLike,
        mass_kg: float,
        inertia_kg_m2: npt.ArrayLike,
        drag_torque_ratio_m: float,
        *,
        min_thrust_n: npt.ArrayLike | None = None,
        efficiency: npt.ArrayLike | None = None,
        gravity_m_s2: float = _rfcore.DEFAULT_GRAVITY_M_S2,
        name: str = "custom",
    ) -> None:
        check_label("name", name)
        angles = float_array("arm_angle_rad", arm_angle_rad, 1)
        m = angles.shape[0]
        self._core = _rfcore.Airframe(
            name,
            angles,
            float_array("arm_length_m", arm_length_m, 1),
            _spin_signs(spin),
            *_rotor_limits_and_body(m, max_thrust_n, min_thrust_n, efficiency, mass_kg, inertia_kg_m2, drag_torque_ratio_m, gravity_m_s2),
        )

    @classmethod
    def from_rotors(
        cls,
        *,
        position_m: npt.ArrayLike,
        spin: Sequence[Spin | str] | npt.ArrayLike,
        max_thrust_n: npt.ArrayLike,
        mass_kg: float,
        inertia_kg_m2: npt.ArrayLike,
        drag_torque_ratio_m: float,
        thrust_axis: npt.ArrayLike | None = None,
        rotor_drag_torque_ratio_m: npt.ArrayLike | None = None,
        min_thrust_n: npt.ArrayLike | None = None,
        efficiency: npt.ArrayLike | None = None,
        gravity_m_s2: float = _rfcore.DEFAULT_GRAVITY_M_S2,
        name: str = "custom",
    ) -> Airframe:
        """The general form (PX4's): per rotor a position ``position_m`` (m x 3, body FRD, m, from
        the centre of mass) and a unit ``thrust_axis`` (m x 3, body FRD; default ``[0, 0, -1]``,
        straight up). ``spin`` is seen from the side the thrust points to. Rotor i's thrust f then
        gives the force ``f a_i`` and the torque ``f (p_i x a_i - w_i k_i a_i)`` with ``k_i`` its
        ``rotor_drag_torque_ratio_m`` (default: ``drag_torque_ratio_m`` for every rotor)."""
        check_label("name", name)
        signs = _spin_signs(spin)
        m = signs.shape[0]
        position = float_array("position_m", position_m, 2)
        axis = np.tile([0.0, 0.0, -1.0], (m, 1)) if thrust_axis is None else float_array("thrust_axis", thrust_axis, 2)
        for field, value in (("position_m", position), ("thrust_axis", axis)):
            if value.shape != (m, 3):
                raise ValueError(f"position_m, thrust_axis: {field} must be {m} x 3 (one row per rotor), got {value.shape}")
        k = None if rotor_drag_torque_ratio_m is None else float_array("rotor_drag_torque_ratio_m", rotor_drag_torque_ratio_m, 1)
        return cls._wrap(
            _rfcore.Airframe.general(
                name,
                np.ascontiguousarray(position),
                np.ascontiguousarray(axis),
                signs,
                k,
                *_rotor_limits_and_body(m, max_thrust_n, min_thrust_n, efficiency, mass_kg, inertia_kg_m2, drag_torque_ratio_m, gravity_m_s2),
            )
        )

    # -- other tools' formats (conventions in rotorfault/analysis/_formats.py) ----------------------------

    @classmethod
    def from_px4_params(
        cls,
        path: str | PathLike[str],
        *,
        mass_kg: float | None = None,
        inertia_kg_m2: npt.ArrayLike | None = None,
        gravity_m_s2: float = _rfcore.DEFAULT_GRAVITY_M_S2,
        name: str | None = None,
    ) -> Airframe:
        """Reads a PX4 parameter file as QGroundControl saves it (``CA_ROTOR_COUNT``,
        ``CA_ROTORn_PX/PY/PZ``, ``_AX/AY/AZ``, ``_KM``, ``_CT``, ``CA_R_REV``; missing rotor
        parameters take PX4's defaults). PX4's frame is body FRD like ours; ``KM`` is ``w k_mu``
        (positive anticlockwise), ``CT`` the thrust at full command (``max_thrust_n``), the axis is
        normalised as PX4 does. PX4 has no mass: give ``mass_kg`` or keep ``MPC_THR_HOVER`` in the
        file (mass = MPC_THR_HOVER x the full upward thrust / g). ``inertia_kg_m2`` (not in PX4's
        parameters; the ACAI and the failure verdicts do not depend on it) defaults to
        :data:`rotorfault.analysis._formats.PLACEHOLDER_INERTIA_KG_M2`."""
        from . import _formats

        if not isinstance(path, (str, PathLike)):
            raise TypeError(f"path: expected a file path, got {type(path).__name__}")
        try:
            text = Path(path).read_text(encoding="utf-8")
        except UnicodeDecodeError as exc:
            raise ValueError(f"{path}: not UTF-8 text ({exc.reason} at byte {exc.start})") from None
        params = _formats.parse_px4_params(text, str(path))
        columns = _formats.px4_columns(params, str(path), mass_kg=mass_kg, gravity_m_s2=real("gravity_m_s2", gravity_m_s2))
        return cls.from_rotors(
            **columns,
            inertia_kg_m2=_formats.PLACEHOLDER_INERTIA_KG_M2 if inertia_kg_m2 is None else inertia_kg_m2,
            gravity_m_s2=gravity_m_s2,
            name=Path(path).stem if name is None else name,
        )

    def to_px4_params(self, *, vehicle_id: int = 1, component_id: int = 1) -> str:
        """The rotor geometry as a QGroundControl parameter file (``CA_ROTOR*``, ``CA_R_REV`` for
        rotors with negative ``min_thrust_n``, ``MPC_THR_HOVER`` carrying the mass);
        :meth:`from_px4_params` reads it back to an equal airframe (up to the inertia, which PX4
        does not keep, and the planar short form, which becomes positions)."""
        from . import _formats

        return _formats.to_px4_params(self, vehicle_id=vehicle_id, component_id=component_id)

    @classmethod
    def from_rotorpy(cls, quad_params: dict[str, Any], *, name: str = "rotorpy") -> Airframe:
        """From RotorPy's vehicle parameter dict (``rotor_pos``, ``rotor_directions``,
        ``k_eta``, ``k_m``, ``rotor_speed_min``/``max``, ``mass``, ``Ixx``/``Iyy``/``Izz``).
        RotorPy's body frame is FLU (z up) and its rotors push along body +z: positions are
        converted to FRD (y and z negated); thrust ``k_eta w^2`` gives ``max_thrust_n`` at
        ``rotor_speed_max``, ``k_m / k_eta`` is k_mu, and ``rotor_directions`` +1 (anticlockwise
        seen from above) is our ``"ccw"``."""
        from . import _formats

        return cls.from_rotors(**_formats.rotorpy_columns(quad_params), name=name)

    def to_rotorpy(self) -> dict[str, Any]:
        """RotorPy's parameter dict (upright rotors only); :meth:`from_rotorpy` reads it back."""
        from . import _formats

        return _formats.to_rotorpy(self)

    @classmethod
    def ardupilot(
        cls,
        frame_class: int | str,
        frame_type: int | str,
        *,
        arm_length_m: float,
        max_thrust_n: float,
        mass_kg: float,
        inertia_kg_m2: npt.ArrayLike,
        drag_torque_ratio_m: float,
        gravity_m_s2: float = _rfcore.DEFAULT_GRAVITY_M_S2,
    ) -> Airframe:
        """An ArduPilot standard frame (``FRAME_CLASS`` / ``FRAME_TYPE`` as numbers or names, e.g.
        ``("quad", "x")`` or ``(1, 1)``) with ArduPilot's motor numbering and spins
        (``AP_MotorsMatrix``; the table is in :data:`rotorfault.analysis._formats.ARDUPILOT_FRAMES`)."""
        from . import _formats

        angles, spins, label = _formats.ardupilot_frame(frame_class, frame_type)
        m = len(angles)
        return cls(
            np.radians(angles), [arm_length_m] * m, spins, [max_thrust_n] * m, mass_kg, inertia_kg_m2,
            drag_torque_ratio_m, gravity_m_s2=gravity_m_s2, name=label,
        )

    @classmethod
    def _wrap(cls, core: _rfcore.Airframe) -> Airframe:
        check_label("name", core.name)
        check_label("description", core.description)
        airframe = cls.__new__(cls)
        airframe._core = core
        return airframe

    # -- construction from files ---------------------------------------------------------------

    @staticmethod
    def presets() -> list[str]:
        """Names of the airframes that ship with rotorfault."""
        return sorted(p.stem for p in _preset_dir().glob("*.toml"))

    @classmethod
    def preset(cls, name: str) -> Airframe:
        """A shipped airframe by name (see :meth:`presets`)."""
        if not isinstance(name, str):
            raise TypeError(f"preset: expected a preset name (str), got {type(name).__name__}")
        available = cls.presets()
        if name not in available:
            raise ValueError(f"preset: unknown airframe {name!r}; available: {', '.join(available)}")
        path = _preset_dir() / f"{name}.toml"
        return cls._wrap(_rfcore.Airframe.from_toml_str(path.read_text(encoding="utf-8"), name))

    @classmethod
    def from_toml(cls, path: str | PathLike[str]) -> Airframe:
        """Reads an airframe TOML file (schema: ``rotorfault/presets/README.md``)."""
        if not isinstance(path, (str, PathLike)):
            raise TypeError(f"path: expected a file path, got {type(path).__name__}")
        try:
            text = Path(path).read_text(encoding="utf-8")
        except UnicodeDecodeError as exc:
            raise ValueError(f"{path}: not UTF-8 text ({exc.reason} at byte {exc.start})") from None
        return cls._wrap(_rfcore.Airframe.from_toml_str(text, str(path)))

    @classmethod
    def load(cls, spec: str, relative_to: str | PathLike[str] | None = None, *, mass_kg: float | None = None) -> Airframe:
        """A preset name, or a path to an airframe TOML file (a ``.toml`` name or an existing
        file) or a PX4 ``.params`` file; relative paths resolve against ``relative_to`` when given.
        ``mass_kg``: the vehicle mass of a PX4 file (PX4 keeps none; see :meth:`from_px4_params`)."""
        if not isinstance(spec, str):
            raise TypeError(f"airframe: expected a preset name or a TOML path, got {type(spec).__name__}")
        path = Path(spec) if relative_to is None else Path(relative_to) / spec
        if spec.endswith(".params"):
            return cls.from_px4_params(path, mass_kg=mass_kg)
        if mass_kg is not None:
            raise ValueError(f"mass_kg: only a PX4 .params airframe takes its mass separately; {spec!r} carries its own")
        if spec.endswith(".toml") or path.is_file():
            return cls.from_toml(path)
        return cls.preset(spec)

    @classmethod
    def from_toml_str(cls, text: str, origin: str = "<string>") -> Airframe:
        """Parses an airframe from TOML text; ``origin`` labels error messages."""
        if not isinstance(text, str):
            raise TypeError(f"text: expected TOML text (str), got {type(text).__name__}")
        return cls._wrap(_rfcore.Airframe.from_toml_str(text, origin))

    # -- derived airframes ---------------------------------------------------------------------

    def with_efficiency(self, efficiency: npt.ArrayLike) -> Airframe:
        """A copy with rotor ``efficiency`` (Du's eta_i: one per rotor, each in [0, 1])."""
        eff = float_array("efficiency", efficiency, 1)
        return self._wrap(self._core.with_efficiency(eff))

    def with_failed_rotors(self, rotors: Iterable[int]) -> Airframe:
        """A copy with the given rotors (1-based, as in the papers) at efficiency 0."""
        efficiency = self.efficiency.copy()
        for rotor in rotor_numbers("rotors", rotors, self.rotor_count):
            efficiency[rotor - 1] = 0.0
        return self.with_efficiency(efficiency)

    def with_parameters(
        self,
        *,
        mass_kg: float | None = None,
        drag_torque_ratio_m: float | None = None,
        max_thrust_n: npt.ArrayLike | None = None,
        min_thrust_n: npt.ArrayLike | None = None,
        arm_length_m: npt.ArrayLike | None = None,
        spin: Sequence[Spin | str] | npt.ArrayLike | None = None,
        name: str | None = None,
    ) -> Airframe:
        """A copy with only the given parameters changed; every other field (3-D positions,
        tilted thrust axes, each rotor's own k_mu, reversible bounds, efficiencies, description)
        is kept exactly, through the exact TOML form. ``drag_torque_ratio_m`` is then every
        rotor's k_mu (a rotor with its own takes the new value too); ``arm_length_m`` (one per
        rotor) moves a rotor given by its position radially in the body x-y plane, keeping its
        direction, height and thrust axis (a rotor on the z axis has no direction: refused).
        The core checks the values, naming the field."""
        import tomllib

        doc = tomllib.loads(self.to_toml())
        rotors = doc["rotor"]
        m = len(rotors)

        def per_rotor(field: str, value: Any) -> FloatArray:
            array = float_array(field, value, 1)
            if array.shape != (m,):
                raise ValueError(f"{field}: expected {m} values (one per rotor), got {array.shape[0]}")
            return array

        if mass_kg is not None:
            doc["mass_kg"] = real("mass_kg", mass_kg)
        if drag_torque_ratio_m is not None:
            k = real("drag_torque_ratio_m", drag_torque_ratio_m)
            doc["drag_torque_ratio_m"] = k
            for rotor in rotors:
                if "drag_torque_ratio_m" in rotor:
                    rotor["drag_torque_ratio_m"] = k
        for field, value in (("max_thrust_n", max_thrust_n), ("min_thrust_n", min_thrust_n)):
            if value is not None:
                for rotor, v in zip(rotors, per_rotor(field, value)):
                    rotor[field] = float(v)
        if arm_length_m is not None:
            for i, (rotor, v) in enumerate(zip(rotors, per_rotor("arm_length_m", arm_length_m))):
                if "arm_length_m" in rotor:
                    rotor["arm_length_m"] = float(v)  # the loader's rule checks it
                    continue
                # A rotor given by position is scaled by v / radius before the loader sees it: inf * 0
                # warned before any refusal (long hostile run), so the value is checked first here.
                if not (math.isfinite(v) and v > 0.0):
                    raise ValueError(f"arm_length_m[{i}] (rotor {i + 1}): must be > 0 and finite, got {v}")
                x, y, z = rotor["position_m"]
                radius = math.hypot(x, y)
                if radius == 0.0:
                    raise ValueError(f"arm_length_m[{i}] (rotor {i + 1}): the rotor sits on the body z axis, so it has no arm to lengthen")
                rotor["position_m"] = [x * (v / radius), y * (v / radius), z]
        if spin is not None:
            signs = _spin_signs(spin)
            if signs.shape != (m,):
                raise ValueError(f"spin: expected {m} directions (one per rotor), got {signs.shape[0]}")
            for i, (rotor, w) in enumerate(zip(rotors, signs)):
                if w not in (1.0, -1.0):
                    raise ValueError(f"spin[{i}] (rotor {i + 1}): must be +1 (anticlockwise) or -1 (clockwise), got {w}")
                rotor["spin"] = "ccw" if w > 0 else "cw"
        if name is not None:
            doc["name"] = check_label("name", name)
        return Airframe.from_toml_str(_toml_document(doc), f"airframe {self.name!r} with changed parameters")

    def to_toml(self) -> str:
        """The airframe as TOML in the preset schema; :meth:`from_toml_str` reads it back exactly."""
        return self._core.to_toml_str()

    def effectiveness_matrix(self) -> FloatArray:
        """B_f of Du eq. (5), 4 x m: rows thrust (N/N), roll and pitch (m), yaw (m); columns
        scaled by the rotor efficiencies."""
        return self._core.effectiveness_matrix()

    def wrench_matrix(self) -> FloatArray:
        """The full 6 x m effectiveness matrix, body FRD: rows force ``F_x, F_y, F_z`` (N/N) and
        torque ``L, M, N`` (m); columns scaled by the rotor efficiencies. Hover needs
        :attr:`hover_wrench_6d`."""
        return self._core.wrench_matrix()

    @property
    def hover_wrench_6d(self) -> FloatArray:
        """``[0, 0, -m g, 0, 0, 0]``: the force and torque the rotors supply in level hover
        (thrust up is -z in FRD)."""
        return np.array([0.0, 0.0, -self.hover_thrust_n, 0.0, 0.0, 0.0])

    @property
    def position_m(self) -> FloatArray:
        """Rotor positions, m x 3, body FRD (planar rotors: ``(r cos phi, r sin phi, 0)``)."""
        return self._core.position_m

    @property
    def thrust_axis(self) -> FloatArray:
        """Unit thrust directions, m x 3, body FRD (``[0, 0, -1]``: straight up)."""
        return self._core.thrust_axis

    @property
    def rotor_drag_torque_ratio_m(self) -> FloatArray:
        """Each rotor's k_mu, m (its own, else :attr:`drag_torque_ratio_m`)."""
        return self._core.rotor_drag_torque_ratio_m

    @property
    def is_planar(self) -> bool:
        """Every rotor written in the short (arm angle, arm length) form."""
        return self._core.is_planar

    @property
    def is_fully_actuated(self) -> bool:
        """The 6 x m wrench matrix has rank 6: the vehicle can push sideways without tilting."""
        return self._core.is_fully_actuated

    # -- properties ----------------------------------------------------------------------------

    @property
    def name(self) -> str:
        return self._core.name

    @property
    def description(self) -> str:
        return self._core.description

    @property
    def rotor_count(self) -> int:
        return self._core.rotor_count

    @property
    def arm_angle_rad(self) -> FloatArray:
        return self._core.arm_angle_rad

    @property
    def arm_length_m(self) -> FloatArray:
        return self._core.arm_length_m

    @property
    def spin(self) -> tuple[Spin, ...]:
        """``"cw"`` or ``"ccw"`` per rotor, seen from above."""
        return tuple("ccw" if w > 0 else "cw" for w in self._core.spin_sign)

    @property
    def spin_sign(self) -> FloatArray:
        """Du's ``w_i``: +1 anticlockwise, -1 clockwise."""
        return self._core.spin_sign

    @property
    def max_thrust_n(self) -> FloatArray:
        return self._core.max_thrust_n

    @property
    def min_thrust_n(self) -> FloatArray:
        return self._core.min_thrust_n

    @property
    def efficiency(self) -> FloatArray:
        return self._core.efficiency

    @property
    def mass_kg(self) -> float:
        return self._core.mass_kg

    @property
    def inertia_kg_m2(self) -> FloatArray:
        return self._core.inertia_kg_m2

    @property
    def drag_torque_ratio_m(self) -> float:
        return self._core.drag_torque_ratio_m

    @property
    def gravity_m_s2(self) -> float:
        return self._core.gravity_m_s2

    @property
    def hover_thrust_n(self) -> float:
        """Weight m g, N: the thrust G[0] the rotors must supply to hover."""
        return self.mass_kg * self.gravity_m_s2

    def __repr__(self) -> str:
        return f"Airframe({self.name!r}, {self.rotor_count} rotors, {self.mass_kg:g} kg)"

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Airframe):
            return NotImplemented
        return self.to_toml() == other.to_toml()

    __hash__ = None  # type: ignore[assignment]  # equal airframes may differ in identity only

    def __reduce__(self) -> tuple[Any, ...]:
        # Pickle (for multiprocessing and Dask) through the exact TOML round trip.
        return (Airframe.from_toml_str, (self.to_toml(), f"pickled airframe {self.name!r}"))


#: Unicode categories a label may not hold: control and format characters, line and paragraph
#: separators (``str.splitlines`` breaks on some of them), so a name written into a file or a
#: terminal is never more than text.
#: Characters a name or description may not hold: controls, format characters (bidirectional
#: overrides), line and paragraph separators (each could start a live line or hide text in a
#: written file), and lone surrogates (no UTF-8 form: no file could hold the name). Unassigned
#: code points (Cn) are accepted: which ones are unassigned depends on the Unicode version of the
#: install, and none of them can break a file.
_FORBIDDEN_CATEGORIES = ("Cc", "Cf", "Cs", "Zl", "Zp")


def check_label(field: str, value: Any) -> str:
    """A name or description: a string without control characters (``TypeError``/``ValueError``
    naming the field and the first offending character)."""
    import unicodedata

    if not isinstance(value, str):
        raise TypeError(f"{field}: expected a string, got {type(value).__name__}")
    for i, ch in enumerate(value):
        if unicodedata.category(ch) in _FORBIDDEN_CATEGORIES:
            what = "a lone surrogate (no UTF-8 form)" if unicodedata.category(ch) == "Cs" else "control characters"
            raise ValueError(f"{field}: must not contain {what}, got U+{ord(ch):04X} at position {i}")
    return value


def _toml_value(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return toml_string(value)
    if isinstance(value, float):
        if not math.isfinite(value):
            raise ValueError(f"value: must be finite, got {value}")
        return repr(float(value))  # shortest round trip (a NumPy float's repr names its type)
    if isinstance(value, int):
        return str(value)
    if isinstance(value, list):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    raise TypeError(f"value: cannot write {type(value).__name__} to TOML")


def toml_string(text: str) -> str:
    """``text`` as a TOML basic string: quotes, backslashes and every control character escaped."""
    out = ['"']
    for ch in text:
        code = ord(ch)
        if ch in ('"', "\\"):
            out.append("\\" + ch)
        elif code < 0x20 or code == 0x7F:
            out.append(f"\\u{code:04X}")
        else:
            out.append(ch)
    out.append('"')
    return "".join(out)


def _toml_document(doc: dict[str, Any]) -> str:
    """The airframe schema's TOML (top-level keys, then ``[[rotor]]`` tables) from its parsed form."""
    lines = [f"{key} = {_toml_value(value)}" for key, value in doc.items() if key != "rotor"]
    for rotor in doc["rotor"]:
        lines += ["", "[[rotor]]", *(f"{key} = {_toml_value(value)}" for key, value in rotor.items())]
    return "\n".join(lines) + "\n"


def require_airframe(value: Any) -> Airframe:
    if not isinstance(value, Airframe):
        raise TypeError(f"airframe: expected rotorfault.Airframe, got {type(value).__name__}")
    return value


def rotor_labels(rotors: Sequence[int]) -> str:
    """``(1, 3)`` -> ``"1, 3"``; ``()`` -> ``"none"``."""
    return ", ".join(str(r) for r in rotors) if rotors else "none"

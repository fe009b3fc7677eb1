"""The multirotor airframe.

Frame convention (the same for every analysis in rotorfault): body FRD (x forward, y right,
z down). Rotor ``i`` sits at arm angle ``phi_i`` measured from body x towards body y (clockwise
seen from above) at distance ``r_i``; its thrust gives roll torque ``-r_i sin(phi_i) f_i``, pitch
torque ``r_i cos(phi_i) f_i`` and yaw torque ``w_i k_mu f_i`` with ``w_i = +1`` for a rotor spinning
anticlockwise seen from above, ``-1`` clockwise: Du et al. eqs. (5)-(6) and (17).
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from importlib import resources
from os import PathLike
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from . import _rfcore
from ._convert import FloatArray, float_array, real, rotor_numbers
from ._typing import Spin

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
        if not isinstance(name, str):
            raise TypeError(f"name: expected a string, got {type(name).__name__}")
        angles = float_array("arm_angle_rad", arm_angle_rad, 1)
        m = angles.shape[0]
        self._core = _rfcore.Airframe(
            name,
            angles,
            float_array("arm_length_m", arm_length_m, 1),
            _spin_signs(spin),
            float_array("max_thrust_n", max_thrust_n, 1),
            np.zeros(m) if min_thrust_n is None else float_array("min_thrust_n", min_thrust_n, 1),
            np.ones(m) if efficiency is None else float_array("efficiency", efficiency, 1),
            real("mass_kg", mass_kg),
            float_array("inertia_kg_m2", inertia_kg_m2, 1),
            real("drag_torque_ratio_m", drag_torque_ratio_m),
            real("gravity_m_s2", gravity_m_s2),
        )

    @classmethod
    def _wrap(cls, core: _rfcore.Airframe) -> Airframe:
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
    def load(cls, spec: str, relative_to: str | PathLike[str] | None = None) -> Airframe:
        """A preset name, or a path to an airframe TOML file (a ``.toml`` name or an existing
        file; relative paths resolve against ``relative_to`` when given)."""
        if not isinstance(spec, str):
            raise TypeError(f"airframe: expected a preset name or a TOML path, got {type(spec).__name__}")
        path = Path(spec) if relative_to is None else Path(relative_to) / spec
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

    def to_toml(self) -> str:
        """The airframe as TOML in the preset schema; :meth:`from_toml_str` reads it back exactly."""
        return self._core.to_toml_str()

    def effectiveness_matrix(self) -> FloatArray:
        """B_f of Du eq. (5), 4 x m: rows thrust (N/N), roll and pitch (m), yaw (m); columns
        scaled by the rotor efficiencies."""
        return self._core.effectiveness_matrix()

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


def require_airframe(value: Any) -> Airframe:
    if not isinstance(value, Airframe):
        raise TypeError(f"airframe: expected rotorfault.Airframe, got {type(value).__name__}")
    return value


def rotor_labels(rotors: Sequence[int]) -> str:
    """``(1, 3)`` -> ``"1, 3"``; ``()`` -> ``"none"``."""
    return ", ".join(str(r) for r in rotors) if rotors else "none"

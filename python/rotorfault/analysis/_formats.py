"""Other tools' airframe formats: PX4 parameter files, RotorPy parameter dicts, ArduPilot frames.

Conventions (converted here, once):

- **PX4** (control allocation, ``CA_ROTORn_*``, n from 0): body FRD like ours. Rotor n's thrust
  ``CT_n u^2`` (u in [0, 1]) pushes along the normalised axis ``(AX, AY, AZ)`` (default
  ``(0, 0, -1)``) at ``(PX, PY, PZ)``; its moment is ``CT (p x a) - CT KM a`` with ``KM > 0`` for a
  rotor spinning anticlockwise seen from above. So ``max_thrust_n = CT``, our ``w k_mu = KM``
  (``spin = "ccw"`` when KM >= 0, ``rotor_drag_torque_ratio_m = |KM|``); a bit set in
  ``CA_R_REV`` makes the rotor reversible (``min_thrust_n = -CT``). Missing rotor parameters take
  PX4's defaults (``CT`` 6.5, ``KM`` 0.05, axis ``(0, 0, -1)``, position 0). Rotor n is our rotor
  n + 1.
- **RotorPy** (``quad_params``): body FLU (z up), rotors push along body +z; the yaw moment of
  rotor i is ``(k_m / k_eta) rotor_directions[i] f_i`` about body +z (its ``f_to_TM``), so
  ``rotor_directions = +1`` is a rotor turning clockwise seen from above (our ``w = -1``).
  Positions convert as ``(x, -y, -z)``; ``max_thrust_n = k_eta rotor_speed_max^2``,
  ``min_thrust_n = k_eta rotor_speed_min^2``, ``k_mu = k_m / k_eta``; RotorPy's g is 9.81.
- **ArduPilot** (``AP_MotorsMatrix::setup_*_matrix``): motor angles from the nose, positive
  towards the right (our arm angle), yaw factor +1 (``AP_MOTORS_MATRIX_YAW_FACTOR_CCW``) for a
  motor turning anticlockwise seen from above (our ``w``); motor numbers as ArduPilot's
  ``add_motor`` numbers them (the table below).
"""

from __future__ import annotations

import math
import re
from typing import Any

import numpy as np

from .._util.convert import float_array, real
from .._util.numeric import scaled_norm

#: Used for PX4 imports without ``inertia_kg_m2`` (PX4 keeps no inertia): the ACAI, failure
#: tables, hover margins and ``certify`` do not depend on it; simulations do.
PLACEHOLDER_INERTIA_KG_M2 = (0.01, 0.01, 0.02)

_PX4_DEFAULTS = {"PX": 0.0, "PY": 0.0, "PZ": 0.0, "AX": 0.0, "AY": 0.0, "AZ": -1.0, "CT": 6.5, "KM": 0.05}
_MASS_COMMENT = "# rotorfault mass_kg "
#: A PX4 parameter name (``param_t`` names are at most 16 characters).
_PX4_NAME = re.compile(r"[A-Za-z0-9_]{1,16}")


def parse_px4_params(text: str, origin: str) -> dict[str, float]:
    """``NAME -> value`` from QGroundControl's format (``vehicle component NAME value type`` per
    line, tab or space separated; ``#`` comments). A ``# rotorfault mass_kg X`` comment (written by
    :func:`to_px4_params`) is returned as ``_MASS_KG``."""
    params: dict[str, float] = {}
    # Lines end at \n only (str.splitlines would also break at form feeds and Unicode separators,
    # which a line may then not hold: they are refused below as part of a malformed line).
    for number, raw in enumerate(text.split("\n"), start=1):
        line = raw.strip(" \t\r")
        if line.startswith(_MASS_COMMENT):
            if "_MASS_KG" in params:
                raise ValueError(f"{origin}: line {number}: a second '{_MASS_COMMENT.strip()}' line")
            params["_MASS_KG"] = _number(line[len(_MASS_COMMENT):].strip(), origin, number)
            continue
        if not line or line.startswith("#"):
            continue
        fields = line.split()
        if len(fields) != 5 or any(not f.isascii() or not f.isprintable() for f in fields):
            raise ValueError(
                f"{origin}: line {number}: expected 'vehicle component NAME value type' "
                f"(QGroundControl's parameter file), got {raw!r}"
            )
        name = fields[2]
        if not _PX4_NAME.fullmatch(name):
            raise ValueError(f"{origin}: line {number}: {name!r} is not a PX4 parameter name (letters, digits and _, at most 16)")
        if name in params:
            raise ValueError(f"{origin}: line {number}: parameter {name} is given twice")
        for field, what in ((fields[0], "vehicle id"), (fields[1], "component id"), (fields[4], "type")):
            if not field.isdigit():
                raise ValueError(f"{origin}: line {number}: the {what} must be a whole number, got {field!r}")
        params[name] = _number(fields[3], origin, number)
    return params


def _number(text: str, origin: str, line: int) -> float:
    try:
        value = float(text)
    except ValueError:
        raise ValueError(f"{origin}: line {line}: value must be a number, got {text!r}") from None
    if not math.isfinite(value):
        raise ValueError(f"{origin}: line {line}: value must be finite, got {text!r}")
    return value


def px4_columns(
    params: dict[str, float], origin: str, *, mass_kg: float | None, gravity_m_s2: float
) -> dict[str, Any]:
    """Keyword arguments of :meth:`Airframe.from_rotors` from PX4 parameters (see the module)."""
    if "CA_ROTOR_COUNT" not in params:
        raise ValueError(f"{origin}: CA_ROTOR_COUNT: missing (not a PX4 multicopter parameter file?)")
    count = params["CA_ROTOR_COUNT"]
    if count != int(count) or not 1 <= count <= 12:
        raise ValueError(f"{origin}: CA_ROTOR_COUNT: must be an integer in 1..12, got {count:g}")
    m = int(count)
    get = {key: np.array([params.get(f"CA_ROTOR{n}_{key}", d) for n in range(m)]) for key, d in _PX4_DEFAULTS.items()}
    axis = np.stack([get["AX"], get["AY"], get["AZ"]], axis=1)
    norms = scaled_norm(axis, axis=1)
    for n, norm in enumerate(norms):
        if norm == 0.0:
            raise ValueError(f"{origin}: CA_ROTOR{n}_AX/AY/AZ: the thrust axis of rotor {n + 1} is zero")
    axis = axis / norms[:, None]  # PX4 uses the direction only
    reversible = int(params.get("CA_R_REV", 0.0))
    ct = get["CT"]
    km = get["KM"]
    if mass_kg is None:
        if "_MASS_KG" in params:
            mass_kg = params["_MASS_KG"]
        elif "MPC_THR_HOVER" in params:
            # PX4's normalised collective thrust: 1 is every rotor at CT along body -z.
            upward = float(np.sum(ct * -axis[:, 2]))
            mass_kg = params["MPC_THR_HOVER"] * upward / gravity_m_s2 if gravity_m_s2 > 0 else math.nan
            if not (math.isfinite(mass_kg) and mass_kg > 0 and abs(mass_kg) >= 1e-300):
                raise ValueError(
                    f"{origin}: mass_kg: cannot be inferred: MPC_THR_HOVER = {params['MPC_THR_HOVER']:g} of the full upward "
                    f"thrust {upward:g} N (sum of CT x -AZ; zero for a frame whose rotors push every way, such as an "
                    f"omnicopter) gives {mass_kg:g} kg; pass mass_kg= (CLI: --mass)"
                )
        else:
            raise ValueError(
                f"{origin}: mass_kg: PX4 parameters carry no vehicle mass; pass mass_kg= or keep "
                "MPC_THR_HOVER in the file"
            )
    k = np.abs(km)
    return {
        "position_m": np.stack([get["PX"], get["PY"], get["PZ"]], axis=1),
        "thrust_axis": axis,
        "spin": ["ccw" if value >= 0.0 else "cw" for value in km],
        "rotor_drag_torque_ratio_m": k,
        "drag_torque_ratio_m": float(k[0]),
        "max_thrust_n": ct,
        "min_thrust_n": np.array([-c if reversible >> n & 1 else 0.0 for n, c in enumerate(ct)]),
        "mass_kg": mass_kg,
    }


def to_px4_params(airframe: Any, *, vehicle_id: int, component_id: int) -> str:
    """QGroundControl's parameter file for an airframe (see :meth:`Airframe.to_px4_params`)."""
    for field, value in (("vehicle_id", vehicle_id), ("component_id", component_id)):
        if isinstance(value, bool) or not isinstance(value, int):
            raise TypeError(f"{field}: expected an integer (MAVLink id), got {type(value).__name__}")
        if not 0 <= value <= 255:
            raise ValueError(f"{field}: a MAVLink id lies in 0..255, got {value}")
    if np.any(airframe.efficiency != 1.0):
        raise ValueError("efficiency: PX4 parameters have no rotor efficiency; export the healthy airframe")
    lo, hi = airframe.min_thrust_n, airframe.max_thrust_n
    bad = [i + 1 for i in range(airframe.rotor_count) if lo[i] not in (0.0, -hi[i])]
    if bad:
        raise ValueError(f"min_thrust_n: PX4 rotors go from 0 (or -CT when reversible) to CT; rotors {bad} do not")
    w = airframe.spin_sign * airframe.rotor_drag_torque_ratio_m
    lines = [
        f"# Onboard parameters for {airframe.name}, written by rotorfault",
        "#",
        f"{_MASS_COMMENT}{airframe.mass_kg!r}",
        "# Vehicle-Id Component-Id Name Value Type",
    ]

    def put(name: str, value: float, kind: int = 9) -> None:
        text = repr(float(value)) if kind == 9 else str(int(value))
        lines.append(f"{vehicle_id}\t{component_id}\t{name}\t{text}\t{kind}")

    put("CA_ROTOR_COUNT", airframe.rotor_count, 6)
    for n in range(airframe.rotor_count):
        p, a = airframe.position_m[n], airframe.thrust_axis[n]
        for key, value in zip(("PX", "PY", "PZ", "AX", "AY", "AZ"), (*p, *a)):
            put(f"CA_ROTOR{n}_{key}", value)
        put(f"CA_ROTOR{n}_CT", hi[n])
        put(f"CA_ROTOR{n}_KM", w[n])
    put("CA_R_REV", sum(1 << n for n in range(airframe.rotor_count) if lo[n] < 0.0), 6)
    upward = float(np.sum(hi * -airframe.thrust_axis[:, 2]))
    if upward > 0.0:
        # Without upward thrust (an omnicopter's rotors cancel) PX4's hover thrust means nothing:
        # the mass comment above carries the mass alone.
        put("MPC_THR_HOVER", airframe.hover_thrust_n / upward)
    return "\n".join(lines) + "\n"


def rotorpy_columns(quad_params: dict[str, Any]) -> dict[str, Any]:
    """Keyword arguments of :meth:`Airframe.from_rotors` from RotorPy's ``quad_params``."""
    if not isinstance(quad_params, dict):
        raise TypeError(f"quad_params: expected RotorPy's parameter dict, got {type(quad_params).__name__}")
    required = ("mass", "Ixx", "Iyy", "Izz", "rotor_pos", "rotor_directions", "k_eta", "k_m", "rotor_speed_max")
    missing = [key for key in required if key not in quad_params]
    if missing:
        raise ValueError(f"quad_params: missing {', '.join(missing)}")
    rotor_pos = quad_params["rotor_pos"]
    if not isinstance(rotor_pos, dict):
        raise TypeError(f"quad_params['rotor_pos']: expected a dict of rotor positions, got {type(rotor_pos).__name__}")
    flu = np.array([float_array(f"quad_params['rotor_pos'][{k!r}]", v, 1) for k, v in rotor_pos.items()], dtype=float)
    if flu.ndim != 2 or flu.shape[1] != 3:
        raise ValueError(f"quad_params['rotor_pos']: each position must have 3 entries, got shape {flu.shape}")
    directions = float_array("quad_params['rotor_directions']", quad_params["rotor_directions"], 1)
    m = flu.shape[0]

    def number(key: str, default: float | None = None) -> float:
        return real(f"quad_params[{key!r}]", quad_params[key] if default is None else quad_params.get(key, default))

    k_eta, k_m = number("k_eta"), number("k_m")
    if k_eta <= 0.0:
        raise ValueError(f"quad_params['k_eta']: must be > 0, got {k_eta}")
    speed_max = number("rotor_speed_max")
    speed_min = number("rotor_speed_min", 0.0)
    return {
        "position_m": flu * np.array([1.0, -1.0, -1.0]),
        "spin": -directions,  # +1 in RotorPy: positive yaw moment about z up, a clockwise rotor
        # Products, not powers: an absurd speed gives an infinite thrust (refused by name), not OverflowError.
        "max_thrust_n": np.full(m, k_eta * speed_max * speed_max),
        "min_thrust_n": np.full(m, k_eta * speed_min * speed_min),
        "mass_kg": number("mass"),
        "inertia_kg_m2": [number(k) for k in ("Ixx", "Iyy", "Izz")],
        "drag_torque_ratio_m": k_m / k_eta,
        "gravity_m_s2": 9.81,
    }


def to_rotorpy(airframe: Any) -> dict[str, Any]:
    """RotorPy's ``quad_params`` for an airframe with upright rotors and one thrust range."""
    if not np.all(airframe.thrust_axis == np.array([0.0, 0.0, -1.0])):
        raise ValueError("thrust_axis: RotorPy's quad_params model upright rotors only")
    hi, lo, k = airframe.max_thrust_n, airframe.min_thrust_n, airframe.rotor_drag_torque_ratio_m
    if np.ptp(hi) != 0.0 or np.ptp(lo) != 0.0 or np.ptp(k) != 0.0 or lo[0] < 0.0:
        raise ValueError("max_thrust_n, min_thrust_n: RotorPy has one rotor model (equal, non-negative bounds and k_mu)")
    k_eta = 1.0  # RotorPy's speeds are then sqrt(thrust): k_eta only fixes the unit of speed
    jx, jy, jz = (float(v) for v in airframe.inertia_kg_m2)
    return {
        "mass": airframe.mass_kg,
        "Ixx": jx, "Iyy": jy, "Izz": jz, "Ixy": 0.0, "Iyz": 0.0, "Ixz": 0.0,
        "num_rotors": airframe.rotor_count,
        "rotor_pos": {f"r{i + 1}": p * np.array([1.0, -1.0, -1.0]) for i, p in enumerate(airframe.position_m)},
        "rotor_directions": -airframe.spin_sign,
        "k_eta": k_eta,
        "k_m": float(k[0]) * k_eta,
        "rotor_speed_min": math.sqrt(lo[0] / k_eta),
        "rotor_speed_max": math.sqrt(hi[0] / k_eta),
    }


# ArduPilot AP_MotorsMatrix (libraries/AP_Motors/AP_MotorsMatrix.cpp): per frame, the motors in
# ArduPilot's numbering as (angle from the nose towards the right, degrees; yaw factor, +1 = CCW).
# Checked entry by entry against the add_motor() tables of AP_MotorsMatrix::setup_motors (quad
# plus/X/H) and the SITL frame tables (libraries/SITL/SIM_Frame.cpp: hexa, hexax, octa), where
# AP_MOTORS_MATRIX_YAW_FACTOR_CCW is +1; octa-X is octa-plus turned by -22.5 degrees there.
ARDUPILOT_FRAMES: dict[tuple[int, int], tuple[str, list[tuple[float, int]]]] = {
    (1, 0): ("quad-plus", [(90, 1), (-90, 1), (0, -1), (180, -1)]),
    (1, 1): ("quad-x", [(45, 1), (-135, 1), (-45, -1), (135, -1)]),
    (1, 3): ("quad-h", [(45, -1), (-135, -1), (-45, 1), (135, 1)]),
    (2, 0): ("hexa-plus", [(0, -1), (180, 1), (-120, -1), (60, 1), (-60, 1), (120, -1)]),
    (2, 1): ("hexa-x", [(90, -1), (-90, 1), (-30, -1), (150, 1), (30, 1), (-150, -1)]),
    (3, 0): ("octa-plus", [(0, -1), (180, -1), (45, 1), (135, 1), (-45, 1), (-135, 1), (-90, -1), (90, -1)]),
    (3, 1): ("octa-x", [(22.5, -1), (-157.5, -1), (67.5, 1), (157.5, 1), (-22.5, 1), (-112.5, 1), (-67.5, -1), (112.5, -1)]),
}
_CLASSES = {"quad": 1, "hexa": 2, "octa": 3}
_TYPES = {"plus": 0, "+": 0, "x": 1, "h": 3}


def ardupilot_frame(frame_class: Any, frame_type: Any) -> tuple[list[float], list[float], str]:
    """Arm angles (degrees), spin signs and a label of an ArduPilot standard frame."""
    def code(field: str, value: Any, names: dict[str, int]) -> int:
        if isinstance(value, str):
            if value.lower() not in names:
                raise ValueError(f"{field}: must be one of {', '.join(names)} (or ArduPilot's number), got {value!r}")
            return names[value.lower()]
        if isinstance(value, bool) or not isinstance(value, int):
            raise TypeError(f"{field}: expected ArduPilot's number or a name, got {type(value).__name__}")
        return value

    key = (code("frame_class", frame_class, _CLASSES), code("frame_type", frame_type, _TYPES))
    if key not in ARDUPILOT_FRAMES:
        known = ", ".join(f"{c}/{t} ({label})" for (c, t), (label, _) in ARDUPILOT_FRAMES.items())
        raise ValueError(f"frame_class, frame_type: {key[0]}/{key[1]} is not supported; supported: {known}")
    label, motors = ARDUPILOT_FRAMES[key]
    return [float(angle % 360.0) for angle, _ in motors], [float(yaw) for _, yaw in motors], f"ardupilot-{label}"

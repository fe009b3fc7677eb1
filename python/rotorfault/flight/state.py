"""The vehicle state: position and velocity in the world frame (NED), attitude, body rates.

Frames: world NED (north, east, down; altitude is ``-position[2]``), body FRD.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import numpy.typing as npt

from .._util.convert import FloatArray, float_array


def _vector3(field_name: str, value: Any) -> tuple[float, float, float]:
    v = float_array(field_name, value, 1)
    if v.shape != (3,):
        raise ValueError(f"{field_name}: expected 3 entries, got {v.shape[0]}")
    if not np.all(np.isfinite(v)):
        raise ValueError(f"{field_name}: must be finite")
    return (float(v[0]), float(v[1]), float(v[2]))


class State:
    """A vehicle state: ``position`` (m, world NED), ``velocity`` (m/s, world), attitude as a unit
    ``quaternion`` (w, x, y, z; body to world) or ``euler`` (roll, pitch, yaw, rad, Z-Y-X), and
    ``omega`` (body rates, rad/s). Omitted fields are zero / level.

    Examples:

        >>> import rotorfault as rf
        >>> state = rf.State(position=(0, 0, -2), euler=(0.1, 0, 0))
        >>> state.position, [round(q, 6) for q in state.quaternion]
        ((0.0, 0.0, -2.0), [0.99875, 0.049979, 0.0, 0.0])
    """

    __slots__ = ("position", "velocity", "quaternion", "omega")

    def __init__(
        self,
        position: npt.ArrayLike = (0.0, 0.0, 0.0),
        velocity: npt.ArrayLike = (0.0, 0.0, 0.0),
        quaternion: npt.ArrayLike | None = None,
        euler: npt.ArrayLike | None = None,
        omega: npt.ArrayLike = (0.0, 0.0, 0.0),
    ) -> None:
        self.position = _vector3("position", position)
        self.velocity = _vector3("velocity", velocity)
        self.omega = _vector3("omega", omega)
        if quaternion is not None and euler is not None:
            raise ValueError("quaternion, euler: give at most one attitude")
        if euler is not None:
            roll, pitch, yaw = _vector3("euler", euler)
            cr, sr = math.cos(roll / 2), math.sin(roll / 2)
            cp, sp = math.cos(pitch / 2), math.sin(pitch / 2)
            cy, sy = math.cos(yaw / 2), math.sin(yaw / 2)
            q = (
                cr * cp * cy + sr * sp * sy,
                sr * cp * cy - cr * sp * sy,
                cr * sp * cy + sr * cp * sy,
                cr * cp * sy - sr * sp * cy,
            )
        elif quaternion is not None:
            arr = float_array("quaternion", quaternion, 1)
            if arr.shape != (4,) or not np.all(np.isfinite(arr)):
                raise ValueError("quaternion: expected 4 finite entries (w, x, y, z)")
            # math.hypot: no overflow of the squares (NumPy 2's norm warned on an entry of 1e300).
            norm = math.hypot(*(float(v) for v in arr))
            if abs(norm - 1.0) > 1e-6:
                raise ValueError(f"quaternion: must have unit norm (within 1e-6), got norm {norm}")
            q = tuple(float(v) / norm for v in arr)  # type: ignore[assignment]
        else:
            q = (1.0, 0.0, 0.0, 0.0)
        self.quaternion: tuple[float, float, float, float] = q

    @classmethod
    def from_vector(cls, x: npt.ArrayLike) -> State:
        """From the 12-element state vector ``[p, v, roll, pitch, yaw, omega]``."""
        v = float_array("x", x, 1)
        if v.shape != (12,):
            raise ValueError(f"x: expected 12 entries, got {v.shape[0]}")
        return cls(position=v[0:3], velocity=v[3:6], euler=v[6:9], omega=v[9:12])

    def vector(self) -> FloatArray:
        """The 12-element state vector the controllers use."""
        w, x, y, z = self.quaternion
        roll = math.atan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y))
        pitch = math.asin(max(-1.0, min(1.0, 2 * (w * y - z * x))))
        yaw = math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
        return np.array([*self.position, *self.velocity, roll, pitch, yaw, *self.omega])

    def _packed(self) -> list[float]:
        return [*self.position, *self.velocity, *self.quaternion, *self.omega]

    def __repr__(self) -> str:
        return f"State(position={self.position}, velocity={self.velocity}, quaternion={self.quaternion}, omega={self.omega})"


__all__ = ["State"]

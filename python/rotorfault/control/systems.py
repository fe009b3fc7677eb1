"""The linear models of rotorfault as python-control systems.

:class:`LinearModel` is a ``control.StateSpace`` (every python-control function takes it: ``lqr``,
``feedback``, ``interconnect``, ``step_response``, ``bode``...) with named signals: the states
``x, y, z, u, v, w, phi, theta, psi, p, q, r`` (:data:`~rotorfault.control.linear.STATE_NAMES`:
NED position (m) and velocity (m/s), Z-Y-X Euler angles (rad), body rates (rad/s)), the
outputs the same (``y = x``), the inputs ``thrust_<i>`` (N, fixed pitch) or ``omega_<i>`` and
``alpha_<i>`` (speed in the preset's unit and pitch in rad, variable pitch), ``i`` the rotor
number. It also carries the operating point it was taken about (``x_trim``, ``u_trim``: what a
:class:`~rotorfault.control.LinearFeedback` needs) and, when it keeps only some command channels
(a VPP with a failed propeller), which ones (``command_columns``).

:func:`lanzon_plant` names the signals of Lanzon et al.'s plant after feedback linearisation.

This module imports python-control, so the package imports it only when a model is built
(``import rotorfault`` stays light).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import control as ct  # type: ignore[import-untyped]
import numpy as np
import numpy.typing as npt

from .._util.convert import FloatArray, float_array, frozen_array
from .._util.deprecation import renamed_attribute
from .linear import STATE_LABELS, STATE_NAMES


class LinearModel(ct.StateSpace):  # type: ignore[misc]
    """``dx/dt ~ A (x - x_trim) + B (u - u_trim)``, ``y = x``: a python-control ``StateSpace``
    (continuous) with named states, inputs and outputs (module notes) and its operating point.

    ``x_trim`` (12 states) and ``u_trim`` (every command channel of the simulator) are the point
    it was taken about; ``command_columns``: the index in the simulator's command vector of each
    input (all channels, or the healthy ones of a VPP model; the first it moves when it moves
    several); ``input_map`` (channels x inputs): how an input moves the command vector,
    ``u = u_trim + input_map (v - v_trim)`` (one 1 per column, several for a shared input such as
    Wang's ``omega_2=omega_4``; default: input ``j`` moves channel ``command_columns[j]``);
    ``state_descriptions``: what each state is (``"yaw rate r"``), used in the design checks'
    messages.

    Examples:

        >>> import control as ct
        >>> import rotorfault as rf
        >>> sim = rf.Simulator(rf.Airframe.preset("quad-x"))
        >>> model = rf.linearize(sim, rf.hover_trim(sim))
        >>> model.state_labels[:3], model.u_trim.round(4).tolist()
        (['x', 'y', 'z'], [3.7607, 3.7608, 3.7608, 3.7608])
        >>> isinstance(model, ct.StateSpace)
        True
    """

    def __init__(
        self,
        a: npt.ArrayLike,
        b: npt.ArrayLike,
        *,
        inputs: Sequence[str],
        x_trim: npt.ArrayLike,
        u_trim: npt.ArrayLike,
        command_columns: Sequence[int],
        name: str,
        input_map: npt.ArrayLike | None = None,
        states: Sequence[str] = STATE_NAMES,
        state_descriptions: Sequence[str] = STATE_LABELS,
    ) -> None:
        am = float_array("a", a, 2)
        bm = float_array("b", b, 2)
        n, m = bm.shape
        # Shapes named here, before python-control's own (unnamed) dimension errors.
        if am.shape != (n, n) or n == 0:
            raise ValueError(f"a: expected a square matrix with as many rows as b ({n}), got shape {am.shape}")
        for field, labels, size in (("states", states, n), ("state_descriptions", state_descriptions, n), ("inputs", inputs, m),
                                    ("command_columns", command_columns, m)):
            if isinstance(labels, (str, bytes)) or len(labels) != size:
                raise ValueError(f"{field}: expected {size} entries (the shape of b is {bm.shape})")
        super().__init__(am, bm, np.eye(n), np.zeros((n, m)), states=list(states), inputs=list(inputs),
                         outputs=list(states), name=name)
        self.x_trim: FloatArray = frozen_array("x_trim", x_trim, 1)
        if self.x_trim.shape != (n,):
            raise ValueError(f"x_trim: expected {n} states, got {self.x_trim.shape[0]}")
        self.u_trim: FloatArray = frozen_array("u_trim", u_trim, 1)
        self.command_columns: tuple[int, ...] = tuple(int(c) for c in command_columns)
        channels = self.u_trim.shape[0]
        outside = [c for c in self.command_columns if not 0 <= c < channels]
        if outside:  # an IndexError in the input map below otherwise (hostile harness: u_trim=[])
            raise ValueError(f"command_columns: each must index one of u_trim's {channels} channels, got {outside[0]}")
        if input_map is None:
            selection = np.zeros((self.u_trim.shape[0], m))
            selection[list(self.command_columns), list(range(m))] = 1.0
            input_map = selection
        self.input_map: FloatArray = frozen_array("input_map", input_map, 2)
        if self.input_map.shape != (self.u_trim.shape[0], m):
            raise ValueError(f"input_map: expected {self.u_trim.shape[0]} x {m} (channels x inputs), got {self.input_map.shape}")
        self.state_descriptions: tuple[str, ...] = tuple(state_descriptions)

    # The names of ``rotorfault.vpp.VppLinearization``, which this replaces, for one release.
    a = renamed_attribute("a", "A")
    b = renamed_attribute("b", "B")
    inputs = renamed_attribute("inputs", "input_labels")
    columns = renamed_attribute("columns", "command_columns")


def input_names(command_count: int, rotor_count: int) -> list[str]:
    """The python-control input names of a simulator's command channels: ``thrust_<i>`` for
    fixed pitch, ``omega_<i>`` and ``alpha_<i>`` (interleaved) for variable pitch."""
    if command_count == 2 * rotor_count:
        return [f"{'alpha' if j % 2 else 'omega'}_{j // 2 + 1}" for j in range(command_count)]
    return [f"thrust_{j + 1}" for j in range(command_count)]


#: Lanzon's plant after feedback linearisation (eq. (26)-(27)): states in hat coordinates
#: (``dr = r - r0``, rad and rad/s, the paper's z-up frame), inputs ``u = [u_f - m g, tau_q,
#: tau_r - m g d]`` (N, N m), outputs ``[phi, theta, dr]``.
LANZON_STATES = ("phi", "theta", "p", "q", "dr")
LANZON_INPUTS = ("du_f", "tau_q", "dtau_r")
LANZON_OUTPUTS = ("phi", "theta", "dr")


def lanzon_plant(vehicle: Any) -> ct.StateSpace:
    """``vehicle.plant()`` (:class:`~rotorfault.control.lanzon.LanzonVehicle`: ``(A_r, B_r)`` of
    eq. (26), outputs of (27)), whose signals are named :data:`LANZON_STATES`,
    :data:`LANZON_INPUTS` and :data:`LANZON_OUTPUTS` (the loop-shaping design names its weight,
    controller and shaped plant after them).

    Examples:

        >>> from rotorfault.control import lanzon_plant
        >>> from rotorfault.control.lanzon import LanzonVehicle
        >>> plant = lanzon_plant(LanzonVehicle())
        >>> plant.state_labels, plant.input_labels, plant.output_labels
        (['phi', 'theta', 'p', 'q', 'dr'], ['du_f', 'tau_q', 'dtau_r'], ['phi', 'theta', 'dr'])
    """
    if not callable(getattr(vehicle, "plant", None)):
        raise TypeError(f"vehicle: expected a rotorfault.control.lanzon.LanzonVehicle, got {type(vehicle).__name__}")
    plant: ct.StateSpace = vehicle.plant()
    return plant


__all__ = ["LANZON_INPUTS", "LANZON_OUTPUTS", "LANZON_STATES", "LinearModel", "input_names", "lanzon_plant"]

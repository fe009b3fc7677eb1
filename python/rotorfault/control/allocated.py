"""A virtual-control law followed by constrained allocation, run in Rust."""

from __future__ import annotations

import numpy as np

from .. import _rfcore
from .._util.convert import FloatArray
from ..allocation import Allocator
from .linear import LinearFeedback, Lti, OpenLoop


class Allocated:
    """A virtual-control law followed by constrained allocation, all in Rust: ``law``
    (:class:`LinearFeedback`, :class:`Lti` or :class:`OpenLoop`) writes the virtual control
    (``allocator.virtual_dimension`` entries, e.g. thrust N and roll/pitch/yaw torques N m), and
    the active-set solver of ``allocator`` (a :class:`rotorfault.allocation.Allocator`) turns it
    into rotor thrusts within their bounds, warm-started from the previous control step.

    The allocator's matrix is what the controller believes; the simulator's rotor efficiency is
    what happens. Pass an allocator built from a degraded airframe to model a known fault.

    Examples:

        >>> import rotorfault as rf
        >>> quad = rf.Airframe.preset("quad-x")
        >>> sim = rf.Simulator(quad)
        >>> weight_n = quad.mass_kg * quad.gravity_m_s2
        >>> hold = rf.Allocated(rf.OpenLoop([0.0], [[weight_n, 0, 0, 0]]), rf.Allocator(quad))
        >>> run = sim.run(rf.State(position=(0, 0, -1)), 0.5, controller=hold)
        >>> run.rotor_thrust[-1].round(4).tolist()
        [3.7608, 3.7608, 3.7607, 3.7608]
    """

    def __init__(self, law: OpenLoop | LinearFeedback | Lti, allocator: Allocator) -> None:
        if not isinstance(law, (OpenLoop, LinearFeedback, Lti)):
            raise TypeError(f"law: expected LinearFeedback, Lti or OpenLoop, got {type(law).__name__}")
        if not isinstance(allocator, Allocator):
            raise TypeError(f"allocator: expected a rotorfault.allocation.Allocator, got {type(allocator).__name__}")
        self.law = law
        self.allocator = allocator
        # The law's trim has one entry per output: it must match the allocation's rows. (Building
        # the core here would need the simulator's period, which a discrete Lti insists on.)
        outputs = np.asarray(law.u_trim).shape[0]
        if outputs != allocator.virtual_dimension:
            raise ValueError(
                f"law: writes {outputs} outputs, the allocation matrix has {allocator.virtual_dimension} rows"
            )

    @property
    def u_trim(self) -> FloatArray:
        """The rotor commands for the law's trim virtual control: where the actuators start."""
        trim = np.asarray(self.law.u_trim, dtype=np.float64)
        commands: FloatArray = self.allocator.allocate(trim).commands
        return commands

    def core(self, dt_s: float) -> _rfcore.Allocated:
        return _rfcore.Allocated(self.law.core(dt_s), self.allocator._core)


__all__ = ["Allocated"]

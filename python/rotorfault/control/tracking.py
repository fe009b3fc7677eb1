"""State feedback on a moving reference with a saturated error (reference shaping):
``u = u_trim - K sat(x - x_ref(t))``, run in Rust (``crates/rfcore/src/control/tracking.rs``).

A gain designed about hover answers a 5 m step with commands far outside the linear model (Wang's
scenario 2 is lost by a plain LQR); clipping each error component to ``error_limit`` turns a
step into a bounded approach. The reference is a table of 12-state rows at non-decreasing
``times_s``: linear between distinct times, held outside, and a repeated time is a jump (the
later row holds from then), so one table holds setpoint steps and a sampled path alike.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from .. import _rfcore
from .._util.convert import FloatArray, float_array, frozen_array
from .linear import STATE_DIM, LinearFeedback


class TrackingFeedback:
    """``u = u_trim - K sat(x - x_ref(t))`` (module docs). ``error_limit``: 12 entries > 0 or
    ``inf`` (no limit); ``None``: no limit anywhere (plain feedback on the reference)."""

    def __init__(
        self,
        gain: npt.ArrayLike,
        u_trim: npt.ArrayLike,
        *,
        times_s: npt.ArrayLike,
        references: npt.ArrayLike,
        error_limit: npt.ArrayLike | None = None,
    ) -> None:
        self.gain = frozen_array("gain", gain, 2)
        self.u_trim = frozen_array("u_trim", u_trim, 1)
        self.times_s = frozen_array("times_s", times_s, 1)
        self.references = frozen_array("references", references, 2)
        limit = np.full(STATE_DIM, math.inf) if error_limit is None else float_array("error_limit", error_limit, 1)
        self.error_limit = frozen_array("error_limit", limit, 1)
        self._core = _rfcore.TrackingFeedback(
            u_trim=self.u_trim, gain=self.gain, times_s=self.times_s, references=self.references, error_limit=self.error_limit,
        )

    @classmethod
    def from_feedback(
        cls,
        feedback: LinearFeedback,
        *,
        times_s: npt.ArrayLike,
        references: npt.ArrayLike,
        error_limit: npt.ArrayLike | None = None,
    ) -> TrackingFeedback:
        """``feedback``'s gain and trim command on a reference table (its ``x_trim`` is unused:
        the references replace it)."""
        if not isinstance(feedback, LinearFeedback):
            raise TypeError(f"feedback: expected a LinearFeedback, got {type(feedback).__name__}")
        return cls(feedback.gain, feedback.u_trim, times_s=times_s, references=references, error_limit=error_limit)

    def reference(self, t_s: float) -> FloatArray:
        """The reference state at ``t_s`` (as the Rust loop sees it)."""
        return np.array(self._core.reference(float(t_s)))

    def core(self, dt_s: float) -> _rfcore.TrackingFeedback:
        return self._core


__all__ = ["TrackingFeedback"]

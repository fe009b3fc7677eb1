"""A number a paper prints beside the one rotorfault computes: the unit of every reproduction
table (the tests, the CLI and the reproduce-all report read the same rows)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

#: ``pass``: within the tolerance of the printed value; ``differs``: not (the note says why).
NumberStatus = Literal["pass", "differs"]


@dataclass(frozen=True)
class PaperNumber:
    """``printed`` (as the paper prints it) beside ``ours``; they agree when
    ``|ours - printed| <= tolerance`` (half a unit in the last printed place, unless stated)."""

    paper: str
    where: str
    quantity: str
    printed: float
    ours: float
    tolerance: float
    note: str = ""

    @property
    def difference(self) -> float:
        return self.ours - self.printed

    @property
    def status(self) -> NumberStatus:
        ok = math.isfinite(self.ours) and abs(self.difference) <= self.tolerance
        return "pass" if ok else "differs"

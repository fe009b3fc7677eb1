"""A number a paper prints beside the one rotorfault computes: the unit of every reproduction
table (the tests, the CLI and the reproduce-all report read the same rows)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from collections.abc import Sequence
from typing import Literal

from .._util.convert import real
from .._util.tables import Records

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

    def __post_init__(self) -> None:
        for name in ("paper", "where", "quantity", "note"):
            if not isinstance(getattr(self, name), str):
                raise TypeError(f"{name}: expected a string, got {type(getattr(self, name)).__name__}")
        for name in ("printed", "ours", "tolerance"):
            object.__setattr__(self, name, real(name, getattr(self, name)))
        # ``ours`` may be anything a computation gave (a NaN or an infinity reads "differs").
        if not math.isfinite(self.printed):
            raise ValueError(f"printed: must be finite (a number the paper prints), got {self.printed}")
        if not (math.isfinite(self.tolerance) and self.tolerance >= 0.0):
            raise ValueError(f"tolerance: must be >= 0 and finite, got {self.tolerance}")

    @property
    def difference(self) -> float:
        return self.ours - self.printed

    @property
    def status(self) -> NumberStatus:
        ok = math.isfinite(self.ours) and abs(self.difference) <= self.tolerance
        return "pass" if ok else "differs"


def number_rows(numbers: Sequence[PaperNumber]) -> Records:
    """Printed numbers as records (a sequence of dicts with ``to_arrow()`` and ``to_pandas()``):
    one per number, with the difference and the status."""
    columns = [("paper", "string"), ("where", "string"), ("quantity", "string"), ("printed", "float64"), ("ours", "float64"),
               ("difference", "float64"), ("tolerance", "float64"), ("status", "string"), ("note", "string")]
    if isinstance(numbers, (str, bytes)) or not isinstance(numbers, Sequence):
        raise TypeError(f"numbers: expected a sequence of PaperNumber, got {type(numbers).__name__}")
    for i, n in enumerate(numbers):
        if not isinstance(n, PaperNumber):
            raise TypeError(f"numbers[{i}]: expected a PaperNumber, got {type(n).__name__}")
    rows = [
        {"paper": n.paper, "where": n.where, "quantity": n.quantity, "printed": n.printed, "ours": n.ours,
         "difference": n.difference, "tolerance": n.tolerance, "status": n.status, "note": n.note}
        for n in numbers
    ]
    return Records(rows, columns, title="printed numbers beside ours", kind="paper-numbers")

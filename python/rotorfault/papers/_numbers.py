"""A number a paper prints beside the one rotorfault computes: the unit of every reproduction
table (the tests, the CLI and the reproduce-all report read the same rows)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from collections.abc import Sequence
from typing import Literal

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
    rows = [
        {"paper": n.paper, "where": n.where, "quantity": n.quantity, "printed": n.printed, "ours": n.ours,
         "difference": n.difference, "tolerance": n.tolerance, "status": n.status, "note": n.note}
        for n in numbers
    ]
    return Records(rows, columns, title="printed numbers beside ours", kind="paper-numbers")

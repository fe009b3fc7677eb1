"""A number a paper prints beside the one rotorfault computes, and a claim a paper makes beside
what we measure: the units of every reproduction table (the tests, the CLI and the reproduce-all
report read the same rows).

Every row says what it is (:data:`~rotorfault._typing.NumberKind`), and only one kind is scored:

- ``reproduced``: our computation, independent of the printed number, agrees with it (``pass``)
  or not (``differs``). Each scored row has a test that breaks the thing it measures and watches
  it fail (``tests/papers/test_scoreboard.py``);
- ``input``: a parameter we took from the paper (a bound, a coefficient), shown for reference;
- ``consistency``: a check of our own code against the paper's statement (it passes by
  construction if the code is right, so it is not evidence that we reproduce the paper).

A row whose kind is ``None`` has not been classified yet: it is shown, marked so, and not scored.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from collections.abc import Sequence
from typing import Literal, get_args

from .._typing import ClaimStatus, FlightVerdict, NumberKind

from .._util.convert import real
from .._util.tables import Records

#: ``pass``: within the tolerance of the printed value; ``differs``: not (the note says why).
NumberStatus = Literal["pass", "differs"]
#: The kinds of row, in the order the report counts them.
NUMBER_KINDS: tuple[NumberKind, ...] = get_args(NumberKind)
#: What each kind means (the report's legend).
KIND_DESCRIPTIONS: dict[str, str] = {
    "reproduced": "our computation, independent of the printed number: scored",
    "input": "a parameter taken from the paper: shown, not scored",
    "consistency": "a check of our own code against the paper's statement: shown, not scored",
    "not classified": "not yet classified: shown, not scored",
}


@dataclass(frozen=True)
class PaperNumber:
    """``printed`` (as the paper prints it) beside ``ours``; they agree when
    ``|ours - printed| <= tolerance`` (half a unit in the last printed place, unless stated).
    ``kind``: what the row is (module docs); only ``reproduced`` rows are scored.

    Examples:

        >>> from rotorfault.papers import PaperNumber
        >>> row = PaperNumber("Du", "Table 2", "ACAI, rotor 1 failed", printed=0.7221, ours=0.72213, tolerance=1e-4, kind="reproduced")
        >>> row.status, row.scored
        ('pass', True)
    """

    paper: str
    where: str
    quantity: str
    printed: float
    ours: float
    tolerance: float
    note: str = ""
    kind: NumberKind | None = None

    def __post_init__(self) -> None:
        if self.kind is not None and self.kind not in NUMBER_KINDS:
            raise ValueError(f"kind: must be one of {', '.join(NUMBER_KINDS)} or None, got {self.kind!r}")
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

    @property
    def scored(self) -> bool:
        """Counted on the scoreboard: only ``reproduced`` rows."""
        return self.kind == "reproduced"

    @property
    def kind_label(self) -> str:
        return "not classified" if self.kind is None else self.kind


@dataclass(frozen=True)
class PaperClaim:
    """A claim a paper makes about a flight (``claim``, where it makes it: ``where``), beside what
    we measure in our model (``measurement``), the flight's verdict over its whole window
    (:mod:`rotorfault.flight.outcomes`: ``holds``, ``drifts``, ``circles``, ``crashed``,
    ``diverged``), whether the claim holds here (``status``) and why (``reason``)."""

    paper: str
    where: str
    claim: str
    measurement: str
    verdict: FlightVerdict
    status: ClaimStatus
    reason: str

    def __post_init__(self) -> None:
        if self.status not in get_args(ClaimStatus):
            raise ValueError(f"status: must be one of {', '.join(get_args(ClaimStatus))}, got {self.status!r}")
        if self.verdict not in get_args(FlightVerdict):
            raise ValueError(f"verdict: must be one of {', '.join(get_args(FlightVerdict))}, got {self.verdict!r}")


def score(numbers: list[PaperNumber]) -> dict[str, int]:
    """The scoreboard of ``numbers``: ``reproduced`` rows (scored), how many of them pass and
    differ, and how many rows of each other kind are shown beside them."""
    scored = [n for n in numbers if n.scored]
    return {
        "reproduced": len(scored),
        "passed": sum(n.status == "pass" for n in scored),
        "differs": sum(n.status == "differs" for n in scored),
        "input": sum(n.kind == "input" for n in numbers),
        "consistency": sum(n.kind == "consistency" for n in numbers),
        "unclassified": sum(n.kind is None for n in numbers),
    }



def number_rows(numbers: Sequence[PaperNumber]) -> Records:
    """Printed numbers as records (a sequence of dicts with ``to_arrow()`` and ``to_pandas()``):
    one per number, with the difference and the status.

    Examples:

        >>> from rotorfault.papers import PaperNumber, number_rows
        >>> rows = number_rows([PaperNumber("Du", "Table 2", "ACAI", printed=0.7221, ours=0.72213, tolerance=1e-4, kind="reproduced")])
        >>> rows
        <Records printed numbers beside ours: 1 rows x 11 columns>
    """
    columns = [("paper", "string"), ("where", "string"), ("quantity", "string"), ("printed", "float64"), ("ours", "float64"),
               ("difference", "float64"), ("tolerance", "float64"), ("status", "string"), ("kind", "string"), ("scored", "bool"), ("note", "string")]
    if isinstance(numbers, (str, bytes)) or not isinstance(numbers, Sequence):
        raise TypeError(f"numbers: expected a sequence of PaperNumber, got {type(numbers).__name__}")
    for i, n in enumerate(numbers):
        if not isinstance(n, PaperNumber):
            raise TypeError(f"numbers[{i}]: expected a PaperNumber, got {type(n).__name__}")
    rows = [
        {"paper": n.paper, "where": n.where, "quantity": n.quantity, "printed": n.printed, "ours": n.ours,
         "difference": n.difference, "tolerance": n.tolerance, "status": n.status, "kind": n.kind, "scored": n.scored, "note": n.note}
        for n in numbers
    ]
    return Records(rows, columns, title="printed numbers beside ours", kind="paper-numbers")


__all__ = ["KIND_DESCRIPTIONS", "NUMBER_KINDS", "NumberStatus", "PaperClaim", "PaperNumber", "number_rows", "score"]

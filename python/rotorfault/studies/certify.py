"""A controllability certificate for a real vehicle: for every single and double rotor failure,
can it still hover with all axes, only by giving up yaw, or not at all (``rotorfault certify``).

The JSON certificate names the hover classes ``all-axes``, ``give-up-yaw`` and ``no`` and the
ACAI fields ``acai`` and ``acai_give_up_yaw`` (the facet margin); before issue 26 they read
``without-yaw`` and ``acai_without_yaw``."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any, Literal

from .._typing import AcaiFormula
from .._util.convert import count
from .._util.deprecation import renamed_attribute
from .._util.tables import Column, Tabular
from ..allocation.attainable import hover_thrust_margin
from ..analysis.airframe import Airframe, require_airframe, rotor_labels
from ..analysis.acai import GIVE_UP_YAW, acai_label
from ..analysis.controllability import failure_table

#: ``all-axes``: hovers with thrust, roll, pitch and yaw; ``give-up-yaw``: only by giving up yaw
#: (spinning); ``no``: cannot hover.
Hover = Literal["all-axes", "give-up-yaw", "no"]
FAILURE_CLASSES = {"none": 0, "single": 1, "double": 2}
#: The ACAI a certificate reports: the facet margin (how far outside, where hover is infeasible).
FORMULA: AcaiFormula = "facet-margin"


@dataclass(frozen=True)
class CertificateCase:
    failed: tuple[int, ...]
    hover: Hover
    #: The ACAI (N / N m; the facet margin, negative where hover is infeasible) with all four axes
    #: and giving up yaw (-inf: rank deficient).
    acai: float
    acai_give_up_yaw: float
    #: Largest balanced upward thrust over the weight with the axes kept (0 when it cannot hover).
    thrust_to_weight: float
    #: What an allocator must let go (``"lateral-force"`` only for fully actuated frames whose
    #: 6-D wrench is lost; ``None``: nothing helps).
    drop_axes: tuple[str, ...] | None

    #: The name before issue 26, for one release.
    acai_without_yaw = renamed_attribute("acai_without_yaw", "acai_give_up_yaw")


@dataclass(frozen=True)
class Certificate(Tabular):
    """The verdicts of :func:`certify`, one case per failure combination; ``to_arrow()`` /
    ``to_pandas()`` give one row per case, :meth:`to_dict` the JSON document."""

    airframe: str
    rotor_count: int
    fully_actuated: bool
    cases: tuple[CertificateCase, ...]

    def failing(self, required: str) -> list[CertificateCase]:
        """The cases up to the ``required`` class (``none``, ``single``, ``double``) it cannot hover."""
        k = FAILURE_CLASSES[required]
        return [c for c in self.cases if len(c.failed) <= k and c.hover == "no"]

    def _table_columns(self) -> list[Column]:
        acai_ = f"acai_{FORMULA.replace('-', '_')}"
        cases = self.cases
        return [
            ("failed_rotors", "list<int64>", [list(c.failed) for c in cases]),
            ("failed_count", "int64", [len(c.failed) for c in cases]),
            ("hover", "string", [c.hover for c in cases]),
            (acai_, "float64", [c.acai for c in cases]),
            (f"{acai_}_give_up_yaw", "float64", [c.acai_give_up_yaw for c in cases]),
            ("thrust_to_weight", "float64", [c.thrust_to_weight for c in cases]),
            ("drop_axes", "list<string>", [None if c.drop_axes is None else list(c.drop_axes) for c in cases]),
        ]

    def _table_title(self) -> str:
        kind = "fully actuated" if self.fully_actuated else "not fully actuated"
        return f"certificate of {self.airframe}: {self.rotor_count} rotors, {kind}"

    def _table_metadata(self) -> dict[str, Any]:
        return {"kind": "certificate", "airframe": self.airframe, "rotor_count": self.rotor_count, "fully_actuated": self.fully_actuated, "formula": FORMULA}

    def to_dict(self) -> dict[str, Any]:
        out = asdict(self)
        for case in out["cases"]:
            for key in ("acai", "acai_give_up_yaw", "thrust_to_weight"):
                if math.isinf(case[key]):
                    case[key] = None  # JSON has no infinity: rank deficient / undefined
        return out


def certify(airframe: Airframe, *, max_failed: int = 2) -> Certificate:
    """Every combination of up to ``max_failed`` (default 2) fully failed rotors."""
    airframe = require_airframe(airframe)
    max_failed = count("max_failed", max_failed)
    table = failure_table(airframe, max_failed=max_failed, formula=FORMULA)
    full = airframe.is_fully_actuated
    cases = []
    for row in table:
        hover: Hover = "all-axes" if row.controllable else ("give-up-yaw" if row.controllable_give_up_yaw else "no")
        drop: tuple[str, ...] | None
        if hover == "no":
            drop, ratio = None, 0.0
        else:
            drop = () if hover == "all-axes" else ("yaw",)
            if full and not row.controllable_wrench:
                drop = ("lateral-force", *drop)
            margin = hover_thrust_margin(airframe.with_failed_rotors(row.failed), give_up_yaw=hover == "give-up-yaw")
            ratio = margin.thrust_to_weight
        cases.append(CertificateCase(row.failed, hover, row.acai, row.acai_give_up_yaw, ratio, drop))
    return Certificate(airframe.name, airframe.rotor_count, full, tuple(cases))


def rows_for_display(cert: Certificate) -> tuple[list[str], list[list[str]]]:
    acai_ = acai_label(FORMULA)
    headers = ["failed", "hover", acai_, f"{acai_} {GIVE_UP_YAW}", "T/W", "allocator drops"]

    def number(x: float) -> str:
        return "undefined" if math.isinf(x) else f"{x:.4f}"

    rows = [
        [
            rotor_labels(c.failed), c.hover, number(c.acai), number(c.acai_give_up_yaw),
            f"{c.thrust_to_weight:.2f}" if c.hover != "no" else "-",
            "-" if c.drop_axes is None else (", ".join(c.drop_axes) or "nothing"),
        ]
        for c in cert.cases
    ]
    return headers, rows

"""Analysis: what an airframe can do, before anything flies. The :class:`Airframe` (geometry,
thrust limits, rotor efficiency; other tools' formats in ``_formats``), the ACAI with its two
named formulas (:mod:`~rotorfault.analysis.acai`: Du's eq. (13) and the facet margin), Du's
controllability test and failure tables (:mod:`~rotorfault.analysis.controllability`), relaxed
hover (:mod:`~rotorfault.analysis.relaxed_hover`: Mueller and D'Andrea, flying on by spinning) and
whether it can be entered from hover (:mod:`~rotorfault.analysis.spin_entry`).
Mirrors the core's ``analysis`` room plus ``airframe``.

May import: the extension module, ``rotorfault._typing`` and ``rotorfault._util``; nothing else
of the package (every other room builds on this one).
"""

from .acai import (
    ACAI_FORMULAS,
    EQ13_ZERO_NOTE,
    FORMULA_DESCRIPTIONS,
    GIVE_UP_YAW,
    HOVER_CODES,
    HOVER_WRENCH_NOTE,
    RANK_RTOL,
    ZERO_RTOL,
    AcaiBatch,
    AcaiValue,
    acai,
    acai_batch,
    acai_from_matrix,
    acai_label,
    format_acai,
    hover_wrench_text,
)
from .airframe import Airframe
from .controllability import ControllabilityReport, FailureCase, FailureTable, controllability, failure_table
from .relaxed_hover import RelaxedHoverAnalysis, RelaxedHoverSettings, RelaxedHoverSolution, relaxed_hover
from .spin_entry import ENTRY_TILT_LIMIT_RAD, EntryFromHover, entry_from_hover

__all__ = [
    "ACAI_FORMULAS",
    "ENTRY_TILT_LIMIT_RAD",
    "EQ13_ZERO_NOTE",
    "FORMULA_DESCRIPTIONS",
    "GIVE_UP_YAW",
    "HOVER_CODES",
    "HOVER_WRENCH_NOTE",
    "RANK_RTOL",
    "ZERO_RTOL",
    "AcaiBatch",
    "AcaiValue",
    "Airframe",
    "ControllabilityReport",
    "EntryFromHover",
    "FailureCase",
    "FailureTable",
    "RelaxedHoverAnalysis",
    "RelaxedHoverSettings",
    "RelaxedHoverSolution",
    "acai",
    "acai_batch",
    "acai_from_matrix",
    "acai_label",
    "controllability",
    "entry_from_hover",
    "failure_table",
    "format_acai",
    "hover_wrench_text",
    "relaxed_hover",
]

"""Reproductions of the papers rotorfault implements: one module per paper, holding only what is
the paper's own (its parameters, scenarios, printed numbers, and which study or flight to run);
the verdicts, engines and figures they use live in the rooms below.

- :mod:`~rotorfault.papers.ke`: Ke et al., uniform passive FTC (``rotorfault ftc-report``);
- :mod:`~rotorfault.papers.du`: Du et al., controllability and the ACAI;
- :mod:`~rotorfault.papers.lanzon_checks`: Lanzon et al.'s eq. (26) and loop shape (imported on use);
  :mod:`~rotorfault.papers.lanzon`: its flights, claims and studies, and
  :mod:`~rotorfault.papers.lanzon_report`: their report (``rotorfault lanzon-report``);
- :mod:`~rotorfault.papers.reproduce`: every paper in one report (``rotorfault reproduce``; imported
  on use), each paper a section provider (``report_section``), with
  :mod:`~rotorfault.papers.decisions` (the README's decisions table, linked to the code), every
paper feeding the one report writer (:mod:`~rotorfault.papers._report`: sections, tables,
figures, Markdown and CSV files).

May import: every room below (``studies``, ``control``, ``flight``, ``allocation``,
``analysis``, ``plotting``), ``rotorfault._typing`` and ``rotorfault._util``; never ``cli``. No
paper imports another paper; the shared machinery (``_report``, ``_numbers``, ``decisions``,
``reproduce``) imports none (the reproduce-all report finds them by name).
"""

from __future__ import annotations

from . import du, ke
from ._numbers import PaperNumber, number_rows

__all__ = ["PaperNumber", "du", "ke", "number_rows"]

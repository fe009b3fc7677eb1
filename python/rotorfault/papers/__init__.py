"""Reproductions of the papers rotorfault implements: one module per paper, holding its named
scenarios, metrics and reports (the generic API they use lives in the rest of the package).

- :mod:`~rotorfault.papers.ke`: Ke et al., uniform passive FTC (``rotorfault ftc-report``);
- :mod:`~rotorfault.papers.du`: Du et al., controllability and the ACAI;
- :mod:`~rotorfault.papers.lanzon_checks`: Lanzon et al.'s eq. (26) and loop shape (imported on use);
- :mod:`~rotorfault.papers.reproduce`: every paper in one report (``rotorfault reproduce``; imported
  on use), each paper a section provider (``report_section``), with
  :mod:`~rotorfault.papers.decisions` (the README's decisions table, linked to the code).
"""

from __future__ import annotations

from . import du, ke

__all__ = ["du", "ke"]

"""Reproductions of the papers rotorfault implements: one module per paper, holding its named
scenarios, metrics and reports (the generic API they use lives in the rest of the package).

- :mod:`~rotorfault.papers.ke`: Ke et al., uniform passive FTC (``rotorfault ftc-report``);
- :mod:`~rotorfault.papers.du`: Du et al., controllability and the ACAI.
"""

from __future__ import annotations

from . import du, ke

__all__ = ["du", "ke"]

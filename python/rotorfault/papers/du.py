"""Du, Quan, Yang, Cai (JGCD 2015): controllability and the Available Control Authority Index.

Du's reproduction needs nothing beyond the generic API: the ACAI, the 9-step test and failure
tables are :mod:`rotorfault.controllability` (including the eq. (13) footnote that the failure
table itself prints), the Fig. 4 efficiency grid is :mod:`rotorfault.scan`, and the paper's Tables
I-III and Fig. 4 are checked number by number in ``tests/test_du_paper.py``. This module is the
place for Du-specific scenarios and reports when they appear.
"""

from __future__ import annotations

__all__: list[str] = []

"""Deprecated name of :mod:`rotorfault.analysis` (split in issue 26 into
:mod:`rotorfault.analysis.acai` and :mod:`rotorfault.analysis.controllability`; this name works
for one release and warns). Import from :mod:`rotorfault.analysis`, or from ``rotorfault`` itself."""

from ._util.deprecation import warn

warn("module rotorfault.controllability", "rotorfault.analysis (acai, controllability)", stacklevel=2)

from .analysis.acai import *  # noqa: E402,F401,F403
from .analysis.acai import _efficiency, _formula  # noqa: E402,F401
from .analysis.airframe import Airframe, require_airframe, rotor_labels  # noqa: E402,F401
from .analysis.controllability import *  # noqa: E402,F401,F403
from .analysis.controllability import _COLUMNS  # noqa: E402,F401

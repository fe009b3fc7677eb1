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

import sys as _sys  # noqa: E402
import types as _types  # noqa: E402


class _CallableModule(_types.ModuleType):
    """Importing this module sets ``rotorfault.controllability`` to it, where the package's own
    ``rotorfault.controllability`` is the function: calling the module calls the function, so
    ``rf.controllability(airframe)`` keeps working after ``import rotorfault.controllability``."""

    def __call__(self, *args: object, **kwargs: object) -> object:
        return controllability(*args, **kwargs)  # type: ignore[arg-type]  # noqa: F405


_sys.modules[__name__].__class__ = _CallableModule

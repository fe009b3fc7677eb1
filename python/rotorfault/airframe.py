"""Deprecated name of :mod:`rotorfault.analysis.airframe` (moved in issue 26; this name works for one release and
warns). Import from :mod:`rotorfault.analysis.airframe`, or from ``rotorfault`` itself."""

from ._util.deprecation import moved_module

moved_module(__name__, "rotorfault.analysis.airframe")

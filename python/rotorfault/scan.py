"""Deprecated name of :mod:`rotorfault.studies.scan` (moved in issue 26; this name works for one release and
warns). Import from :mod:`rotorfault.studies.scan`, or from ``rotorfault`` itself."""

from ._util.deprecation import moved_module

moved_module(__name__, "rotorfault.studies.scan")

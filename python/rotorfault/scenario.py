"""Deprecated name of :mod:`rotorfault.studies.scenario_file` (moved in issue 26; this name works for one release and
warns). Import from :mod:`rotorfault.studies.scenario_file`, or from ``rotorfault`` itself."""

from ._util.deprecation import moved_module

moved_module(__name__, "rotorfault.studies.scenario_file")

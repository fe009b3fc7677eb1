"""Plotting: every figure the package draws, in one style (:mod:`~rotorfault.plotting.style`:
own Agg canvas, no pyplot, atomic save, legible in greyscale) and one module per kind of figure:
time histories (:mod:`~rotorfault.plotting.timeseries`), controllable regions of scans
(:mod:`~rotorfault.plotting.regions`), attainable sets (:mod:`~rotorfault.plotting.attainable`),
paths in space and on the unit sphere (:mod:`~rotorfault.plotting.paths`), frequency responses
(:mod:`~rotorfault.plotting.frequency`) and distributions of many runs
(:mod:`~rotorfault.plotting.distributions`).

Plotting only reads results: a plot function takes what a computation returned (a trajectory,
a scan, boundary points, runs) and draws it; it computes nothing of its own. May import:
``rotorfault._util`` and matplotlib (on first use), nothing else of the package; the rooms call
it (``Trajectory.plot``, ``Scan.plot``, the papers' reports), never the other way round.
"""

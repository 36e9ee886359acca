"""Trajectories: integrator lanes (Python, scipy, compiled, CVODES, event-driven contacts), the table of
which lane takes which solver (:mod:`gausspp.simulation.lanes`), and one recording path that builds every
:class:`~gausspp.Trajectory` (:mod:`gausspp.simulation.recording`).
"""

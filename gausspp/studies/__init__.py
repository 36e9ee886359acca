"""Studies written once, as functions that return results: error against run time, stability on stiff and
extreme cases, sweeps, the runs behind the figures and the demo's content. :mod:`gausspp.plot` draws what they
return; :mod:`gausspp.cli` calls them.
"""

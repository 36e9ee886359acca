"""Is a trajectory a motion of a model? The integral principle (23) on smooth paths and in pieces
(:func:`gausspp.verify`), and the cross-check of one step against an independent reference (:func:`gausspp.crosscheck`).
"""

"""One step at one state: the direct formula and Gauss's QP, compiled or from Python, and their checks.

The step layer reads a model through the :class:`~gausspp.step.protocol.StepModel` protocol and never imports
:mod:`gausspp.model`. One registry (:mod:`gausspp.step.qp`) names every QP backend.
"""

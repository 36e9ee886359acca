"""What the user declares: mechanisms, constraints, realizations, and the immutable :class:`~gausspp.Model`.

Compiled artefacts built from a model live in its workspace (:mod:`gausspp.workspace`), never in it.
"""

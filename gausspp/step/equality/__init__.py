"""The compiled equality step, one of the two kinds of step beside the general Gauss QP (:mod:`gausspp.step.general`).

:mod:`.expressions` reduces the step to reaction space symbolically (dense, or :mod:`.sparse` in the mechanism's own
sparsity); :mod:`.kernel` compiles it for the QP (:mod:`.qp_parts`) or the direct formula (:mod:`.direct`);
:mod:`.checked` and :mod:`.checked_call` are ``model.step``'s checked call; :mod:`.solve_numbers` solves a step given
as numbers (:class:`~gausspp.step.data.StepProblem`).
"""

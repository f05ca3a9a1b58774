"""The report's fast modal solvers for bodies without contact (report Sec. 2–4).

``PureMA`` (analytic modal response to step loads), ``SimpleRB`` (plus uncoupled
rigid-body motion) and ``CoupledRB`` (two-way coupled), on a ``ModalBasis`` built from
the same body data as :class:`~mbs.FlexibleBodyFFR`; loads are ``StepLoads``
(report eq. 9, Appendix A force files). Mode selection by effective mass and the
α–Ω decision boundaries live in :mod:`mbs.modal.mode_selection` and
:mod:`mbs.modal.decision`.
"""

from mbs.modal.basis import ModalBasis
from mbs.modal.coupled_rb import CoupledRB
from mbs.modal.pure_ma import PureMA
from mbs.modal.result import ModalResult
from mbs.modal.simple_rb import SimpleRB
from mbs.modal.step_loads import StepLoads

__all__ = ["CoupledRB", "ModalBasis", "ModalResult", "PureMA", "SimpleRB", "StepLoads"]

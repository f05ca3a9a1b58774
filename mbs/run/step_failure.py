"""The exception of a step that cannot be completed (a stage of :mod:`mbs.run.stages` or an
integrator's ``step``); the driver (:mod:`mbs.integrators.driver`) turns it into a
:class:`~ffrmbs.errors.SimulationError` with the time and step number."""


class StepFailure(Exception):
    """Raised when a step cannot be completed; the message names the cause."""

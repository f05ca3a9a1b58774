"""ffrmbs: flexible multibody dynamics with sliding contacts.

This small package holds what every other package shares: the version, the
exception hierarchy (:mod:`ffrmbs.errors`) and the command line (:mod:`ffrmbs.cli`).
The physics lives in the top-level packages ``preprocess``, ``mbs``, ``contours``,
``contact`` and ``validation``.
"""

__version__ = "0.1.0"

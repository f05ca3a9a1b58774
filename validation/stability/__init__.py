"""The stability suite (issue 8: "check numerical stability on stiff and extreme cases").

:mod:`validation.stability.core` holds the row type and the registry; importing this
package registers the cases of :mod:`~validation.stability.body_cases` (stiff modes,
long spins, the intermediate-axis flip, the Cardan singularity, spin near the first
bending frequency) and :mod:`~validation.stability.contact_cases`;
:func:`~validation.stability.runner.run_stability` runs them
(``ffrmbs validate --stability --out DIR``).
"""

from validation.stability import body_cases, contact_cases  # noqa: F401  (register the cases)
from validation.stability.core import CASES, StabilityCase, StabilityRow, graceful_row, stability_case
from validation.stability.runner import run_stability

__all__ = ["CASES", "StabilityCase", "StabilityRow", "graceful_row", "run_stability", "stability_case"]

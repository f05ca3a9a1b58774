"""Validation: cases that report error against run time (DESIGN.md, "Validation protocol").

``run_validation(out_dir)`` runs the cases registered in ``validation/cases/__init__.py``
and writes ``results.json``, ``report.md`` and one work-precision PNG per case.
"""

from ffrmbs.caches import configure_numba

configure_numba()      # numba's cache directory, before any kernel is defined (ffrmbs.caches)

from validation.harness import CASES, CaseResult, CpuTiming, available_cases, cpu_per_call, cpu_samples, make_row, timed
from validation.report import run_validation

__all__ = ["CASES", "CaseResult", "CpuTiming", "available_cases", "cpu_per_call", "cpu_samples", "make_row",
           "run_validation", "timed"]

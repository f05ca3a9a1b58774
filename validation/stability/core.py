"""The stability suite's vocabulary: one registered case per stiff or extreme situation,
each returning one :class:`StabilityRow` (issue 8, "check numerical stability on stiff
and extreme cases").

A case is a function ``run(quick: bool) -> StabilityRow`` registered with
:func:`stability_case`. It builds its scene, simulates, and measures against its own
independent reference. Its *expectation* is part of the case: most cases expect to finish
stable and within a stated error bound; some expect a graceful stop (a
:class:`ffrmbs.errors.SimulationError` naming time, step and cause) or a warning. A row
``passed`` when the outcome is the expected one — a crash (any other exception) never
passes; the runner records it as ``FAILED``.
"""

from __future__ import annotations

import math
import time
from dataclasses import asdict, dataclass, field
from typing import Callable

from ffrmbs.errors import SimulationError


@dataclass
class StabilityRow:
    """One row of the stability table.

    case: registered name; finished: the run reached t_end; stable: the state stayed
    finite and bounded (energy did not grow beyond the case's bound); energy_drift:
    max |E(t) − E(0)| / scale [-] (None when not meaningful, e.g. with dissipation by
    design: then the case says so in ``note``); max_penetration [m] (None without
    contact); error: against ``reference`` (relative unless ``note`` says otherwise);
    run_time_s: wall seconds of the simulation(s) [s]; passed: the outcome is the
    case's expected one; outcome: "passed", "failed gracefully: <reason>" (an expected
    or unexpected SimulationError), or "FAILED: <reason>"; note: what was checked,
    warnings seen, bounds used.
    """

    case: str
    finished: bool
    stable: bool
    energy_drift: float | None
    max_penetration: float | None
    error: float | None
    reference: str
    run_time_s: float
    passed: bool
    outcome: str
    note: str = ""
    details: dict = field(default_factory=dict)

    def as_dict(self) -> dict:
        return {k: (None if isinstance(v, float) and not math.isfinite(v) else v) for k, v in asdict(self).items()}


@dataclass(frozen=True)
class StabilityCase:
    name: str
    title: str
    run: Callable[[bool], StabilityRow]


CASES: dict[str, StabilityCase] = {}


def stability_case(name: str, title: str):
    """Register ``run(quick) -> StabilityRow`` under ``name`` (a short identifier) with a
    one-line ``title`` for the table."""
    def register(fn):
        if name in CASES:
            raise ValueError(f"stability case {name!r} registered twice")
        CASES[name] = StabilityCase(name, title, fn)
        return fn
    return register


def graceful_row(case: str, err: SimulationError, run_time_s: float, reference: str, expected: bool,
                 note: str = "") -> StabilityRow:
    """The row of a run that stopped with a SimulationError: ``expected`` says whether the
    case predicted this stop (then it passes); the reason (time, step, cause) is shown."""
    return StabilityRow(case, finished=False, stable=False, energy_drift=None, max_penetration=None, error=None,
                        reference=reference, run_time_s=run_time_s, passed=expected,
                        outcome=f"failed gracefully: {err}", note=note,
                        details={"t": err.t, "step": err.step, "cause": err.cause,
                                 "samples_kept": 0 if getattr(err, "result", None) is None else len(err.result.t)})


class Stopwatch:
    """Wall time of a block: ``with Stopwatch() as w: ...; w.seconds``."""

    def __enter__(self):
        self._t0 = time.perf_counter()
        self.seconds = 0.0
        return self

    def __exit__(self, *exc):
        self.seconds = time.perf_counter() - self._t0
        return False

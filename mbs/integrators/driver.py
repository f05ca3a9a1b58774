"""The loop every smooth integrator shares: steps that land on the output times, sampling,
and a clear stop when the state diverges."""

from __future__ import annotations

import math
import time

import numpy as np
from threadpoolctl import threadpool_limits

from ffrmbs.errors import ModelError, SimulationError

from ..body import Frame
from ..link import body_q
from ..result import Result


def output_times(t_end, dt, t_out):
    """Sorted output times in [0, t_end]; every step when ``t_out`` is None."""
    if not (t_end > 0 and dt > 0):
        raise ModelError(f"need t_end > 0 and dt > 0, got t_end={t_end}, dt={dt}")
    if t_out is None:
        n = max(1, math.ceil(t_end / dt - 1e-9))
        return np.linspace(0.0, t_end, n + 1)
    t_out = np.asarray(t_out, dtype=float).ravel()
    if t_out.size == 0 or np.any(np.diff(t_out) <= 0) or t_out[0] < 0 or t_out[-1] > t_end * (1 + 1e-12):
        raise ModelError("t_out must be strictly increasing times within [0, t_end]")
    return t_out


def _probe(system, spec):
    """A callable (t, q, u) -> array for an output spec: a Frame (its position) or a callable."""
    if isinstance(spec, Frame):
        return lambda t, q, u: spec.position(body_q(spec, q), t)
    if callable(spec):
        return spec
    raise ModelError(f"an output must be a Frame or a callable (t, q, u), got {spec!r}")


class StepFailure(Exception):
    """Raised by an integrator's ``step`` when it cannot complete the step; the driver turns
    it into a SimulationError with the time and step number."""


class Integrator:
    """Base class: subclasses implement ``start(t, q, u)`` and ``step(h)`` on ``self.t``,
    ``self.q``, ``self.u`` and count Newton iterations in ``self.iterations``; accepted
    steps are counted in ``self.steps``. :meth:`advance` takes equal steps; step-size
    controlled integrators override it."""

    name = "integrator"

    def __init__(self, system):
        self.system = system
        self.iterations = 0
        self.steps = 0
        self.plan = None        # the scene plan of a planned run (mbs.plan), set by run()

    def advance(self, end, dt):
        """Step from ``self.t`` to ``end`` [s] in ceil((end − t)/dt) equal steps."""
        gap = end - self.t
        k = math.ceil(gap / dt - 1e-9) if gap > 1e-14 * max(1.0, abs(end)) else 0
        for _ in range(k):
            self.step(gap / k)
            self.accepted(gap / k)

    def accepted(self, h):
        """Book an accepted step of size ``h``; a NaN or infinite state stops the run."""
        self.steps += 1
        if not math.isfinite(self.q.sum() + self.u.sum()):     # a NaN or inf anywhere propagates
            raise SimulationError(self.t, self.steps, "the state became NaN or infinite")

    def trace(self) -> dict:
        """Per-step records {name: (steps,) array} when the integrator keeps them, else {}."""
        return {}

    def options(self) -> dict:
        return {}

    def diagnostics(self) -> dict:
        """Counters the integrator keeps over the run (merged into ``Result.stats``)."""
        return {}

    def start(self, t, q, u):
        raise NotImplementedError

    def step(self, h):
        raise NotImplementedError

    def run(self, q0, u0, t_end, dt, t_out, outputs, energies, breakpoints=(), plan=None):
        """Integrate and sample (see ``System.simulate``). At each breakpoint t_b the
        integration ends at t_b − 1e-12 max(1, t_b) s, safely below t_b despite rounding
        (so loads that jump at t_b act with their left limit), and restarts at t_b with
        consistent accelerations.

        BLAS runs single-threaded meanwhile: the per-step matrices are small (n_f + 6
        per body), and on this project's 2-core machines OpenBLAS threads made a 753 x 753
        Cholesky factorization 13 times slower (55 ms against 4 ms).

        With a ``plan`` (:mod:`mbs.plan`), its modal bodies are solved first at the output
        times, left out of the integrated equations (their velocities held at zero) and
        written into the state at each output."""
        with threadpool_limits(limits=1, user_api="blas"):
            try:
                return self._run(q0, u0, t_end, dt, t_out, outputs, energies, breakpoints, plan)
            finally:
                self.system.leave_out()

    def _run(self, q0, u0, t_end, dt, t_out, outputs, energies, breakpoints, plan):
        sys = self.system
        times = output_times(t_end, dt, t_out)
        breaks = sorted(float(b) for b in breakpoints if 0.0 < b < t_end)
        landings = sorted(set(times.tolist()) | set(breaks))
        record_at = {t: i for i, t in enumerate(times)}
        probes = {name: _probe(sys, spec) for name, spec in outputs.items()}
        n = len(times)
        res = Result(np.full(n, np.nan), np.full((n, sys.nq), np.nan), np.full((n, sys.nu), np.nan))
        res.stats = {"integrator": self.name, "dt": dt, **self.options()}
        q, u = np.array(q0, dtype=float), np.array(u0, dtype=float)
        sys.normalize(q)
        cpu0, wall0 = time.process_time(), time.perf_counter()
        modal = plan.solve_modal(sys, times, q, u, dt) if plan is not None else {}
        self.plan = plan
        res.plan = "" if plan is None else str(plan)
        if modal:
            sys.leave_out(modal, plan.forces)
            for b in modal:
                u[b.u_slice] = 0.0
        res.stats["modal_cpu_s"] = time.process_time() - cpu0
        stepping = len(modal) < len(sys.bodies)
        self.start(0.0, q, u)
        recorded = 0

        def record(i):
            res.t[i], res.q[i], res.u[i] = self.t, self.q, self.u
            q, u = res.q[i], res.u[i]
            for b, (qb, ub) in modal.items():
                q[b.q_slice], u[b.u_slice] = qb[i], ub[i]
            for name, probe in probes.items():
                value = np.asarray(probe(self.t, q, u), dtype=float)
                if name not in res.outputs:
                    res.outputs[name] = np.full((n,) + value.shape, np.nan)
                res.outputs[name][i] = value
            if energies:
                for key in ("kinetic", "potential"):
                    res.energy.setdefault(key, np.full(n, np.nan))
                res.energy["kinetic"][i] = sys.kinetic_energy(self.t, q, u)
                res.energy["potential"][i] = sys.potential_energy(self.t, q)

        try:
            for target in landings:
                is_break = target in breaks
                end = target - 1e-12 * max(1.0, abs(target)) if is_break else target
                try:
                    if stepping:
                        self.advance(end, dt)
                except StepFailure as failure:
                    raise SimulationError(self.t, self.steps + 1, str(failure)) from None
                except np.linalg.LinAlgError as failure:
                    raise SimulationError(self.t, self.steps + 1, f"singular system matrix ({failure}); "
                                          "a rotation singularity or a redundant constraint?") from None
                if is_break:
                    self.start(target, self.q, self.u)
                self.t = target
                if target in record_at:
                    record(record_at[target])
                    recorded += 1
        except SimulationError as err:
            err.result = res.truncated(recorded)
            err.result.stats.update(steps=self.steps, newton_iterations=self.iterations,
                                    cpu_s=time.process_time() - cpu0, **self.diagnostics())
            err.result.trace = self.trace()
            raise
        res.stats.update(steps=self.steps, newton_iterations=self.iterations,
                         cpu_s=time.process_time() - cpu0, wall_s=time.perf_counter() - wall0, **self.diagnostics())
        res.trace = self.trace()
        return res

"""The loop every integrator shares: steps that land on the output times, sampling, a
clear stop when the state diverges, and the hooks of a run that lasts — a recorder that
streams the samples to a result file and takes checkpoints (:mod:`mbs.results.result_file`,
:mod:`mbs.results.checkpoint`), a stop on request (:func:`request_stop`, e.g. from a signal
handler) and a progress callback.

A run compiles the System under its plan into a :class:`~mbs.run.model.Model` and keeps
everything that changes in a :class:`~mbs.run.model.Data` (``t``, ``q``, ``u`` of an
integrator are Data's); the System is never mutated. A run is resumable at every
output sample: a checkpoint holds its state as arrays — the Data, the integrator's own
state (:meth:`Integrator.collect`), the :class:`RunState` and the samples so far, the
contours' and contacts' run state — and :meth:`Integrator.run` given that checkpoint
prepares the same run from its inputs, loads the arrays and continues bit for bit."""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np
from threadpoolctl import threadpool_limits

from ffrmbs.errors import ModelError, RunInterrupted, SimulationError

from mbs.bodies._kernels import finite_sum
from mbs.results.contact_record import ContactRecorder, empty_records
from mbs.run.model import Data, compile_model
from mbs.results.probes import FramePosition, probe
from mbs.run.residual_contact import spring_energy
from mbs.results.result import Result
from mbs.run.step_failure import StepFailure
from mbs.bodies.validity import SpinMonitor


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


def non_finite(t, step, what) -> SimulationError:
    """The error stopping a run whose ``what`` (``"q/u"``, ``"energy"``, a probe's name)
    became NaN or infinite at time ``t`` [s], step ``step``: one wording for every check."""
    return SimulationError(t, step, f"state became non-finite (NaN/inf) in {what}")


_stop = [None, 0]   # the reason of a requested stop and how many times it was asked


def request_stop(reason: str) -> None:
    """Ask the running integrator to stop (safe to call from a signal handler). The first
    request stops the run at its next output sample, where the recorder takes a
    checkpoint, so a resumed run loses nothing; a second request stops it after the
    current step. Either way the run raises :class:`~ffrmbs.errors.RunInterrupted`
    carrying the results so far."""
    _stop[0] = reason
    _stop[1] += 1


def clear_stop() -> None:
    _stop[0], _stop[1] = None, 0


@dataclass
class RunState:
    """Where a run stands: what it samples and when, and what it has recorded.

    times (n,) [s]: output times; landings: output and break times in order;
    breaks: times where loads jump; probes: {name: callable (t, q, u)}; result: the
    preallocated :class:`~mbs.results.result.Result`, rows [0, recorded) filled; modal: {body:
    (q (n, nq_b), u (n, nu_b))} of the bodies the plan solves apart; next_landing: index
    into ``landings`` of the next target; cpu_s: CPU seconds spent before this process
    (a resumed run adds its own); resumed_at: times [s] where the run was resumed;
    resumed_steps: the step count when the last resume began (0 for a fresh run).
    """

    times: np.ndarray
    landings: list
    breaks: list
    probes: dict
    result: Result
    modal: dict
    energies: bool
    contacts: bool
    stepping: bool
    next_landing: int = 0
    recorded: int = 0
    cpu_s: float = 0.0
    resumed_at: list = field(default_factory=list)
    resumed_steps: int = 0


class CarriedEntry:
    """An integrator's attribute kept in its run's Data — what it carries from step to
    step, so that a checkpoint of Data resumes it: the Data attribute of its name
    (``attribute``: the counters) or its entry of ``data.integrator``; ``default``
    before a run."""

    def __init__(self, attribute=False, default=None):
        self.attribute, self.default = attribute, default

    def __set_name__(self, owner, name):
        self.name = name

    def __get__(self, obj, owner=None):
        if obj is None:
            return self
        if obj.data is None:
            return self.default
        return getattr(obj.data, self.name) if self.attribute else obj.data.integrator[self.name]

    def __set__(self, obj, value):
        if self.attribute:
            setattr(obj.data, self.name, value)
        else:
            obj.data.integrator[self.name] = value


class Integrator:
    """Base class: subclasses implement ``start(t, q, u)`` and ``step(dt)`` on ``self.t``,
    ``self.q``, ``self.u`` (the run's Data: assigning copies into it) and count Newton
    iterations in ``self.iterations``; accepted steps are counted in ``self.steps``. The
    equations of the active bodies are ``self.model.equations``. :meth:`advance` takes
    equal steps; step-size controlled integrators override it. What an integrator carries
    from step to step is Data's (the counters, ``data.integrator``): a checkpoint of Data
    resumes it."""

    name = "integrator"

    def __init__(self, system):
        self.system = system
        self.state = None       # the RunState of the current run
        self.model = None       # the compiled Model of the current run
        self.data = None        # its Data
        self.contact_recorder = None    # samples Result.contacts (mbs.results.contact_record) when asked for

    steps = CarriedEntry(attribute=True, default=0)          # accepted steps of the run
    iterations = CarriedEntry(attribute=True, default=0)     # Newton iterations of the run

    @property
    def t(self) -> float:
        return self.data.t

    @t.setter
    def t(self, value):
        self.data.t = value

    @property
    def q(self) -> np.ndarray:
        return self.data.q

    @q.setter
    def q(self, value):
        self.data.q[...] = value

    @property
    def u(self) -> np.ndarray:
        return self.data.u

    @u.setter
    def u(self, value):
        self.data.u[...] = value

    def compile(self, plan=None, model=None) -> None:
        """Compile the System under ``plan`` (None: every body integrated) into the run's
        :class:`~mbs.run.model.Model`, or take ``model`` (compiled before for this System
        and this integrator's options, :meth:`mbs.System.compile`: its plan is the run's),
        and make a new :class:`~mbs.run.model.Data` (before ``start``)."""
        if model is None:
            model = compile_model(self.system, plan, **self.model_options())
        else:
            self.check_model(model)
        self.model = model
        self.data = Data(model)

    def check_model(self, model) -> None:
        """ModelError unless ``model`` was compiled for this System with this integrator's
        options (θ and the contact solver's settings)."""
        if model.system is not self.system:
            raise ModelError("the Model was compiled for another System")
        options = self.model_options()
        theta, solver = options.get("theta", 0.5), options.get("solver")
        if model.theta != theta or (solver is None) != (model.solver is None) or (
                solver is not None and vars(solver) != vars(model.solver)):
            raise ModelError(f"the Model was compiled with theta = {model.theta:g} and the solver "
                             f"{_settings(model.solver)}; this run asks for theta = {theta:g} and {_settings(solver)}")

    def spring_energy(self) -> float:
        """½ Σ Fᵀδ [J] of the compliant contacts' springs (:mod:`mbs.run.residual_contact`),
        part of the potential energy recorded with ``energies``."""
        return spring_energy(self.model, self.data)

    def collect(self, prefix, arrays: dict, kinds: dict) -> None:
        """What a checkpoint keeps of the integrator besides Data (its state between steps
        is Data's): nothing here; Moreau's per-step trace rows."""

    def restore(self, prefix, arrays, kinds) -> None:
        """What :meth:`collect` saved (after :meth:`start` built the workspaces)."""

    def model_options(self) -> dict:
        """Options of :func:`mbs.run.model.compile_model` the integrator fixes (Moreau: θ, solver)."""
        return {}

    def advance(self, end, dt):
        """Step from ``self.t`` to ``end`` [s] in ceil((end − t)/dt) equal steps."""
        gap = end - self.t
        k = math.ceil(gap / dt - 1e-9) if gap > 1e-14 * max(1.0, abs(end)) else 0
        dt_k = gap / k if k else 0.0
        step, accepted = self.step, self.accepted
        for _ in range(k):
            step(dt_k)
            accepted(dt_k)

    def accepted(self, dt):
        """Book an accepted step of size ``dt`` [s]; a NaN or infinite state stops the run, so
        does a requested stop (:func:`request_stop`)."""
        data = self.data
        data.steps += 1
        if not math.isfinite(finite_sum(data.q, data.u)):       # a NaN or inf anywhere propagates
            raise non_finite(self.t, self.steps, "q/u")
        if _stop[1] > 1:
            raise RunInterrupted(self.t, self.steps, _stop[0])

    trace_units: dict = {}      # {trace key: unit} of the integrator's per-step records

    def trace(self, start=0) -> dict:
        """Per-step records {name: (steps − start,) array} from step ``start`` on when the
        integrator keeps them, else {}."""
        return {}

    def options(self) -> dict:
        return {}

    def diagnostics(self) -> dict:
        """Counters the integrator keeps over the run (merged into ``Result.stats``)."""
        return {}

    def contact_force(self, i, out) -> None:
        """The force on contact ``i``'s first contour's body (world, (3,) [N]) at the last
        step into ``out``: a single-valued law's normal force n F_N; set-valued laws are
        the time-stepping integrators' (they know the impulses)."""
        contact = self.model.contacts[i]
        closed = self.data.closed[i] and not contact.set_valued
        out[:] = contact.kinematics.n * self.data.force_N[i] if closed else 0.0

    def start(self, t, q, u):
        raise NotImplementedError

    def step(self, dt):
        raise NotImplementedError

    def run(self, q0, u0, t_end, dt, t_out, outputs, energies, breakpoints=(), plan=None,
            recorder=None, progress=None, contacts=False, checkpoint=None, model=None):
        """Integrate and sample (see ``System.simulate``). At each breakpoint t_b the
        integration ends at t_b − 1e-12 max(1, t_b) s, safely below t_b despite rounding
        (so loads that jump at t_b act with their left limit), and restarts at t_b with
        consistent accelerations.

        BLAS runs single-threaded meanwhile: the per-step matrices are small (n_f + 6
        per body), and on this project's 2-core machines OpenBLAS threads made a 753 x 753
        Cholesky factorization 13 times slower (55 ms against 4 ms).

        With a ``plan`` (:mod:`mbs.run.plan`), its modal bodies are solved first at the output
        times, left out of the integrated equations of the compiled Model (their
        velocities held at zero) and written into the state at each output.

        ``recorder`` (:class:`mbs.results.result_file.ResultRecorder` or alike): ``begin(self)``
        (``resume(self)`` for a restored run), ``landed(self)`` after each landing (it
        reads the new rows of ``self.state.result`` and may take a checkpoint),
        ``checkpoint(self)``, ``end(self, status)``. ``progress``: a
        callable (t) after each landing. ``contacts``: also record each contact's state
        (``Result.contacts``).

        ``checkpoint`` (:class:`mbs.results.checkpoint.Checkpoint` of this run, taken at an output
        sample): continue from it — the run is prepared as above from the same inputs,
        its state loaded from the checkpoint's arrays, and the result (samples before the
        checkpoint included) equals the uninterrupted run's bit for bit; the recorder
        gets ``resume(self)``.

        ``model``: a :class:`~mbs.run.model.Model` of this System compiled before
        (:meth:`mbs.System.compile`) to run on, with a new Data, instead of compiling one;
        its plan is the run's (``plan`` is not used)."""
        self.dt = dt
        if model is not None:
            plan = model.plan
        self.state = self._prepare(q0, u0, t_end, dt, t_out, outputs, energies, breakpoints, plan, contacts, model)
        if checkpoint is not None:
            checkpoint.restore(self)
            self.state.resumed_at.append(float(self.t))
            self.state.resumed_steps = self.steps
        return self._go(recorder, progress, fresh=checkpoint is None)

    def _prepare(self, q0, u0, t_end, dt, t_out, outputs, energies, breakpoints, plan, contacts, model=None):
        sys = self.system
        times = output_times(t_end, dt, t_out)
        breaks = sorted(float(b) for b in breakpoints if 0.0 < b < t_end)
        n = len(times)
        res = Result(np.full(n, np.nan), np.full((n, sys.nq), np.nan), np.full((n, sys.nu), np.nan))
        res.stats = {"integrator": self.name, "dt": dt, **self.options()}
        if contacts:
            res.contacts = empty_records(sys.contacts, n)
            if len(res.contacts) < len(sys.contacts):
                raise ModelError("contacts need distinct names to be recorded")
        q, u = np.array(q0, dtype=float), np.array(u0, dtype=float)
        sys.normalize(q)
        cpu0 = time.process_time()
        modal = plan.solve_modal(sys, times, q, u, dt) if plan is not None else {}
        self.compile(plan, model)
        self.contact_recorder = ContactRecorder(self.model) if contacts else None
        res.plan = "" if plan is None else str(plan)
        if self.model.idle:
            res.stats["solved_apart"] = [b.name for b in self.model.idle]     # the plan's modal bodies
        res.stats["modal_cpu_s"] = time.process_time() - cpu0
        state = RunState(times, sorted(set(times.tolist()) | set(breaks)), breaks,
                         {name: probe(spec) for name, spec in outputs.items()}, res, modal, energies, contacts,
                         stepping=len(modal) < len(sys.bodies), cpu_s=time.process_time() - cpu0)
        for b in modal:
            u[b.u_slice] = 0.0
        self.t, self.q, self.u = 0.0, q, u       # started in _go, once the plan's bodies are left out
        self.monitor = SpinMonitor(sys)          # warns when a body spins too fast for linear FFR
        return state

    def _go(self, recorder, progress, fresh):
        """The sampling loop from ``self.state.next_landing`` on, BLAS single-threaded."""
        with threadpool_limits(limits=1, user_api="blas"):
            st = self.state
            self._cpu0 = time.process_time()
            try:
                if fresh:
                    self.start(self.t, self.q, self.u)
                if recorder is not None:
                    recorder.begin(self) if fresh else recorder.resume(self)
                res = self._loop(recorder, progress)
            except (SimulationError, RunInterrupted) as err:
                err.result = self._finish(st.result.truncated(st.recorded))
                if recorder is not None:
                    recorder.end(self, "interrupted" if isinstance(err, RunInterrupted) else f"failed: {err}")
                raise
            if recorder is not None:
                recorder.end(self, "complete")
            return res

    def _finish(self, res):
        st = self.state
        res.stats.update(steps=self.steps, newton_iterations=self.iterations,
                         cpu_s=st.cpu_s + time.process_time() - self._cpu0, **self.diagnostics())
        if st.resumed_at:
            res.stats["resumed_at"] = list(st.resumed_at)
            res.stats["resumed_steps"] = st.resumed_steps
        if self.monitor.events:
            res.stats["validity_warnings"] = list(self.monitor.events)
        res.trace = self.trace()
        return res

    def _loop(self, recorder, progress):
        st = self.state
        wall0 = time.perf_counter()
        record_at = {t: i for i, t in enumerate(st.times)}
        while st.next_landing < len(st.landings):
            target = st.landings[st.next_landing]
            is_break = target in st.breaks
            end = target - 1e-12 * max(1.0, abs(target)) if is_break else target
            try:
                if st.stepping:
                    self.advance(end, self.dt)
            except StepFailure as failure:
                raise SimulationError(self.t, self.steps + 1, str(failure)) from None
            except np.linalg.LinAlgError as failure:
                raise SimulationError(self.t, self.steps + 1, f"singular system matrix ({failure}); "
                                      "a rotation singularity or a redundant constraint?") from None
            if is_break:
                self.start(target, self.q, self.u)
            self.t = target
            if target in record_at:
                self._record(record_at[target])
                st.recorded += 1
            st.next_landing += 1
            if recorder is not None:
                st.cpu_s += time.process_time() - self._cpu0     # booked before a checkpoint is taken
                self._cpu0 = time.process_time()
                recorder.landed(self)
            if progress is not None:
                progress(target)
            if _stop[1]:
                if recorder is not None:
                    recorder.checkpoint(self)
                raise RunInterrupted(self.t, self.steps, _stop[0])
        res = self._finish(st.result)
        res.stats["wall_s"] = time.perf_counter() - wall0
        return res

    def _record(self, i):
        """Sample row ``i`` of the result at the current state; SimulationError if q, u or
        the energy there is NaN or infinite (the steps check only the integrated
        coordinates, and a finite state can have an infinite energy); such a sample is not
        counted, so the result keeps the finite ones before it."""
        st = self.state
        res, n = st.result, len(st.times)
        res.t[i], res.q[i], res.u[i] = self.t, self.q, self.u
        q, u = res.q[i], res.u[i]
        for b, (qb, ub) in st.modal.items():
            q[b.q_slice], u[b.u_slice] = qb[i], ub[i]
        if not math.isfinite(finite_sum(q, u)):             # as in accepted(), modal-plan bodies included
            raise non_finite(self.t, self.steps, "q/u")
        self.monitor.check(self.t, q, u)
        for name, sample in st.probes.items():
            rows = res.outputs.get(name)
            if rows is not None and type(sample) is FramePosition:
                sample.into(self.t, q, rows[i])         # in place (mbs.results.probes)
                continue
            value = np.asarray(sample(self.t, q, u), dtype=float)
            if rows is None:
                rows = res.outputs[name] = np.full((n,) + value.shape, np.nan)
            rows[i] = value
        if st.energies:
            for key in ("kinetic", "potential"):
                if key not in res.energy:
                    res.energy[key] = np.full(n, np.nan)
            kinetic, potential = self._scene_energies(q, u)
            res.energy["kinetic"][i], res.energy["potential"][i] = kinetic, potential
            if not math.isfinite(kinetic + potential):
                raise non_finite(self.t, self.steps, "energy")
        if st.contacts:
            self.contact_recorder.record(self.data, res.contacts, i, self.t, q, u)
            for j, c in enumerate(self.model.contacts):
                self.contact_force(j, res.contacts[c.name]["force"][i])

    def _scene_energies(self, q, u):
        """(kinetic, potential) energy [J] of the whole scene at (``self.t``, q, u): the
        body stage's one kernel when it holds every body and force element
        (:meth:`mbs.run.body_stage.BodyStage.energies`), else the System's sums over bodies
        and links; the compliant contacts' springs in the potential."""
        sys, model = self.system, self.model
        energies = model.body_stage.energies(q, u) if len(model.equations.forces) == len(sys.forces) else None
        if energies is None:
            energies = sys.kinetic_energy(self.t, q, u), sys.potential_energy(self.t, q)
        return energies[0], energies[1] + self.spring_energy()


def _settings(solver) -> str:
    """A contact solver's settings in words (none without one)."""
    if solver is None:
        return "none"
    return f"{solver.method} (tol = {solver.tol:g}, max_iter = {solver.max_iter})"

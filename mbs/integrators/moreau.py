"""Moreau's time-stepping for set-valued contacts and impacts (thesis eq. 3.1, 4.1), as the
θ-method of Moreau–Jean (Acary & Brogliato 2008, Sec. 10.1) on the smooth forces.

One step of size Δt is the eight stages of :mod:`mbs.run.stages` on the run's
:class:`~mbs.run.model.Model` and :class:`~mbs.run.model.Data` (DESIGN, "the data flow of one
Moreau step"):

1. q_θ = q_k ⊕ θΔt u_k (θ = 1/2: the thesis's midpoint q_m);
2. M, h at (t_k + θΔt, q_θ, u_k); single-valued contact forces join h (when M and the
   tangents are constant — point masses, frame-fixed FFR bodies, no springs — only h,
   and M̂ below is factored once per step size);
3. the contours of the contacts update at q_θ (each once);
4. contacts located; a unilateral contact is closed where g_N(q_θ) <= ``closing_tol``
   (:class:`contact.Contact`; 1e-12 m by default, i.e. touching to rounding);
5. bilateral joints (velocity level, C_q u⁺ + g_t = 0) and closed contacts form
   W (nu, m); with M̂ = M + θ Δt D + θ² Δt² K (linearly implicit stiffness and damping,
   so stiff modes do not limit Δt) the free velocity is u_free = u_k + M̂⁻¹ h Δt, the
   Delassus matrix G = Wᵀ M̂⁻¹ W, and the impulses Λ solve the laws on velocity level
   (:class:`contact.solver.ProxSolver`, Newton's impact law with γ⁻ = Wᵀ u_k).
   A resting contact (closed in this step and the previous one) still apart by
   0 < g_N(q_θ) <= closing_tol has the law act on γ_N⁺ + g_N/Δt: pressed, it closes
   that gap (for θ = 1/2 the next midpoint's gap is zero: g_N(q_θ,k+1) = g_N(q_θ) +
   Δt γ_N⁺ for a body at rest); it is never pulled, and penetrations (g_N < 0) are not
   pushed out (that would inject energy). Without this a resting contact's gap walks
   off by rounding: in a heavy-on-light stack (Delassus condition ~ m_top/m_bottom)
   the relative velocity is exact only to cond(G) ε |c| ~ 1e-12 m/s, always with the
   same sign, so the gap grew by ~1e-15 m per step until it passed closing_tol; the
   contact opened for a step and the top body fell g Δt² into the bottom one (the
   stability suite's ``mass_ratio_stack_1e6_newton``);
6. u_{k+1} = u_free + M̂⁻¹ W Λ;
7. q_{k+1} = q_k ⊕ Δt (θ u_{k+1} + (1 − θ) u_k) = q_θ ⊕ Δt (θ u_{k+1} + (1 − 2θ) u_k),
   orientations renormalized.

Why θ² in M̂: the θ-method evaluates the elastic forces at θ q_{k+1} + (1 − θ) q_k =
q_θ + θ² Δt (u_{k+1} − u_k) (from step 7), so M (u_{k+1} − u_k) = Δt [h(q_θ) − θ² Δt K
(u_{k+1} − u_k) − θ D (u_{k+1} − u_k)]. Per elastic mode (s = ωΔt) the step's amplification
has modulus 1 for θ = 1/2 at every s (the trapezoidal rule: elastic energy conserved,
no overshoot of a stiff mode started with a velocity) and tends to (θ − 1)/θ for s → ∞
(θ = 1: implicit Euler, stiff modes damped out). (An earlier M̂ = M + θΔt² K kept the
midpoint update for every θ: its amplification had determinant 1 for all θ and a stiff
mode with a velocity overshot its exact amplitude by ~ωΔt — found by the stability
suite's ``stiff_modes`` case.)

Single-valued (penalty) contact forces stay explicit: a closed one whose stiffness k
gives ω Δt = Δt √(k w_Nᵀ M̂⁻¹ w_N) > 2 (the leapfrog limit) stops the run with the
numbers, rather than gaining energy.

Options: ``theta`` (0.5..1; default 0.5: the thesis's midpoint scheme, trapezoidal on
the elastic forces, conserves elastic energy; 1: implicit Euler, stiff modes damped out,
but positions advance with u_{k+1} alone: a plastic impact stops a body up to |u| Δt
short of the surface, from where it falls again in small hops), ``solver`` (a ProxSolver
or its method name), ``tol``, ``trace`` (True: per-step records in ``Result.trace``:
t, dt [s], closed contacts, largest penetration [m], solver iterations and residual
[m/s], the work of the impulses Λᵀ (γ⁺ + γ⁻)/2 [J] (contacts and joints; the energy the
impact laws take out; with residual flexibility the work on the bodies, of which the
contacts' springs hold a part while closed), total energy E = T + V [J] (gravity and
the compliant contacts' springs in V; the springs' ½ Fᵀδ also on their own as
``contact_springs``), the contacts that transmitted a force (non-zero Λ; "closed"
counts those touching too), the applied loads' work and the damping's loss [J]
(:mod:`mbs.run.step_work`); the energy at the start, E(0) of the integrated bodies, is
``Result.stats["initial_energy"]``), ``penetration_bound`` [m] (default None: no
bound; a penetration max(0, −g_N) at q_θ beyond it, in an accepted step, stops the run). Non-convergence of
the contact problem stops the run with a SimulationError naming the residual.

:class:`AdaptiveMoreauTimeStepping` ("moreau-adaptive") controls the step size by step
doubling, like MBSim's ``AutoTimeSteppingSSCIntegrator``: each step of size H is also
taken as two steps of H/2; the difference of the positions, weighted by
``atol + rtol |q|``, estimates the local error of the (accepted) half-step solution.
Gap control: a unilateral contact detected only at a midpoint can end a step already
penetrating, and then both solutions agree (a penalty contact: both take the same free
flight into the stiff spring); so the growth of the largest
penetration max(0, −g_N) at the step's end over its start, divided by ``gap_tol`` [m]
(default ``atol``), also enters e. A penetration that merely persists (a resting contact
keeps the depth at which it closed) does not.
A step is accepted when that weighted error e <= 1 and the next H is
H · min(2, max(0.2, 0.9 e^(−1/2))) (first order in the positions across impacts);
a rejected step is retaken with the smaller H. A step taken back (the step of H before
its two halves, a rejected step) leaves no trace: what a step reads of the steps before
it — the Data of :data:`mbs.run.model.CARRIED` (state, closed flags, warm starts, the
compliant contacts' springs, counters, the contours' and contacts' run state with the
searches' warm starts) — is copied before it and put back after
(:class:`mbs.run.model.CarriedCopy`). An impact inside a step separates the
two solutions by about the approach velocity times the mistimed interval, so the step
shrinks around contact closing and grows again in free flight and steady contact.
``dt`` of ``simulate`` is the initial and largest step; ``dt_min`` the smallest (a step
at dt_min is accepted whatever its error and counted in ``forced_steps``). A trial step
that cannot be taken (a penalty contact too stiff for it) is rejected and retaken at a
fifth of its size; at dt_min the run stops with the cause.
"""

from __future__ import annotations

import math

import numpy as np

from contact.solver import ProxSolver
from ffrmbs.errors import ModelError

from mbs.run import stages

from mbs.results.codec import StateMismatch, take
from mbs.run.model import CarriedCopy, LAST_STEP
from mbs.run.step_work import StepWork
from mbs.integrators.driver import CarriedEntry, Integrator, StepFailure, non_finite
from mbs.integrators.step_trace import StepTrace

TRACE_KEYS = ("t", "dt", "closed", "penetration", "iterations", "residual", "impulse_work", "pressed", "load_work",
              "damping_loss", "energy", "contact_springs")      # t, dt, Data.last, energies
TRACE_UNITS = {"t": "s", "dt": "s", "closed": "1", "penetration": "m", "iterations": "1", "residual": "m/s",
               "impulse_work": "J", "energy": "J", "pressed": "1", "load_work": "J", "damping_loss": "J",
               "contact_springs": "J"}
TRACE_DTYPES = {"closed": np.int64, "iterations": np.int64, "pressed": np.int64}     # the others float64


class MoreauTimeStepping(Integrator):
    """Moreau's midpoint time-stepping (module docstring)."""

    name = "moreau"

    def __init__(self, system, theta=0.5, solver="gauss-seidel", tol=1e-10, max_iter=2000, trace=False,
                 penetration_bound=None):
        super().__init__(system)
        if penetration_bound is not None and not penetration_bound > 0:
            raise ModelError(f"penetration_bound must be a positive length [m], got {penetration_bound}")
        self.penetration_bound = None if penetration_bound is None else float(penetration_bound)
        if not 0.5 <= theta <= 1.0:
            raise ModelError(f"theta must lie in [0.5, 1], got {theta}")
        self.theta = float(theta)
        self.solver = solver if isinstance(solver, ProxSolver) else ProxSolver(solver, tol=tol, max_iter=max_iter)
        self._trace = StepTrace(TRACE_KEYS, TRACE_DTYPES) if trace else None
        self._work = None           # the StepWork of the run's Model (trace only)

    def options(self):
        return {"theta": self.theta, "solver": self.solver.method}

    def model_options(self):
        return {"theta": self.theta, "solver": self.solver}

    def diagnostics(self):
        """Closed-contact steps summed over contacts, contact-solver iterations, largest
        penetration max(0, −g_N) at a midpoint [m], contact-steps pruned by a planned run."""
        return dict(self.data.stats)

    def start(self, t, q, u):
        self.t, self.q, self.u = t, q, u
        if self._trace is not None and "initial_energy" not in self.data.stats:     # a fresh run's first start
            self.data.stats["initial_energy"] = self.energy()

    def energy(self) -> float:
        """E = T + V [J] of the run's Data: the integrated bodies' kinetic energy, the
        elastic, gravity and spring energies and the compliant contacts' springs
        (:meth:`spring_energy`); a body the plan solves apart stands still in Data."""
        return self._bodies_energy() + self.spring_energy()

    def _bodies_energy(self) -> float:
        data = self.data
        energy = self.model.body_stage.energy(data.q, data.u)
        if energy is None:
            sys = self.system
            energy = sys.kinetic_energy(data.t, data.q, data.u) + sys.potential_energy(data.t, data.q)
        return energy

    def accepted(self, dt):
        last = self.data.last
        if self.penetration_bound is not None and last[1] > self.penetration_bound:
            raise StepFailure(f"penetration {last[1]:.3g} m beyond the bound {self.penetration_bound:.3g} m "
                              "(a contact tunnelled, or a penalty stiffness is too soft for the load)")
        super().accepted(dt)
        if self._trace is not None:
            springs = self.spring_energy()
            energy = self._bodies_energy() + springs
            if not math.isfinite(energy):
                raise non_finite(self.t, self.steps, "energy")
            self._trace.append((self.t, dt, *last, energy, springs))
        last[:] = LAST_STEP

    def _step_work(self) -> StepWork:
        if self._work is None or self._work.model is not self.model:
            self._work = StepWork(self.model)
        return self._work

    trace_units = TRACE_UNITS

    def collect(self, prefix, arrays, kinds):
        """The per-step trace rows so far (``prefix/trace/<key>``)."""
        for key, rows in self.trace().items():
            arrays[f"{prefix}/trace/{key}"], kinds[f"{prefix}/trace/{key}"] = rows, "array"

    def restore(self, prefix, arrays, kinds):
        if self._trace is not None:
            self._trace.load({key: take(f"{prefix}/trace/{key}", None, arrays, kinds)
                              for key in TRACE_KEYS})
        elif any(key.startswith(f"{prefix}/trace/") for key in kinds):
            raise StateMismatch("the checkpoint has a trace, this run keeps none")

    def trace(self, start=0):
        if self._trace is None:
            return {}
        return self._trace.columns(start)

    def contact_closed(self, i) -> bool:
        return bool(self.data.closed[i])

    def contact_force(self, i, out):
        """Set-valued: (n Λ_N + T Λ_T) / Δt of the last step (the mean force over it) [N],
        Λ = Λ₀ + Λ' for a contact through residual flexibility (:mod:`contact.compliance`,
        S2: the warm start Λ' = θΔt F_{k+1} is only the part of the end force);
        single-valued: the law's normal force."""
        model, data = self.model, self.data
        if not (model.set_valued[i] and data.closed[i] and data.warm[i]):
            super().contact_force(i, out)
            return
        at, dim = model.lam_at[i], model.dims[i]
        lam = data.lam_prev[at:at + dim]
        if model.residual is not None and model.residual.compliant[i]:
            lam = lam + data.comp_impulse0[at:at + dim]
        k = model.contacts[i].kinematics
        out[:] = k.n * lam[0]
        if dim == 3:
            out += k.T @ lam[1:]
        elif dim == 2:                      # planar friction: the in-plane tangent T[:, 1]
            out += k.T[:, 1] * lam[1]
        out /= data.h_last

    def step(self, dt):
        stages.step(self.model, self.data, dt)
        if self._trace is not None:                 # the step's energy terms (mbs.run.step_work)
            data, work = self.data, self._step_work()
            last = data.last
            last[5] = max(last[5], work.pressed(data))
            last[6] += work.load_work(data, dt)
            last[7] += work.damping_loss(data, dt)


class AdaptiveMoreauTimeStepping(MoreauTimeStepping):
    """Moreau time-stepping with step-size control by step doubling (module docstring).

    Its parameters besides MoreauTimeStepping's:

    Parameters
    ----------
    atol : float > 0
        Absolute tolerance of the positions q per step [m, or the unit of each
        coordinate: rad-like for quaternions, kg^½ m for modal coordinates].
    rtol : float >= 0
        Relative tolerance [-].
    dt_min : float > 0
        Smallest step [s].
    """

    name = "moreau-adaptive"
    h_next, _pen = CarriedEntry(), CarriedEntry()       # the next step size [s], the last penetration [m]

    def __init__(self, system, atol=1e-6, rtol=1e-4, dt_min=1e-9, gap_tol=None, **options):
        super().__init__(system, **options)
        gap_tol = atol if gap_tol is None else gap_tol
        if not (atol > 0 and rtol >= 0 and dt_min > 0 and gap_tol > 0):
            raise ModelError(f"need atol > 0, rtol >= 0, dt_min > 0 and gap_tol > 0, got {atol}, {rtol}, "
                             f"{dt_min}, {gap_tol}")
        self.atol, self.rtol, self.dt_min, self.gap_tol = float(atol), float(rtol), float(dt_min), float(gap_tol)

    def options(self):
        return {**super().options(), "atol": self.atol, "rtol": self.rtol, "dt_min": self.dt_min,
                "gap_tol": self.gap_tol}

    def _prepare(self, *args):
        state = super()._prepare(*args)
        model, data = self.model, self.data
        data.stats.update(rejected_steps=0, forced_steps=0, smallest_dt=np.inf, largest_dt=0.0)
        self.h_next, self._pen = None, 0.0
        self._saved = CarriedCopy(data)
        self._q_full = np.zeros(model.nq)
        return state

    def start(self, t, q, u):
        super().start(t, q, u)
        self._pen = self._penetration()

    def _penetration(self) -> float:
        """Largest penetration [m] of the unilateral contacts (set-valued and penalty) at
        (t, q, u); their closed flags follow. Located as the detection stage locates
        them: a contact's fused detection updates its contours and locates it in one
        compiled call; the other contours are updated first (each once)."""
        model, data = self.model, self.data
        if not any(model.unilateral):
            return 0.0
        t, q, u = data.t, data.q, data.u
        for contour, owners, qs, us in model.contours:
            if not owners:                  # updated by its contacts' fused detections
                continue
            if qs is None:
                contour.update(None, None, t)
            else:
                contour.update(q[qs], u[us], t)
        pen = 0.0
        for i, c in enumerate(model.contacts):
            if model.unilateral[i]:
                f = model.fused[i]
                data.closed[i] = closed = c.locate() if f is None else f.locate(q, u, t)
                if closed:
                    pen = max(pen, -c.kinematics.g_N)
        return pen

    def _save(self):
        """Keep what a rejected or repeated step puts back: the Data a step reads of the
        steps before it (:data:`mbs.run.model.CARRIED`: t, q, u, closed flags, warm starts,
        compliant springs, counters, the contours' and contacts' run state)."""
        self._saved.save()

    def _restore(self):
        self._saved.restore()
        self.data.last[:] = LAST_STEP

    def advance(self, end, dt):
        """Controlled steps of at most ``dt`` from ``self.t`` to exactly ``end``."""
        stats = lambda: self.data.stats      # noqa: E731  (restored steps replace the dict)
        dt_try = dt if self.h_next is None else min(self.h_next, dt)
        while end - self.t > 1e-14 * max(1.0, abs(end)):
            rest = end - self.t
            dt_try = dt_ctrl = min(max(dt_try, self.dt_min), dt)
            if dt_try >= rest * (1.0 - 1e-9):              # within rounding of ``end``: land on it
                dt_try = rest
            elif dt_try > 0.5 * rest:                      # avoid a sliver before ``end``
                dt_try = 0.5 * rest
            self._save()
            try:
                self.step(dt_try)
                self._q_full[:] = self.q
                self._restore()
                self.step(0.5 * dt_try)
                self.step(0.5 * dt_try)
            except StepFailure:
                if dt_try <= self.dt_min * (1 + 1e-12):
                    raise
                self._restore()                 # e.g. a penalty contact too stiff for H: retake smaller
                stats()["rejected_steps"] += 1
                dt_try = self.h_next = max(0.2 * dt_try, self.dt_min)
                continue
            dq = np.abs(self.q - self._q_full)
            err = float(np.max(dq / (self.atol + self.rtol * np.abs(self.q)))) if dq.size else 0.0
            pen = self._penetration()
            err = max(err, (pen - self._pen) / self.gap_tol)
            factor = 2.0 if err == 0.0 else min(2.0, max(0.2, 0.9 * err ** -0.5))
            if err <= 1.0 or dt_try <= self.dt_min * (1 + 1e-12):
                if err > 1.0:
                    stats()["forced_steps"] += 1
                stats()["smallest_dt"] = min(stats()["smallest_dt"], dt_try)
                stats()["largest_dt"] = max(stats()["largest_dt"], dt_try)
                self.accepted(dt_try)
                self._pen = pen
                self.h_next = max(dt_try * factor, dt_ctrl)        # landing on ``end`` does not shrink H
            else:
                self._restore()
                stats()["rejected_steps"] += 1
                self.h_next = dt_try * factor
            dt_try = self.h_next

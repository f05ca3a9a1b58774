"""Moreau's time-stepping for set-valued contacts and impacts (thesis eq. 3.1, 4.1), as the
θ-method of Moreau–Jean (Acary & Brogliato 2008, Sec. 10.1) on the smooth forces.

One step of size Δt (DESIGN, "the data flow of one Moreau step"):

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
impact laws take out), total energy [J]), ``penetration_bound`` [m] (default None: no
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
a rejected step is retaken with the smaller H. An impact inside a step separates the
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
from scipy.linalg.lapack import dpotrf, dpotrs

from contact.laws import Bilateral
from contact.solver import ContactSet, ProxSolver
from contours import Contour1sNeutralFFR, Contour2sNeutralFFR, PointContour, SphereContour
from ffrmbs.errors import ModelError

from .driver import Integrator, StepFailure, non_finite

NEUTRAL_FFR = (Contour1sNeutralFFR, Contour2sNeutralFFR)
TRACE_KEYS = ("t", "dt", "closed", "penetration", "iterations", "residual", "impulse_work", "energy")
TRACE_UNITS = {"t": "s", "dt": "s", "closed": "1", "penetration": "m", "iterations": "1", "residual": "m/s",
               "impulse_work": "J", "energy": "J"}
TRACE_DTYPES = {"closed": np.int64, "iterations": np.int64}     # the others float64


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
        self.contacts = list(system.contacts)
        contours = {}
        for c in self.contacts:
            for contour in c.contours():
                contours[id(contour)] = contour
        self.contours = list(contours.values())
        self._owners = [(k, [i for i, c in enumerate(self.contacts) if k in c.contours()]) for k in self.contours]
        self._live, self._live_flags = [], [True] * len(self.contacts)   # reused each step
        self.stats = {"closed_contacts": 0, "solver_iterations": 0, "max_penetration": 0.0, "pruned_contacts": 0}
        self._lam = {}
        self._sets = {}
        self._penalty = [c for c in self.contacts if not c.set_valued and c.unilateral and hasattr(c.law, "derivatives")]
        self._w_N = np.zeros(system.nu)
        self._constant = system.constant_iteration_matrix   # factor M̂ once per step size
        self._factors = []                  # (step size, Cholesky factor of M̂)
        self._last = [0, 0.0, 0, 0.0, 0.0]  # this step: most closed contacts, penetration, iterations,
                                            # residual; impulse work
        self._trace = {key: [] for key in TRACE_KEYS} if trace else None

    def options(self):
        return {"theta": self.theta, "solver": self.solver.method}

    def diagnostics(self):
        """Closed-contact steps summed over contacts, contact-solver iterations, largest
        penetration max(0, −g_N) at a midpoint [m], contact-steps pruned by a planned run."""
        return dict(self.stats)

    def start(self, t, q, u):
        self.t, self.q, self.u = t, q.copy(), u.copy()
        self._bounds = [(c, *_sphere_pair(c)) for c in self.contacts]
        idle = self.system.leaving_out
        self._act = None if not idle else np.setdiff1d(
            np.arange(self.system.nu), np.concatenate([np.arange(self.system.nu)[b.u_slice] for b in idle]))

    def accepted(self, h):
        if self.penetration_bound is not None and self._last[1] > self.penetration_bound:
            raise StepFailure(f"penetration {self._last[1]:.3g} m beyond the bound {self.penetration_bound:.3g} m "
                              "(a contact tunnelled, or a penalty stiffness is too soft for the load)")
        super().accepted(h)
        if self._trace is not None:
            sys = self.system
            energy = sys.kinetic_energy(self.t, self.q, self.u) + sys.potential_energy(self.t, self.q)
            if not math.isfinite(energy):
                raise non_finite(self.t, self.steps, "energy")
            for key, value in zip(TRACE_KEYS, (self.t, h, *self._last, energy)):
                self._trace[key].append(value)
        self._last[:] = 0, 0.0, 0, 0.0, 0.0

    trace_units = TRACE_UNITS

    def trace(self, start=0):
        if self._trace is None:
            return {}
        return {key: np.array(values[start:], dtype=TRACE_DTYPES.get(key, np.float64))
                for key, values in self._trace.items()}

    def _check_penalty(self, factor, dt):
        """Stop when a closed single-valued contact is too stiff for its explicit force:
        ω Δt = Δt √(k w_Nᵀ M̂⁻¹ w_N) > 2, k = −∂F_N/∂g_N at the contact point."""
        for c in self._penalty:
            if not (c.closed and c.force_N > 0.0):
                continue
            k = c.kinematics
            stiffness = -float(c.law.derivatives(k.g_N, k.gd_N)[0])
            w = k.W_N(self._w_N)
            s2 = stiffness * dt * dt * float(w @ self._solve(factor, w))
            if s2 > 4.0:
                raise StepFailure(f"penalty contact {c.name!r} too stiff for the step: ω Δt = {s2 ** 0.5:.3g} > 2 "
                                  f"(k = {stiffness:.3g} N/m); take Δt < {2.0 * dt / s2 ** 0.5:.3g} s or a "
                                  "set-valued law")

    def contact_force(self, contact, out):
        """Set-valued: (n Λ_N + T Λ_T) / Δt of the last step (the mean force over it) [N];
        single-valued: the law's normal force."""
        lam = self._lam.get(contact) if contact.set_valued and contact.closed else None
        if lam is None:
            super().contact_force(contact, out)
            return
        k = contact.kinematics
        out[:] = k.n * lam[0]
        if lam.size == 3:
            out += k.T @ lam[1:]
        elif lam.size == 2:                 # planar friction: the in-plane tangent T[:, 1]
            out += k.T[:, 1] * lam[1]
        out /= self._h_last

    def _update_contours(self, t, q, u):
        for contour in self.contours:
            _update_contour(contour, t, q, u)

    def _live_contacts(self, t, q, u):
        """The contacts to locate this step, their contours updated. Unplanned: all. Planned
        (:mod:`mbs.plan`): a unilateral contact only while its two contours' bounding
        spheres (:func:`contour_sphere`) come within its broad-phase margin; the others
        are marked open without touching their contours."""
        if self.plan is None:
            self._update_contours(t, q, u)
            return self.contacts
        live, flags = self._live, self._live_flags
        live.clear()
        for i, (c, s1, s2) in enumerate(self._bounds):
            flags[i] = s2 is None or not _apart(c, s1, s2, q, t)
            if flags[i]:
                live.append(c)
            else:
                c.closed = False
                self.stats["pruned_contacts"] += 1
        for contour, owners in self._owners:
            for i in owners:
                if flags[i]:
                    _update_contour(contour, t, q, u)
                    break
        return live

    def step(self, dt):
        sys = self.system
        th = self.theta
        t_m = self.t + th * dt
        q_m = sys.increment(self.q, th * dt * self.u)
        sys.normalize(q_m)
        if self._constant:
            h = sys.h(t_m, q_m, self.u)
        else:
            M, h = sys.mass_and_h(t_m, q_m, self.u)
        closed = []
        last = self._last            # summed over the sub-steps of one accepted step
        if self.contacts:
            for c in self._live_contacts(t_m, q_m, self.u):
                if c.detect() and c.set_valued:
                    closed.append(c)
                if not c.set_valued:
                    c.add_forces(h)
                last[1] = max(last[1], c.penetration)
            self.stats["max_penetration"] = max(self.stats["max_penetration"], last[1])
        if self._constant:
            for step, factor in self._factors:   # steps landing on output times differ by rounding
                if abs(step - dt) <= 1e-12 * dt:
                    break
            else:
                if len(self._factors) > 8:       # step-size control: keep the latest few
                    self._factors.clear()
                factor = self._factor(t_m, q_m, sys.mass_matrix(t_m, q_m), dt)
                self._factors.append((dt, factor))
        else:
            factor = self._factor(t_m, q_m, M, dt)
        if self._penalty:
            self._check_penalty(factor, dt)
        u_free = self.u + self._solve(factor, dt * h)
        m = sys.n_c + sum(c.dim for c in closed)
        u_prev = self.u
        if m == 0:
            self.u = u_free
            if self._lam:
                self._lam = {}           # nothing closed: no warm start, no resting contact
        else:
            W = np.zeros((sys.nu, m))
            laws = []
            if sys.n_c:
                W[:, :sys.n_c] = sys.constraint_jacobian(t_m, q_m).T
                laws.append(Bilateral(sys.n_c))
            closing = np.zeros(m)
            i = sys.n_c
            for c in closed:
                c.jacobian(W[:, i:i + c.dim])
                laws.append(c.law)
                if c.unilateral and c.kinematics.g_N > 0.0 and c in self._lam:   # resting within closing_tol
                    closing[i] = c.kinematics.g_N / dt
                i += c.dim
            offset = np.zeros(m)
            if sys.n_c:
                offset[:sys.n_c] = sys.constraint_velocity_term(t_m, q_m)
            MW = self._solve(factor, W)
            G = W.T @ MW
            xi_free = W.T @ u_free + offset + closing
            gamma_pre = W.T @ self.u + offset
            sol = self.solver.solve(self._contact_set(closed, laws), G, xi_free, gamma_pre,
                                    self._warm(closed, m), validate=False)
            if not sol.converged:
                raise StepFailure(f"contact problem not solved: residual {sol.residual:.3g} m/s after "
                                  f"{sol.iterations} iterations ({len(closed)} closed contacts)")
            self.stats["solver_iterations"] += sol.iterations
            last[2] += sol.iterations
            last[3] = max(last[3], sol.residual)
            last[4] += 0.5 * float(sol.lam @ (sol.gamma_plus - closing + gamma_pre))
            self._store(closed, sol.lam)
            self.u = u_free + MW @ sol.lam
        self.stats["closed_contacts"] += len(closed)
        last[0] = max(last[0], len(closed))
        du = th * dt * self.u if th == 0.5 else th * dt * self.u + (1.0 - 2.0 * th) * dt * u_prev
        self.q = sys.increment(q_m, du)
        sys.normalize(self.q)
        self.t += dt
        self._h_last = dt

    def _factor(self, t_m, q_m, M, dt):
        """Cholesky factor of M̂ = M + θΔt D + θ²Δt² K with the tangents at q_θ."""
        K, D = self.system.tangents(t_m, q_m, self.u)  # elastic, damping and link (spring) tangents
        th = self.theta
        M_hat = M + th * dt * D + th * th * dt * dt * K
        if self._act is not None:
            M_hat = M_hat[np.ix_(self._act, self._act)]
        factor, info = dpotrf(M_hat, lower=True, overwrite_a=True)
        if info != 0:
            raise StepFailure(f"M + θΔt D + θΔt² K is not positive definite (LAPACK dpotrf info {info})")
        return factor

    def _solve(self, factor, rhs):
        """M̂⁻¹ rhs for rhs (nu,) or (nu, m); on the active rows only when a planned run left
        bodies out (zero on theirs: their blocks of M̂ are decoupled from the rest)."""
        if self._act is None:
            return dpotrs(factor, rhs, lower=True)[0]
        out = np.zeros_like(rhs)
        out[self._act] = dpotrs(factor, rhs[self._act], lower=True)[0]
        return out

    def _contact_set(self, closed, laws):
        """The ContactSet of this active set, built once per set of closed contacts."""
        key = tuple(closed)              # the contacts themselves: keys survive a checkpoint
        cs = self._sets.get(key)
        if cs is None:
            cs = self._sets[key] = ContactSet(laws)
        return cs

    def _warm(self, closed, m):
        """Λ of the previous step for contacts closed again (joints first), else zero."""
        lam = np.zeros(m)
        i = self.system.n_c
        if i and "joints" in self._lam and self._lam["joints"].size == i:
            lam[:i] = self._lam["joints"]
        for c in closed:
            prev = self._lam.get(c)
            if prev is not None:
                lam[i:i + c.dim] = prev
            i += c.dim
        return lam

    def _store(self, closed, lam):
        i = self.system.n_c
        self._lam = {"joints": lam[:i].copy()}
        for c in closed:
            self._lam[c] = lam[i:i + c.dim].copy()
            i += c.dim



class AdaptiveMoreauTimeStepping(MoreauTimeStepping):
    """Moreau time-stepping with step-size control by step doubling (module docstring).

    Parameters (besides MoreauTimeStepping's)
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

    def __init__(self, system, atol=1e-6, rtol=1e-4, dt_min=1e-9, gap_tol=None, **options):
        super().__init__(system, **options)
        gap_tol = atol if gap_tol is None else gap_tol
        if not (atol > 0 and rtol >= 0 and dt_min > 0 and gap_tol > 0):
            raise ModelError(f"need atol > 0, rtol >= 0, dt_min > 0 and gap_tol > 0, got {atol}, {rtol}, "
                             f"{dt_min}, {gap_tol}")
        self.atol, self.rtol, self.dt_min, self.gap_tol = float(atol), float(rtol), float(dt_min), float(gap_tol)
        self.unilateral = [c for c in self.contacts if c.unilateral]     # set-valued and penalty
        self.h_next = None
        self._pen = 0.0
        self.stats.update(rejected_steps=0, forced_steps=0, smallest_dt=np.inf, largest_dt=0.0)

    def options(self):
        return {**super().options(), "atol": self.atol, "rtol": self.rtol, "dt_min": self.dt_min,
                "gap_tol": self.gap_tol}

    def start(self, t, q, u):
        super().start(t, q, u)
        self._pen = self._penetration()

    def _penetration(self) -> float:
        """Largest penetration [m] of the unilateral contacts (set-valued and penalty) at (t, q, u)."""
        if not self.unilateral:
            return 0.0
        self._update_contours(self.t, self.q, self.u)
        pen = 0.0
        for c in self.unilateral:
            c.detect()
            pen = max(pen, c.penetration)
        return pen

    def _save(self):
        return (self.t, self.q.copy(), self.u.copy(), dict(self._lam), dict(self.stats))

    def _restore(self, saved):
        self.t, q, u, lam, stats = saved
        self.q, self.u, self._lam, self.stats = q.copy(), u.copy(), dict(lam), dict(stats)
        self._last[:] = 0, 0.0, 0, 0.0, 0.0

    def advance(self, end, dt):
        """Controlled steps of at most ``dt`` from ``self.t`` to exactly ``end``."""
        h = dt if self.h_next is None else min(self.h_next, dt)
        while end - self.t > 1e-14 * max(1.0, abs(end)):
            rest = end - self.t
            h = h_ctrl = min(max(h, self.dt_min), dt)
            if h >= rest * (1.0 - 1e-9):              # within rounding of ``end``: land on it
                h = rest
            elif h > 0.5 * rest:                      # avoid a sliver before ``end``
                h = 0.5 * rest
            saved = self._save()
            try:
                self.step(h)
                q_full = self.q
                self._restore(saved)
                self.step(0.5 * h)
                self.step(0.5 * h)
            except StepFailure:
                if h <= self.dt_min * (1 + 1e-12):
                    raise
                self._restore(saved)                  # e.g. a penalty contact too stiff for H: retake smaller
                self.stats["rejected_steps"] += 1
                h = self.h_next = max(0.2 * h, self.dt_min)
                continue
            dq = np.abs(self.q - q_full)
            err = float(np.max(dq / (self.atol + self.rtol * np.abs(self.q)))) if dq.size else 0.0
            pen = self._penetration()
            err = max(err, (pen - self._pen) / self.gap_tol)
            factor = 2.0 if err == 0.0 else min(2.0, max(0.2, 0.9 * err ** -0.5))
            if err <= 1.0 or h <= self.dt_min * (1 + 1e-12):
                if err > 1.0:
                    self.stats["forced_steps"] += 1
                self.stats["smallest_dt"] = min(self.stats["smallest_dt"], h)
                self.stats["largest_dt"] = max(self.stats["largest_dt"], h)
                self.accepted(h)
                self._pen = pen
                self.h_next = max(h * factor, h_ctrl)        # landing on ``end`` does not shrink H
            else:
                self._restore(saved)
                self.stats["rejected_steps"] += 1
                self.h_next = h * factor
            h = self.h_next


def _update_contour(contour, t, q, u):
    """Update one contour at the global state (q, u, t) (ground contours take None)."""
    body = contour.body
    if body is None:
        contour.update(None, None, t)
    else:
        contour.update(q[body.q_slice], u[body.u_slice], t)


def contour_sphere(contour):
    """A function (q, t) -> (centre (3,) [m], radius [m]) of a sphere holding ``contour``
    at the global state, or None: a point or sphere contour about its frame's position;
    a neutral contour of a flexible body within its body's sphere
    (:meth:`mbs.body.Body.bounding_sphere`; the interpolant's overshoot beyond the nodes
    is far below the broad-phase margin); anything else (planes, derived contours)
    cannot be bounded."""
    body = contour.body
    if isinstance(contour, (PointContour, SphereContour)) and body is not None:
        frame, radius = contour.frame_ref, getattr(contour, "radius", 0.0)
        return lambda q, t: (frame.position(q[body.q_slice], t), radius)
    if isinstance(contour, NEUTRAL_FFR):
        return lambda q, t: body.bounding_sphere(q[body.q_slice], t)
    return None


def _apart(contact, sphere1, sphere2, q, t) -> bool:
    """True when the contact's two contours are certainly farther apart than its margin."""
    c1, r1 = sphere1(q, t)
    c2, r2 = sphere2(q, t)
    d = c1 - c2
    reach = r1 + r2 + contact.margin
    return float(d @ d) > reach * reach


def _sphere_pair(contact):
    """(sphere1, sphere2) functions of a prunable contact (unilateral, with a margin, both
    contours bounded), else (None, None)."""
    if not (contact.unilateral and contact.margin is not None):
        return None, None
    s1, s2 = contour_sphere(contact.kinematics.contour1), contour_sphere(contact.kinematics.contour2)
    return (s1, s2) if s1 is not None and s2 is not None else (None, None)

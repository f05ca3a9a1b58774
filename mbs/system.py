"""System: bodies and links assembled into M(q) u̇ = h(q, u, t) + W λ, g(q, t) = 0.

The System owns the flat state arrays: q (nq,) and u (nu,) with q̇ = Y(q) u (thesis
eq. 3.1a); every body gets its slices when added. It assembles the block-diagonal mass
matrix, the smooth forces h (bodies' Q_v − K q − D u, gravity, force elements), the
constraint residuals g, their Jacobian C_q (W = C_qᵀ) and accelerations terms γ,
and reports energies and momenta. ``simulate`` runs an integrator of
:mod:`mbs.integrators` and returns a :class:`~mbs.result.Result`.

Example::

    system = System(gravity=(0, 0, -9.81))
    beam = system.add(FlexibleBodyFFR.from_file("beam.h5", modes=10))
    system.add(Joint.revolute(system.ground, beam.origin, axis=(0, 1, 0)))
    result = system.simulate(t_end=1.0, dt=1e-3, outputs={"tip": beam.node(12)})
"""

from __future__ import annotations

import logging

import numpy as np
import scipy.linalg

from ffrmbs.errors import ModelError

from .body import Body, Frame, ground_frame
from .link import Constraint, ForceElement, add_point_force, body_q


class System:
    """A multibody system (see module docstring). ``gravity`` (3,) [m/s²]."""

    def __init__(self, gravity=(0.0, 0.0, 0.0)):
        self.gravity = np.asarray(gravity, dtype=float).reshape(3)
        self.bodies: list[Body] = []
        self.forces: list[ForceElement] = []
        self.constraints: list[Constraint] = []
        self.contacts: list = []  # contact.Contact, contact.CurveConstraint (Moreau time-stepping)
        self.ground = ground_frame()
        self.nq = self.nu = self.n_c = 0
        self._com = []
        self._idle = ()     # bodies a planned run solves apart (mbs.plan), left out of the equations
        self._idle_forces = ()

    # --- building -----------------------------------------------------------------------
    def add(self, item):
        """Add a body, a force element or a constraint; returns it (for chaining)."""
        if isinstance(item, Body):
            if item.q_slice is not None:
                raise ModelError(f"body {item.name!r} already belongs to a system")
            item.q_slice = slice(self.nq, self.nq + item.nq)
            item.u_slice = slice(self.nu, self.nu + item.nu)
            self.nq += item.nq
            self.nu += item.nu
            self.bodies.append(item)
            self._com.append(item.com_frame())
        elif isinstance(item, (ForceElement, Constraint)) or getattr(item, "is_contact", False):
            for body in item.bodies():
                if body is not None and body not in self.bodies:
                    raise ModelError(f"{type(item).__name__} acts on body {body.name!r}, "
                                     "which is not in the system: add the body first")
            if isinstance(item, Constraint):
                self.constraints.append(item)
                self.n_c += item.n_c
            elif getattr(item, "is_contact", False):
                self.contacts.append(item)
            else:
                self.forces.append(item)
        else:
            raise ModelError(f"cannot add {item!r} to a System: expected a body, a force "
                             "element, a constraint or a contact")
        return item

    def frame(self, position=(0.0, 0.0, 0.0), orientation=None, name=None) -> Frame:
        """A frame fixed in the inertial frame."""
        return ground_frame(position, orientation, name or "ground")

    # --- state --------------------------------------------------------------------------
    def initial_state(self):
        """(q0, u0): the bodies' initial states concatenated (copies)."""
        if not self.bodies:
            raise ModelError("the system has no bodies")
        q = np.concatenate([b.q_init for b in self.bodies])
        u = np.concatenate([b.u_init for b in self.bodies])
        return q, u

    def qdot(self, q, u):
        """q̇ = Y(q) u (thesis eq. 3.1a)."""
        out = np.empty(self.nq) if not self._idle else np.zeros(self.nq)
        for b in self._active():
            out[b.q_slice] = b.qdot(q[b.q_slice], u[b.u_slice])
        return out

    def increment(self, q, du):
        """q ⊕ Δu, exact for rotations (exponential map); idle bodies keep their q
        (their Δu is zero). One vector sum when no active body has rotation coordinates."""
        active = self._active()
        if all(b.additive for b in active):
            return q + du
        out = np.empty(self.nq) if not self._idle else q.copy()
        for b in active:
            out[b.q_slice] = b.increment(q[b.q_slice], du[b.u_slice])
        return out

    def normalize(self, q):
        for b in self._active():
            if not b.additive:
                b.normalize(q[b.q_slice])

    # --- planned runs -------------------------------------------------------------------
    def plan(self, t_end, tolerance=None, outputs=None):
        """The scene plan for a run to ``t_end`` [s] (:mod:`mbs.plan`): per body the
        cheapest formulation within ``tolerance`` [m] (default 1e-6, shared half and half
        by neglected coupling and dropped modes) and what it leaves out; ``outputs`` the
        requested outputs. ``print(system.plan(1.0))`` shows it."""
        from .plan import TOLERANCE, make_plan

        return make_plan(self, t_end, TOLERANCE if tolerance is None else tolerance, outputs)

    def leave_out(self, bodies=(), forces=()):
        """Leave ``bodies`` and ``forces`` out of M, h, the tangents and the increments
        (identity mass block, zero force) until the next call; ``leave_out()`` restores
        all. A planned run leaves out the bodies it solves apart."""
        self._idle, self._idle_forces = tuple(bodies), tuple(forces)
        self._active_bodies = [b for b in self.bodies if b not in self._idle]
        self._active_force_list = [f for f in self.forces if f not in self._idle_forces]

    @property
    def leaving_out(self) -> tuple:
        """The bodies :meth:`leave_out` currently leaves out."""
        return self._idle

    def _active(self):
        return self._active_bodies if self._idle else self.bodies

    def _active_forces(self):
        return self._active_force_list if self._idle_forces else self.forces

    def _idle_identity(self, M):
        for b in self._idle:
            np.fill_diagonal(M[b.u_slice, b.u_slice], 1.0)

    # --- dynamics -----------------------------------------------------------------------
    def mass_matrix(self, t, q):
        """Block-diagonal M (nu, nu) [kg, kg m, kg m²]."""
        M = np.zeros((self.nu, self.nu))
        for b in self._active():
            M[b.u_slice, b.u_slice] = b.mass_matrix(q[b.q_slice], t)
        self._idle_identity(M)
        return M

    def h(self, t, q, u):
        """Smooth generalized forces h (nu,): bodies' Q_v − K q − D u, gravity, links."""
        out = np.empty(self.nu) if not self._idle else np.zeros(self.nu)
        for b in self._active():
            out[b.u_slice] = b.h(q[b.q_slice], u[b.u_slice], t)
        self._add_external(t, q, u, out)
        return out

    def mass_and_h(self, t, q, u):
        """(M, h) in one pass over the bodies (what an implicit step needs per iteration)."""
        M = np.zeros((self.nu, self.nu))
        out = np.empty(self.nu) if not self._idle else np.zeros(self.nu)
        for b in self._active():
            M[b.u_slice, b.u_slice], out[b.u_slice] = b.mass_and_h(q[b.q_slice], u[b.u_slice], t)
        self._idle_identity(M)
        self._add_external(t, q, u, out)
        return M, out

    def _add_external(self, t, q, u, out):
        """Gravity and force elements into ``out``."""
        if self.gravity.any():
            for b, com in zip(self.bodies, self._com):
                if b not in self._idle:
                    add_point_force(com, q, t, b.mass * self.gravity, out)
        for f in self._active_forces():
            f.add_forces(t, q, u, out)

    @property
    def constant_iteration_matrix(self) -> bool:
        """True when M, the bodies' tangents K and D and the links' (none) do not change:
        every body has a constant mass matrix (point masses, FFR bodies on a prescribed
        frame) and no force element has tangents."""
        return all(b.constant_mass for b in self._active()) and not any(f.has_tangents for f in self._active_forces())

    def tangents(self, t, q, u):
        """(K_t, D_t) (nu, nu): constant elastic and damping tangents plus link tangents,
        for the iteration matrix of implicit integrators."""
        K = np.zeros((self.nu, self.nu))
        D = np.zeros((self.nu, self.nu))
        for b in self._active():
            Kb, Db = b.stiffness_tangent(), b.damping_tangent()
            if Kb is not None:
                K[b.u_slice, b.u_slice] += Kb
            if Db is not None:
                D[b.u_slice, b.u_slice] += Db
        for f in self._active_forces():
            f.add_tangents(t, q, u, K, D)
        return K, D

    def constraint_residual(self, t, q):
        """g(q, t) (n_c,) [m or rad]."""
        return np.concatenate([c.residual(t, q) for c in self.constraints]) \
            if self.constraints else np.zeros(0)

    def constraint_jacobian(self, t, q):
        """C_q (n_c, nu); W = C_qᵀ."""
        C = np.zeros((self.n_c, self.nu))
        i = 0
        for c in self.constraints:
            c.jacobian(t, q, C[i:i + c.n_c])
            i += c.n_c
        return C

    def constraint_velocity_term(self, t, q):
        return np.concatenate([c.velocity_term(t, q) for c in self.constraints]) \
            if self.constraints else np.zeros(0)

    def constraint_bias(self, t, q, u):
        """γ (n_c,) with g̈ = C_q u̇ + γ."""
        return np.concatenate([c.bias(t, q, u) for c in self.constraints]) \
            if self.constraints else np.zeros(0)

    def accelerations(self, t, q, u, baumgarte=(0.0, 0.0)):
        """(u̇, λ) from [[M, −C_qᵀ], [C_q, 0]] (u̇, λ) = (h, −γ − 2a ġ − b² g): the
        index-1 form, with Baumgarte's stabilization terms a [1/s], b [1/s] if given.
        Sign convention: reaction forces W λ = C_qᵀ λ enter as M u̇ = h + W λ."""
        M, h = self.mass_and_h(t, q, u)
        if not self.n_c:
            return scipy.linalg.solve(M, h, assume_a="pos", check_finite=False), np.zeros(0)
        C = self.constraint_jacobian(t, q)
        a, b = baumgarte
        rhs_c = -self.constraint_bias(t, q, u)
        if a or b:
            g = self.constraint_residual(t, q)
            gd = C @ u + self.constraint_velocity_term(t, q)
            rhs_c -= 2 * a * gd + b * b * g
        n = self.nu
        K = np.zeros((n + self.n_c, n + self.n_c))
        K[:n, :n] = M
        K[:n, n:] = -C.T
        K[n:, :n] = C
        sol = np.linalg.solve(K, np.concatenate((h, rhs_c)))
        return sol[:n], sol[n:]

    # --- energies and momenta ----------------------------------------------------------
    def kinetic_energy(self, t, q, u):
        return sum(b.kinetic_energy(q[b.q_slice], u[b.u_slice], t) for b in self.bodies)

    def potential_energy(self, t, q):
        """Elastic energy of the bodies, gravity (−m g·r_com) and links' stored energy [J]."""
        e = sum(b.elastic_energy(q[b.q_slice]) for b in self.bodies)
        if self.gravity.any():
            e -= sum(b.mass * self.gravity @ com.position(body_q(com, q), t)
                     for b, com in zip(self.bodies, self._com))
        return e + sum(f.potential_energy(t, q) for f in self.forces)

    def total_energy(self, t, q, u):
        return self.kinetic_energy(t, q, u) + self.potential_energy(t, q)

    def linear_momentum(self, t, q, u):
        """Σ over bodies of Σ m ṙ [kg m/s]."""
        return sum(b.linear_momentum(q[b.q_slice], u[b.u_slice], t) for b in self.bodies)

    def angular_momentum(self, t, q, u):
        """Σ m r × ṙ about the inertial origin [kg m²/s]."""
        return sum(b.angular_momentum(q[b.q_slice], u[b.u_slice], t) for b in self.bodies)

    # --- simulation ---------------------------------------------------------------------
    def simulate(self, t_end, dt, integrator="generalized-alpha", t_out=None, outputs=None,
                 energies=False, q0=None, u0=None, breakpoints=(), plan=True, tolerance=None, contacts=False,
                 recorder=None, progress=None, **options):
        """Integrate from t = 0 to ``t_end`` [s] with step ``dt`` [s].

        ``integrator``: "generalized-alpha" (implicit, default; option ``rho_inf``),
        "rk4" (explicit; option ``baumgarte``), "moreau" (time-stepping for contacts and
        impacts; options ``theta``, ``solver``, ``trace``) or "moreau-adaptive" (step
        doubling; ``dt`` the largest step; options ``atol``, ``rtol``, ``dt_min``). ``t_out``: output times (default: every
        step); the integrator lands exactly on each. ``outputs``: {name: Frame (its
        position is recorded) or callable(t, q, u) -> array}. ``energies``: also record
        kinetic and potential energy. ``breakpoints``: times [s] where loads jump, added to
        those the force elements declare (step tables, force files); the integrator stops
        just before each and restarts there. Returns a :class:`~mbs.result.Result`; a diverging
        run raises :class:`~ffrmbs.errors.SimulationError` whose ``result`` holds what
        was computed up to then.

        ``plan`` (default True): plan the scene first (:meth:`plan`, :mod:`mbs.plan`;
        logged on the "ffrmbs.plan" logger and kept in ``Result.plan``) and solve the
        bodies it assigns to exact modal propagation or SimpleRB apart from the
        integrator, within ``tolerance`` [m]; a :class:`~mbs.plan.Plan` from
        :meth:`plan` is used as given; ``plan=False`` integrates every body with
        ``integrator`` and updates every contour each step.

        ``contacts``: also record each contact's state at the outputs (``Result.contacts``).
        ``recorder``: streams the samples to a result file while the run goes and takes
        checkpoints (:class:`mbs.result_file.ResultRecorder`); ``progress``: a callable
        (t) called after each output time (e.g. :func:`ffrmbs_app.progress.progress_bar`).
        """
        from .integrators import integrator_class

        if q0 is None or u0 is None:
            q_init, u_init = self.initial_state()
            q0 = q_init if q0 is None else np.asarray(q0, dtype=float)
            u0 = u_init if u0 is None else np.asarray(u0, dtype=float)
        the_plan = None
        if plan is True:
            the_plan = self.plan(t_end, tolerance, outputs=outputs)
        elif plan:
            the_plan = plan
        if the_plan is not None:
            logging.getLogger("ffrmbs.plan").info("%s", the_plan)
        return integrator_class(integrator)(self, **options).run(
            q0, u0, t_end, dt, t_out, outputs or {}, energies,
            set(breakpoints).union(*(f.breakpoints() for f in self.forces)), the_plan,
            recorder=recorder, progress=progress, contacts=contacts)

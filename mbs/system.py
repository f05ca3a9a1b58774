"""System: bodies and links assembled into M(q) u̇ = h(q, u, t) + W λ, g(q, t) = 0.

The System owns the flat state arrays: q (nq,) and u (nu,) with q̇ = Y(q) u (thesis
eq. 3.1a); its bodies' rows of them follow the order they were added in (:meth:`System.layout`).
A body may belong to several Systems: it holds as ``q_slice``, ``u_slice`` the rows of the
System that placed it last — when it was added, when that System was compiled or asked
for its equations, and when a run's Data is made. Its equations of motion — the
block-diagonal mass matrix, the smooth forces h (bodies' Q_v − K q − D u, gravity,
force elements), the constraint residuals g, their Jacobian C_q (W = C_qᵀ) and
acceleration terms γ, energies — come from :class:`~mbs.run.equations.Equations` over all
its bodies; a run compiles the System into a :class:`~mbs.run.model.Model` and never
mutates it. ``simulate`` runs an integrator of
:mod:`mbs.integrators` and returns a :class:`~mbs.results.result.Result`.

Example::

    system = System(gravity=(0, 0, -9.81))
    beam = system.add(FlexibleBodyFFR.from_file("beam.h5", modes=10))
    system.add(Joint.revolute(system.ground, beam.origin, axis=(0, 1, 0)))
    result = system.simulate(t_end=1.0, dt=1e-3, outputs={"tip": beam.node(12)})

``static_equilibrium()`` replaces the bodies' initial state by their rest under gravity
and the loads (:mod:`mbs.run.static`).
"""

from __future__ import annotations

import logging

import numpy as np

from contact.contact import ContactElement
from contact.face import FaceContact
from ffrmbs.errors import ModelError

from mbs.bodies.body import Body, Frame, ground_frame, place_bodies
from mbs.run.equations import Equations
from mbs.links.link import Constraint, ForceElement


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
        self.com_frames = []     # each body's centre-of-mass frame (gravity)
        self.cache_dir = None    # where preprocessing reused between runs is kept (residual
                                 # flexibility of contours, mbs.run.residual_contact); None: not kept
        self._equations = None

    # --- building -----------------------------------------------------------------------
    def add(self, item):
        """Add a body, a force element, a constraint or a contact (a face contact: each of
        its point contacts); returns it (for chaining)."""
        if isinstance(item, Body):
            if any(item is b for b in self.bodies):
                raise ModelError(f"body {item.name!r} is already in this system")
            item.q_slice = slice(self.nq, self.nq + item.nq)
            item.u_slice = slice(self.nu, self.nu + item.nu)
            self.nq += item.nq
            self.nu += item.nu
            self.bodies.append(item)
            self.com_frames.append(item.com_frame())
        elif isinstance(item, FaceContact):
            for point in item.contacts():
                self.add(point)
        elif isinstance(item, (ForceElement, Constraint, ContactElement)):
            for body in item.bodies():
                if body is not None and body not in self.bodies:
                    raise ModelError(f"{type(item).__name__} acts on body {body.name!r}, "
                                     "which is not in the system: add the body first")
            if isinstance(item, Constraint):
                self.constraints.append(item)
                self.n_c += item.n_c
            elif isinstance(item, ContactElement):
                self.contacts.append(item)
            else:
                self.forces.append(item)
        else:
            raise ModelError(f"cannot add {item!r} to a System: expected a body, a force "
                             "element, a constraint, a contact or a face contact")
        return item

    def frame(self, position=(0.0, 0.0, 0.0), orientation=None, name=None) -> Frame:
        """A frame fixed in the inertial frame."""
        return ground_frame(position, orientation, name or "ground")

    def layout(self) -> tuple:
        """((body, q_slice, u_slice), …): each body's rows of this System's q and u, in the
        order the bodies were added; the bodies take them as their ``q_slice``, ``u_slice``."""
        layout, nq, nu = [], 0, 0
        for b in self.bodies:
            layout.append((b, slice(nq, nq + b.nq), slice(nu, nu + b.nu)))
            nq, nu = nq + b.nq, nu + b.nu
        place_bodies(layout)
        return tuple(layout)

    # --- state --------------------------------------------------------------------------
    def initial_state(self):
        """(q0, u0): the bodies' initial states concatenated (copies)."""
        if not self.bodies:
            raise ModelError("the system has no bodies")
        q = np.concatenate([b.q_init for b in self.bodies])
        u = np.concatenate([b.u_init for b in self.bodies])
        return q, u

    def static_equilibrium(self, t=0.0, bodies=None, tol=1e-10, max_iter=30):
        """Put ``bodies`` (default: all; bodies or names) at rest in static equilibrium
        under gravity and the loads at time ``t`` [s], held by joints, springs, fixed
        frames and resting contacts, as their initial state; returns (q, u). The others
        keep their given state. :func:`mbs.run.static.static_equilibrium` (Newton's method on
        h(q, 0, t) + W λ = 0, g(q) = 0; for a clamped FFR body K_ff q_f = Q_f)."""
        from mbs.run.static import static_equilibrium

        self.layout()
        return static_equilibrium(self, t, bodies, tol, max_iter)

    def equations(self):
        """The :class:`~mbs.run.equations.Equations` of all bodies and force elements (rebuilt
        when the System grows)."""
        self.layout()
        key = (len(self.bodies), len(self.forces), len(self.constraints))
        if self._equations is None or self._equations[0] != key:
            self._equations = (key, Equations(self))
        return self._equations[1]

    def qdot(self, q, u):
        """q̇ = Y(q) u (thesis eq. 3.1a)."""
        return self.equations().qdot(q, u)

    def increment(self, q, du):
        """q ⊕ Δu, exact for rotations (exponential map)."""
        return self.equations().increment(q, du)

    def normalize(self, q):
        """Renormalize the orientation coordinates in place."""
        self.equations().normalize(q)

    # --- planned runs -------------------------------------------------------------------
    def plan(self, t_end, tolerance=None, outputs=None):
        """The scene plan for a run to ``t_end`` [s] (:mod:`mbs.run.plan`): per body the
        cheapest formulation within ``tolerance`` [m] (default 1e-6, shared half and half
        by neglected coupling and dropped modes) and what it leaves out; ``outputs`` the
        requested outputs. ``print(system.plan(1.0))`` shows it."""
        from mbs.run.plan import TOLERANCE, make_plan

        self.layout()
        return make_plan(self, t_end, TOLERANCE if tolerance is None else tolerance, outputs)

    # --- dynamics (:class:`~mbs.run.equations.Equations` over all bodies) ------------------
    def mass_matrix(self, t, q):
        """Block-diagonal M (nu, nu) [kg, kg m, kg m²]."""
        return self.equations().mass_matrix(t, q)

    def h(self, t, q, u):
        """Smooth generalized forces h (nu,): bodies' Q_v − K q − D u, gravity, links."""
        return self.equations().h(t, q, u)

    def mass_and_h(self, t, q, u):
        """(M, h) in one pass over the bodies (what an implicit step needs per iteration)."""
        return self.equations().mass_and_h(t, q, u)

    @property
    def constant_iteration_matrix(self) -> bool:
        """True when M, the bodies' tangents K and D and the links' (none) do not change:
        every body has a constant mass matrix (point masses, FFR bodies on a prescribed
        frame) and no force element has tangents."""
        return self.equations().constant_iteration_matrix

    def tangents(self, t, q, u):
        """(K_t, D_t) (nu, nu): constant elastic and damping tangents plus link tangents,
        for the iteration matrix of implicit integrators."""
        return self.equations().tangents(t, q, u)

    def constraint_residual(self, t, q):
        """g(q, t) (n_c,) [m or rad]."""
        return self.equations().constraint_residual(t, q)

    def constraint_jacobian(self, t, q):
        """C_q (n_c, nu); W = C_qᵀ."""
        return self.equations().constraint_jacobian(t, q)

    def constraint_velocity_term(self, t, q):
        """∂g/∂t (n_c,): ġ = C_q u + ∂g/∂t."""
        return self.equations().constraint_velocity_term(t, q)

    def constraint_bias(self, t, q, u):
        """γ (n_c,) with g̈ = C_q u̇ + γ."""
        return self.equations().constraint_bias(t, q, u)

    def accelerations(self, t, q, u, baumgarte=(0.0, 0.0)):
        """(u̇, λ) of the index-1 form (:meth:`mbs.run.equations.Equations.accelerations`)."""
        return self.equations().accelerations(t, q, u, baumgarte)

    # --- energies and momenta ----------------------------------------------------------
    def kinetic_energy(self, t, q, u):
        """Σ over bodies of their kinetic energy [J]."""
        return self.equations().kinetic_energy(t, q, u)

    def potential_energy(self, t, q):
        """Elastic energy of the bodies, gravity (−m g·r_com) and links' stored energy [J]."""
        return self.equations().potential_energy(t, q)

    def total_energy(self, t, q, u):
        return self.kinetic_energy(t, q, u) + self.potential_energy(t, q)

    def linear_momentum(self, t, q, u):
        """Σ over bodies of Σ m ṙ [kg m/s]."""
        self.layout()
        return sum(b.linear_momentum(q[b.q_slice], u[b.u_slice], t) for b in self.bodies)

    def angular_momentum(self, t, q, u):
        """Σ m r × ṙ about the inertial origin [kg m²/s]."""
        self.layout()
        return sum(b.angular_momentum(q[b.q_slice], u[b.u_slice], t) for b in self.bodies)

    # --- simulation ---------------------------------------------------------------------
    def compile(self, t_end, integrator="generalized-alpha", plan=True, tolerance=None, outputs=None, **options):
        """(Model, Data) of a run to ``t_end`` [s] with ``integrator`` and its ``options``,
        planned as :meth:`simulate` plans (``plan``, ``tolerance``, ``outputs``): the
        compiled Model (:mod:`mbs.run.model`) that :meth:`simulate` runs on when given it
        as ``model`` — for several runs of one scene (another Δt or t_end, the warm-up
        and the check of a job), each with a new Data from the same start — and a Data of it.
        The contours and contacts hold views of the state of the Data made last
        (:mod:`mbs.run.contact_state`): one run at a time per Model."""
        from mbs.integrators import integrator_class

        integ = integrator_class(integrator)(self, **options)
        integ.compile(self._plan(t_end, plan, tolerance, outputs))
        return integ.model, integ.data

    def _plan(self, t_end, plan, tolerance, outputs):
        """The scene plan :meth:`simulate` takes for ``plan`` (True: made and logged; a
        Plan: as given; False or None: none)."""
        the_plan = None
        if plan is True:
            the_plan = self.plan(t_end, tolerance, outputs=outputs)
        elif plan:
            the_plan = plan
        if the_plan is not None:
            logging.getLogger("ffrmbs.plan").info("%s", the_plan)
        return the_plan

    def simulate(self, t_end, dt, integrator="generalized-alpha", t_out=None, outputs=None,
                 energies=False, q0=None, u0=None, breakpoints=(), plan=True, tolerance=None, contacts=False,
                 recorder=None, progress=None, checkpoint=None, model=None, **options):
        """Integrate from t = 0 to ``t_end`` [s] with step ``dt`` [s].

        ``integrator``: "generalized-alpha" (implicit, default; option ``rho_inf``),
        "rk4" (explicit; option ``baumgarte``), "moreau" (time-stepping for contacts and
        impacts; options ``theta``, ``solver``, ``trace``) or "moreau-adaptive" (step
        doubling; ``dt`` the largest step; options ``atol``, ``rtol``, ``dt_min``). ``t_out``: output times (default: every
        step); the integrator lands exactly on each. ``outputs``: {name: Frame (its
        position is recorded) or callable(t, q, u) -> array}. ``energies``: also record
        kinetic and potential energy. ``breakpoints``: times [s] where loads jump, added to
        those the force elements declare (step tables, force files); the integrator stops
        just before each and restarts there. Returns a :class:`~mbs.results.result.Result`; a diverging
        run raises :class:`~ffrmbs.errors.SimulationError` whose ``result`` holds what
        was computed up to then.

        ``plan`` (default True): plan the scene first (:meth:`plan`, :mod:`mbs.run.plan`;
        logged on the "ffrmbs.plan" logger and kept in ``Result.plan``) and solve the
        bodies it assigns to exact modal propagation or SimpleRB apart from the
        integrator, within ``tolerance`` [m]; a :class:`~mbs.run.plan.Plan` from
        :meth:`plan` is used as given; ``plan=False`` integrates every body with
        ``integrator`` and updates every contour each step.

        ``contacts``: also record each contact's state at the outputs (``Result.contacts``).
        ``recorder``: streams the samples to a result file while the run goes and takes
        checkpoints (:class:`mbs.results.result_file.ResultRecorder`); ``progress``: a callable
        (t) called after each output time (e.g. :func:`ffrmbs_app.progress.progress_bar`).
        ``checkpoint``: a :class:`mbs.results.checkpoint.Checkpoint` of this same run (same
        arguments, same System built afresh): the run continues from it
        (:meth:`mbs.integrators.driver.Integrator.run`).
        ``model``: a Model of this System from :meth:`compile` with the same integrator
        options, run with a new Data instead of compiling one (its plan is the run's:
        ``plan`` and ``tolerance`` are not used); ModelError if it was compiled for
        another System or other options.
        """
        from mbs.integrators import integrator_class

        if q0 is None or u0 is None:
            q_init, u_init = self.initial_state()
            q0 = q_init if q0 is None else np.asarray(q0, dtype=float)
            u0 = u_init if u0 is None else np.asarray(u0, dtype=float)
        the_plan = None if model is not None else self._plan(t_end, plan, tolerance, outputs)
        return integrator_class(integrator)(self, **options).run(
            q0, u0, t_end, dt, t_out, outputs or {}, energies,
            set(breakpoints).union(*(f.breakpoints() for f in self.forces)), the_plan,
            recorder=recorder, progress=progress, contacts=contacts, checkpoint=checkpoint, model=model)

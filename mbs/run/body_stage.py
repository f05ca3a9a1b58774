"""The body stage of a step (DESIGN.md, stage 2): M, h, the tangents and the position
update of all integrated bodies, written into arrays the caller owns.

For each active body, at (t, q, u):

    M = blockdiag(M_b(q_b, t))                                  (nu, nu)
    h = Σ_b h_b(q_b, u_b, t) + Σ_b J_T,com,bᵀ m_b g + Σ_e Q_e    (nu,)

with h_b = Q_v − K q_f − D q̇_f of each body (thesis eq. 2.77–2.79, 2.36), gravity at
each body's centre of mass and the force elements' generalized forces Q = J_Tᵀ F
(thesis eq. 2.76). A body left out (a planned run solves it apart, :mod:`mbs.run.plan`)
gets the identity as its mass block, zero force and a position that does not move.
The tangents are K = blockdiag(−∂h_b/∂q) + the force elements' and D likewise (for the
iteration matrices of the implicit schemes).

Point masses (M = m 1, h = 0 but for gravity, q ⊕ Δu = q + Δu) are done all at once
by the kernels :func:`mbs.bodies._kernels.point_masses_mass`, :func:`~mbs.bodies._kernels.point_masses_h`
and :func:`~mbs.bodies._kernels.point_masses_increment` over their index arrays, their gravity
m g included, so that many of them cost one call. Every other body contributes through
its in-place methods (``mass_and_h_into``, ``h_into``,
``increment_into``, ``add_point_load_into`` of :class:`mbs.bodies.body.Body`): numba kernels
for FFR bodies (free quaternion, prescribed and fixed frames), rigid bodies and point
masses, a copy from the allocating methods for the rest. Gravity and force elements
that are a point force given by a step table (:meth:`mbs.links.link.ForceElement.point_load`:
``Force``, ``DistributedForce`` with constant or step loads) go through the bodies'
kernels too; other force elements add their forces with their own ``add_forces``.
When every body's h is linear with constant coefficients (point masses, FFR bodies on
a frame at rest) and gravity is the only load, h is one kernel
(:func:`mbs.bodies._kernels.linear_bodies_h`): gravity on a body at rest is the constant
J_Tᵀ m g, taken once from the body's own ``add_point_load_into``, and so is the
energy (kinetic and potential, :meth:`BodyStage.energies`); FFR bodies on free
quaternion frames beside point masses take one energy kernel each.
The results equal :meth:`mbs.system.System.mass_and_h` (the numpy reference) to
rounding.
"""

from __future__ import annotations

import numpy as np

from ffrmbs.errors import ModelError

from mbs.bodies import _kernels as K
from mbs.bodies.rigid_body import PointMass

GRAVITY_TABLE = np.array([-np.inf])     # gravity acts at every time: one table row from −inf


class BodyStage:
    """The body stage of ``bodies`` (module docstring).

    Parameters
    ----------
    bodies : sequence of Body
        All bodies of the system, in order, with their slices (``q_slice``, ``u_slice``)
        of the global q and u.
    gravity : (3,) [m/s²]
    forces : sequence of ForceElement
        The force elements acting (those of a planned run's left-out bodies excluded).
    active : None or sequence
        The bodies integrated: None (all), one bool per body, or indices into ``bodies``.
    nu : int or None
        Length of the global u (default: the bodies' velocities summed).
    """

    def __init__(self, bodies, gravity, forces, active=None, nu=None):
        self.bodies = list(bodies)
        self.nu = sum(b.nu for b in self.bodies) if nu is None else int(nu)
        flags = _active_flags(self.bodies, active)
        self.active = [b for b, on in zip(self.bodies, flags) if on]
        self.idle = [b for b, on in zip(self.bodies, flags) if not on]
        if any(b.u_slice is None for b in self.bodies):
            raise ModelError("BodyStage: every body needs its slices (add it to a System first)")
        self._one = len(self.bodies) == 1 and len(self.active) == 1 and self.active[0].nu == self.nu
        points = [] if self._one else [b for b in self.active if type(b) is PointMass]
        self._items = [(b, b.q_slice, b.u_slice, b.workspace()) for b in self.active if b not in points]
        self._work = {id(b): w for b, _, _, w in self._items}
        self._work.update((id(b), b.workspace()) for b in points)
        # each body's M block, C-contiguous: its mass kernel sees one array layout whether the
        # body is alone (M itself) or beside others (a view of M's block would be another)
        self._mass_blocks = {id(b): np.zeros((b.nu, b.nu)) for b, _, _, _ in self._items}
        self.gravity = np.asarray(gravity, dtype=float).reshape(3)
        self._point_q = np.array([b.q_slice.start for b in points], dtype=np.int64)
        self._point_u = np.array([b.u_slice.start for b in points], dtype=np.int64)
        self._point_mass = np.array([b.mass for b in points], dtype=float)
        self._point_force = np.zeros((len(points), 3))      # their gravity m g [N]
        self.forces = list(forces)
        self._loads = []            # ("point", body, q_slice, u_slice, frame, times, values, body_axes, work)
        if self.gravity.any():      # or ("element", force element)
            self._point_force[:] = np.multiply.outer(self._point_mass, self.gravity)
            for b, qs, us, work in self._items:
                F = (b.mass * self.gravity).reshape(1, 3)
                self._loads.append(("point", b, qs, us, b.com_frame(), GRAVITY_TABLE, F, False, work))
        self._applied = []          # the entries of the applied loads (mbs.links.link.ForceElement.applied)
        for f in self.forces:
            load = f.point_load()
            if load is not None and load[0].body is not None and load[0].body in self.active:
                frame, times, values, body_axes = load
                b = frame.body
                self._loads.append(("point", b, b.q_slice, b.u_slice, frame, times, values, body_axes,
                                    self._work[id(b)]))
            else:
                self._loads.append(("element", f))
            if f.applied:
                self._applied.append(self._loads[-1])
        self._force_tangents = [f for f in self.forces if f.has_tangents]
        self._varying = [b for b in self.active if b.varying_tangents]
        self.K0 = np.zeros((self.nu, self.nu))      # the bodies' constant tangents
        self.D0 = np.zeros((self.nu, self.nu))
        for b in self.active:
            Kb, Db = b.stiffness_tangent(), b.damping_tangent()
            if Kb is not None:
                self.K0[b.u_slice, b.u_slice] += Kb
            if Db is not None:
                self.D0[b.u_slice, b.u_slice] += Db
        self.additive = all(b.additive for b in self.active)
        self._rotating = [(b, b.q_slice) for b in self.active if not b.additive]
        self._one_free = self._one and bool(getattr(self.active[0], "free_quaternion", False))
        self._flat = self.additive and sum(b.nq for b in self.bodies) == self.nu     # q and u row for row
        self.linear_rows, self.linear_KD, self.linear_force, self.linear_V0 = self._linear_table()
        self.linear = self.linear_rows is not None
        self.linear_M = self._linear_mass() if self.linear and not self.idle else None
        self._free = self._free_frames() if self.linear_M is None else None

    def _linear_table(self):
        """The rows (k, 3) (first row, end row, kind), coefficients KD (2, nu, nu) and
        constant forces (nu,) of :func:`mbs.bodies._kernels.linear_bodies_h`, and V0 [J] of
        :func:`~mbs.bodies._kernels.linear_bodies_energy`, when every body's h is linear with
        constant coefficients — point masses, bodies whose
        :meth:`~mbs.bodies.body.Body.linear_forces` says so, left-out bodies (h = 0) — and the
        only loads are gravity on such bodies (:meth:`_constant_loads`); else
        (None, None, None, 0.0)."""
        loads = self._constant_loads() if self._flat else None
        if loads is None:
            return None, None, None, 0.0
        points = {id(b): k for k, b in enumerate(self.bodies) if type(b) is PointMass}
        rows, KD, force = [], np.zeros((2, self.nu, self.nu)), np.zeros(self.nu)
        active = {id(b) for b in self.active}
        V0 = 0.0
        for b in self.bodies:
            a, e = b.u_slice.start, b.u_slice.stop
            if id(b) not in active:
                rows.append((a, e, K.LEFT_OUT))
                continue
            if id(b) in points and not self._one:
                force[a:e] = b.mass * self.gravity
                rows.append((a, e, K.CONSTANT_FORCE))
                continue
            load = loads.get(id(b))
            if id(b) in points:                 # a lone point mass: its gravity is its load
                force[a:e] = load[0] if load is not None else 0.0
                rows.append((a, e, K.CONSTANT_FORCE))
                continue
            linear = b.linear_forces()
            if linear is None:
                return None, None, None, 0.0
            KD[0, a:e, a:e] = linear[0]
            if linear[1] is not None:
                KD[1, a:e, a:e] = linear[1]
            kind = K.ELASTIC if linear[1] is None else K.ELASTIC_DAMPED
            if load is not None:
                force[a:e], V0 = load[0], V0 + load[1]
                kind = K.ELASTIC_LOADED if linear[1] is None else K.ELASTIC_DAMPED_LOADED
            rows.append((a, e, kind))
        return np.array(rows, dtype=np.int64).reshape(-1, 3), KD, force, V0

    def _constant_loads(self):
        """{id(body): (Q (nu_b,) [N], V0 [J])}: gravity's generalized force Q = J_Tᵀ m g
        (thesis eq. 2.76) on each body at rest (constant J_T) and its potential
        −m g·r_com at q = 0 (r_com is linear in q_f there: −m g·r_com = V0 − Qᵀ q_f) —
        when gravity is the only load and acts on such bodies; else None. Q is the body's
        own :meth:`~mbs.bodies.body.Body.add_point_load_into` added onto −0.0 (the identity of
        +), so h = −K q_f + Q is the step's h to the bit."""
        loads = {}
        for load in self._loads:
            if load[0] != "point" or load[5] is not GRAVITY_TABLE:
                return None
            _, b, qs, us, frame, times, values, body_axes, work = load
            if type(b) is not PointMass and b.linear_forces() is None:
                return None
            Q = np.full(b.nu, -0.0)
            b.add_point_load_into(b.q_init, frame, times, values, 0.0, body_axes, Q, work)
            V0 = 0.0 if type(b) is PointMass else -float(values[0] @ frame.position(np.zeros(b.nq), 0.0))
            loads[id(b)] = (Q, V0)
        return loads

    def _free_frames(self):
        """[(body, q slice, u slice, work)] of the FFR bodies on free quaternion frames, when
        they and point masses are all the bodies, none is left out and no force element
        acts (gravity the only load): :meth:`energies` sums their kernels then; else None."""
        if self.idle or self.forces:
            return None
        free = []
        for b, qs, us, work in self._items:
            if not (getattr(b, "free_quaternion", False) and callable(getattr(b, "free_energies", None))):
                return None
            free.append((b, qs, us, work))
        return free

    def _linear_mass(self):
        """The constant mass matrix (nu, nu) of the linear bodies (their blocks at the
        initial state), for :meth:`energies`."""
        M = np.zeros((self.nu, self.nu))
        for b in self.bodies:
            M[b.u_slice, b.u_slice] = b.mass_matrix(b.q_init)
        return M

    def energies(self, q, u):
        """(kinetic, potential) energy [J], when none is left out and no force element acts
        (then the energy is the bodies' and gravity's alone): in one kernel
        (:func:`mbs.bodies._kernels.linear_bodies_energy`) when every body is linear, in one
        kernel per body (:meth:`~mbs.bodies.flexible_body.FlexibleBodyFFR.free_energies`) and
        one for the point masses (:func:`~mbs.bodies._kernels.point_masses_energies`) when
        the others are FFR bodies on free quaternion frames; else None (the caller sums the
        bodies' and links' own energies)."""
        if self.linear_M is not None:
            return K.linear_bodies_energy(self.linear_rows, self.linear_M, self.linear_KD[0], self.linear_force,
                                          self.linear_V0, q, u)
        if self._free is None:
            return None
        kinetic, potential = K.point_masses_energies(self._point_q, self._point_u, self._point_mass, self.gravity, q, u)
        for b, qs, us, work in self._free:
            body_kinetic, body_potential = b.free_energies(q[qs], u[us], self.gravity, work)
            kinetic += body_kinetic
            potential += body_potential
        return kinetic, potential

    def energy(self, q, u):
        """Kinetic plus potential energy [J] (:meth:`energies`), or None."""
        energies = self.energies(q, u)
        return None if energies is None else energies[0] + energies[1]

    @classmethod
    def of_equations(cls, equations) -> "BodyStage":
        """The body stage of an :class:`~mbs.run.equations.Equations`: its active bodies and
        force elements (a planned run's left-out ones excluded)."""
        return cls(equations.bodies, equations.gravity, equations.forces,
                   [b not in equations.idle for b in equations.bodies], equations.nu)

    @property
    def constant_tangents(self) -> bool:
        """True when K and D do not change (no active force element has tangents and no
        active body's tangents vary, e.g. a stiffened FFR body on a moving frame)."""
        return not self._force_tangents and not self._varying

    @property
    def block_tangents(self) -> bool:
        """True when the tangents couple no two bodies (no active force element has
        tangents): M̂ is then block diagonal by body."""
        return not self._force_tangents

    @property
    def varying_body_tangents(self) -> bool:
        """True when an active body's tangents change with (t, q, u)."""
        return bool(self._varying)

    @property
    def constant_iteration_matrix(self) -> bool:
        """True when M, K and D do not change: every active body has a constant mass
        matrix and no force element has tangents."""
        return all(b.constant_mass for b in self.active) and self.constant_tangents

    # --- the stage --------------------------------------------------------------------
    def mass_and_h(self, t, q, u, M, h) -> None:
        """Write M (nu, nu) and h (nu,) at (t [s], q, u) into ``M`` and ``h`` (module
        docstring); M is written whole, h whole."""
        if self._one:
            b, _, _, work = self._items[0]
            b.mass_and_h_into(q, u, t, M, h, work)
        else:
            M.fill(0.0)
            if self.idle:
                h.fill(0.0)
                for b in self.idle:
                    for i in range(b.u_slice.start, b.u_slice.stop):
                        M[i, i] = 1.0
            blocks = self._mass_blocks
            for b, qs, us, work in self._items:
                M_b = blocks[id(b)]
                b.mass_and_h_into(q[qs], u[us], t, M_b, h[us], work)
                M[us, us] = M_b
            if self._point_u.size:
                K.point_masses_mass(self._point_u, self._point_mass, M)
                K.point_masses_h(self._point_u, self._point_force, h)
        if self._loads:
            self._add_loads(t, q, u, h)

    def h_only(self, t, q, u, h) -> None:
        """Write h (nu,) at (t [s], q, u) into ``h`` (for a constant M); one kernel when
        every body's h is linear (:func:`mbs.bodies._kernels.linear_bodies_h`)."""
        if self.linear:
            K.linear_bodies_h(self.linear_rows, self.linear_KD, self.linear_force, q, u, h)
            return
        if self._one:
            b, _, _, work = self._items[0]
            b.h_into(q, u, t, h, work)
        else:
            if self.idle:
                h.fill(0.0)
            for b, qs, us, work in self._items:
                b.h_into(q[qs], u[us], t, h[us], work)
            if self._point_u.size:
                K.point_masses_h(self._point_u, self._point_force, h)
        if self._loads:
            self._add_loads(t, q, u, h)

    def _add_loads(self, t, q, u, h):
        """Gravity and force elements into h, in the System's order."""
        for load in self._loads:
            self._add(load, t, q, u, h)

    @property
    def has_applied_loads(self) -> bool:
        return bool(self._applied)

    def add_applied_loads(self, t, q, u, h) -> None:
        """The applied loads alone (force elements with ``applied``: no gravity, no
        springs) into h (nu,) [N], as in :meth:`h_only` (allocation-free for point loads
        of step tables)."""
        for load in self._applied:
            self._add(load, t, q, u, h)

    def _add(self, load, t, q, u, h):
        if load[0] == "point":
            _, b, qs, us, frame, times, values, body_axes, work = load
            if self._one:
                b.add_point_load_into(q, frame, times, values, t, body_axes, h, work)
            else:
                b.add_point_load_into(q[qs], frame, times, values, t, body_axes, h[us], work)
        else:
            load[1].add_forces(t, q, u, h)

    def tangents(self, t, q, u, K, D) -> None:
        """Write the tangents K = −∂h/∂q (in velocity-increment coordinates) and
        D = −∂h/∂u (nu, nu) into ``K`` and ``D``: the bodies' constant elastic and damping
        tangents, their varying ones (:meth:`~mbs.bodies.body.Body.add_tangents`) and the force
        elements' (springs)."""
        K[...] = self.K0
        D[...] = self.D0
        for b in self._varying:
            us = b.u_slice
            b.add_tangents(t, q[b.q_slice], u[us], K[us, us], D[us, us])
        for f in self._force_tangents:
            f.add_tangents(t, q, u, K, D)

    def increment(self, q, du, out) -> None:
        """Write q ⊕ Δu (exact for rotations, exponential map) into ``out`` (nq,), which
        may be ``q``; left-out bodies keep their q."""
        if self.additive:
            np.add(q, du, out=out)
            return
        if self._one:
            self.active[0].increment_into(q, du, out)
            return
        if out is not q:
            for b in self.idle:
                out[b.q_slice] = q[b.q_slice]
        for b, qs, us, _ in self._items:
            b.increment_into(q[qs], du[us], out[qs])
        if self._point_u.size:
            K.point_masses_increment(self._point_q, self._point_u, q, du, out)

    def advance(self, q, u, step, du, out) -> None:
        """q ⊕ step · u [step: s], renormalized, into ``out`` (:meth:`increment`,
        :meth:`normalize`), ``du`` (nu,) scratch; one kernel when q ⊕ Δu = q + Δu for
        every body (:func:`mbs.bodies._kernels.additive_advance`) and for a lone free quaternion
        body (:func:`mbs.bodies._kernels.free_quat_advance`)."""
        if self._flat:
            K.additive_advance(q, u, step, out)
            return
        if self._one_free:
            K.free_quat_advance(q, u, step, du, out)
            return
        K.scaled_into(u, step, du)
        self.increment(q, du, out)
        self.normalize(out)

    def normalize(self, q) -> None:
        """Project q onto its constraint manifold in place (unit quaternions)."""
        if self._one and self._rotating:
            self._rotating[0][0].normalize(q)
            return
        for b, qs in self._rotating:
            b.normalize(q[qs])


def _active_flags(bodies, active) -> list:
    """One bool per body from None, bools or indices."""
    if active is None:
        return [True] * len(bodies)
    active = list(active)
    if len(active) == len(bodies) and all(isinstance(a, (bool, np.bool_)) for a in active):
        return [bool(a) for a in active]
    chosen = {int(i) for i in active}
    if any(not 0 <= i < len(bodies) for i in chosen):
        raise ModelError(f"BodyStage: active body indices {sorted(chosen)} outside 0..{len(bodies) - 1}")
    return [i in chosen for i in range(len(bodies))]

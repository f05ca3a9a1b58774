"""The body stage of a step (DESIGN stage 2) over the bodies' own assembly: M, h, the
tangents K, D, the increment q ⊕ Δu and the renormalization of the active bodies of
an :class:`~mbs.equations.Equations`, written into the caller's arrays.

Bodies whose terms are constant or linear are written without temporaries: a point
mass (h = 0, M = m 1), an FFR body on a frame fixed in space (h = −K_ff q_f − D_ff q̇_f,
thesis eq. 2.69 and 4.2 with Q_v = 0, M = m_ff constant). Any other body fills its
blocks through its own methods (which return new arrays). The interface — ``h_only``,
``mass_and_h``, ``tangents``, ``increment``, ``normalize`` into given arrays — is the
one of :class:`mbs.body_stage.BodyStage`, the allocation-free kernels of every body
kind, which replaces this class in :func:`mbs.model.compile_model`.
"""

from __future__ import annotations

import numpy as np

from .rigid_body import PointMass


class SystemBodyStage:
    """In-place body stage over ``equations`` (an :class:`~mbs.equations.Equations`)."""

    def __init__(self, equations):
        self.equations = eq = equations
        self.nu = eq.nu
        self.active, self.idle = eq.active, eq.idle
        self.additive = eq.additive
        self.has_external = bool(eq.gravity.any()) or bool(eq.forces)
        self._h_writers = [self._h_writer(b) for b in eq.active]
        self._tangent_blocks = [(b.u_slice, b.stiffness_tangent(), b.damping_tangent()) for b in eq.active]
        self._rotating = [b for b in eq.active if not b.additive]

    def _h_writer(self, b):
        """A function (t, q, u, h) writing body b's rows of h."""
        qs, us = b.q_slice, b.u_slice
        if isinstance(b, PointMass):
            def write(t, q, u, h):
                h[us] = 0.0
            return write
        if getattr(b, "frame_at_rest", False) and b.n_modes:
            f = slice(qs.start + b._f.start, qs.start + b._f.stop)
            fu = slice(us.start + b._fu.start, us.start + b._fu.stop)
            K_ff, D_ff, work = b.K_ff, b.D_ff, np.zeros(b.n_modes)
            if b.damped:
                def write(t, q, u, h):         # h_f = −(K_ff q_f + D_ff q̇_f)
                    np.dot(K_ff, q[f], out=h[fu])
                    np.dot(D_ff, u[fu], out=work)
                    np.add(h[fu], work, out=h[fu])
                    np.negative(h[fu], out=h[fu])
            else:
                def write(t, q, u, h):         # h_f = −K_ff q_f
                    np.dot(K_ff, q[f], out=work)
                    np.negative(work, out=h[fu])
            return write

        def write(t, q, u, h):
            h[us] = b.h(q[qs], u[us], t)
        return write

    def h_only(self, t, q, u, h):
        """h (nu,) at (t, q, u) into ``h`` (the rows of idle bodies are left as they are:
        zero in a Data)."""
        for write in self._h_writers:
            write(t, q, u, h)
        if self.has_external:
            self.equations.add_external(t, q, u, h)

    def mass_and_h(self, t, q, u, M, h):
        """M (nu, nu) and h (nu,) at (t, q, u) into ``M`` and ``h`` (off-diagonal blocks
        and idle rows left as they are: zero and identity in a Data)."""
        for b in self.active:
            s = b.u_slice
            M[s, s], h[s] = b.mass_and_h(q[b.q_slice], u[s], t)
        if self.has_external:
            self.equations.add_external(t, q, u, h)

    def tangents(self, t, q, u, K, D):
        """K_t, D_t (nu, nu): the bodies' constant elastic and damping tangents plus the
        force elements' tangents, into ``K`` and ``D``."""
        K[...] = 0.0
        D[...] = 0.0
        for s, Kb, Db in self._tangent_blocks:
            if Kb is not None:
                K[s, s] += Kb
            if Db is not None:
                D[s, s] += Db
        for f in self.equations.forces:
            f.add_tangents(t, q, u, K, D)

    def increment(self, q, du, out):
        """q ⊕ Δu into ``out`` (idle bodies keep their q: their Δu is zero)."""
        if self.additive:
            np.add(q, du, out=out)
            return
        out[:] = q
        for b in self.active:
            out[b.q_slice] = b.increment(q[b.q_slice], du[b.u_slice])

    def normalize(self, q):
        """Renormalize the active bodies' orientation coordinates in place."""
        for b in self._rotating:
            b.normalize(q[b.q_slice])

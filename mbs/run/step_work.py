"""The energy terms of one Moreau step (:mod:`mbs.run.stages`), for the energy balance of a run

    E(t) − E(0) = W_loads − D_damping + W_impulses + residual

with E = T + V the kinetic energy plus everything stored: the bodies' elastic energy,
gravity's potential −m g·r_com, springs' ½ k (l − l0)² and the compliant contacts'
springs ½ Fᵀδ (:func:`mbs.system.System.potential_energy`,
:func:`mbs.run.residual_contact.spring_energy`). Gravity being in E, its work is not a term.

Over a step of size Δt the positions advance with v = θ u_{k+1} + (1 − θ) u_k
(stage 8: q_{k+1} = q_k ⊕ Δt v), and the smooth forces act at (t_θ, q_θ, u_k) with the
damping made implicit by M̂ (stage 5: the damping force is −D v). So

    W_loads  = Δt vᵀ Q_loads(t_θ, q_θ, u_k)     the applied loads (force elements that
               store no energy: :attr:`mbs.links.link.ForceElement.applied`);
    D_damping = Δt vᵀ D v + Δt Σ P_e(t_θ, q_θ, v) the bodies' damping D (modal, Rayleigh:
               their constant −∂h/∂u) and the force elements' own dissipation P_e
               (:meth:`mbs.links.link.ForceElement.dissipation`, a spring's damper c l̇²);

W_impulses = Λᵀ(γ⁺ + γ⁻)/2 is stage 6's (the impulses' work on the bodies; of it the
compliant contacts' springs hold ½ Fᵀδ while closed, which is in E, so the run's
balance adds to the sum what they hold at its end). For θ = ½ and bodies with constant mass
matrices the balance closes to rounding on a linear system without contacts (the
trapezoidal rule conserves E(t) − W + D exactly); the residual is the integrator's own
energy error: the numerical damping of θ > ½, a varying mass matrix, the
linearization of nonlinear forces over a step. The bodies a planned run solves apart
(:mod:`mbs.run.plan`) are not in the integrated Model and not in these terms.

A step of a Model without loads or damping costs nothing; otherwise one compiled call
for the damping and the loads added into a preallocated vector as the body stage adds
them (:meth:`mbs.run.body_stage.BodyStage.add_applied_loads`): no numpy allocation for
point loads of step tables and bodily damping; a spring-damper's dissipation and
other force elements allocate as their ``add_forces`` does.
"""

from __future__ import annotations

import numpy as np

from mbs.run import _stage_kernels as K


class StepWork:
    """The load work and the damping loss of the last step of a run of ``model``
    (module docstring) and the number of contacts that transmitted a force in it."""

    def __init__(self, model):
        self.model = model
        forces = model.equations.forces
        self.loads = model.body_stage.has_applied_loads
        self.dissipative = tuple(f for f in forces if f.dissipative)
        D = model.body_stage.D0
        self.damped_rows = np.flatnonzero(D.any(axis=0) | D.any(axis=1)).astype(np.int64)
        self.D = np.ascontiguousarray(D[np.ix_(self.damped_rows, self.damped_rows)])
        self.Q = np.zeros(model.nu)
        self.v = np.zeros(model.nu)

    def load_work(self, data, dt) -> float:
        """W_loads of the step [J] (module docstring)."""
        if not self.loads:
            return 0.0
        Q = self.Q
        Q.fill(0.0)
        self.model.body_stage.add_applied_loads(data.t_m, data.q_m, data.u_prev, Q)
        return dt * K.path_power(self.model.theta, data.u, data.u_prev, Q)

    def damping_loss(self, data, dt) -> float:
        """D_damping of the step [J] (module docstring)."""
        th = self.model.theta
        loss = 0.0
        if self.damped_rows.size:
            loss = dt * K.damping_power(th, data.u, data.u_prev, self.damped_rows, self.D)
        if self.dissipative:
            np.multiply(data.u, th, out=self.v)
            np.multiply(data.u_prev, 1.0 - th, out=self.Q)
            self.v += self.Q
            for f in self.dissipative:
                loss += dt * f.dissipation(data.t_m, data.q_m, self.v)
        return loss

    def pressed(self, data) -> int:
        """Contacts that transmitted a force in the step: a non-zero impulse or spring
        force (set-valued), a non-zero normal force (single-valued)."""
        return int(K.pressed_contacts(self.model.contact_table, data.warm, data.lam_prev, data.comp_force,
                                      data.closed, data.force_N))


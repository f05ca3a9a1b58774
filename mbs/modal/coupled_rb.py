"""CoupledRB: modal deformation and rigid-body motion with two-way coupling (report Sec. 3.3, 3.4.4).

One step of length h, after the report's algorithm (Sec. 3.4.4):

- step 1: state f_ext, R, Ω, r, ṙ (b = b0 + P r, ḃ = P ṙ), ρ_cm, ρ̇_cm, Î(r);
- steps 2–6: the report's explicit rigid-body step (:func:`mbs.modal._kernels.report_step`,
  eq. 16, 20, 26–28) with the deformed body's Î(r) and the torque of the deformed
  lever arms T = Σ (b0_i + P_i r) × f_i (eq. 19);
- step 7: the fictitious forces of eq. 22 with the updated Ω, projected into modal space;
- step 8: the modes advanced exactly over h under 𝓕_ext + 𝓕_fict held constant (eq. 10–12);
- step 9: Î updated with the new r.

The report projects eq. 22 node by node and re-assembles Î from all nodes each step
(O(N n) per step, and the reason it cannot use the boundary approach, Sec. 4.2.1).
Here every per-step quantity comes from shape integrals summed once,

    Sb[k, l] = Σ_i m_i P_ik b0_il  (3, 3, n),    S[k, l] = Σ_i m_i P_ikᵀ P_il  (3, 3, n, n),

(with a consistent mass, Σ_i m_i P_i becomes Σ_ij M_ij P_j, :meth:`ModalBasis.mass_nodal`),
so that Pᵀ f_fict = −Σ_kl A_kl (Sb[k, l] + S[k, l] r) − 2 Σ_kl Ω̃_kl S[k, l] ṙ with
A = α̃ + Ω̃Ω̃, and Σ_i m_i b_i b_iᵀ = B0 + Sb·r + (Sb·r)ᵀ + rᵀ S r gives Î(r): O(n²) per
step whatever the node count (the tests check both against the node-by-node sums).
The step is explicit and first order, like the report's.

What the algorithm leaves out: step 5 uses Euler's rigid-body equation with the current
Î(r), without the rates d(Î)/dt Ω and d/dt Σ m b × ḃ of a deforming body. The total
energy then varies by a bounded amount that does not shrink with h — for a free spin,
twice the largest elastic potential energy (``wobble_energy``). The full FFR equations
(:class:`~mbs.FlexibleBodyFFR`) keep these terms; ``wobble_rotation`` compares the two.
"""

from __future__ import annotations

import time

import numpy as np

from ffrmbs.errors import ModelError, SimulationError

from mbs.bodies.rotations import skew
from mbs.modal._kernels import report_step, workspace
from mbs.modal.basis import ModalBasis
from mbs.modal.oscillator import transition
from mbs.modal.pure_ma import decay_rates, initial_modal_state, loads_on_rows, segment_starts
from mbs.modal.result import ModalResult
from mbs.modal.simple_rb import RigidLoads, time_grid

_LEVI = np.zeros((3, 3, 3))
_LEVI[0, 1, 2] = _LEVI[1, 2, 0] = _LEVI[2, 0, 1] = 1.0
_LEVI[0, 2, 1] = _LEVI[2, 1, 0] = _LEVI[1, 0, 2] = -1.0


class CouplingIntegrals:
    """The shape integrals of CoupledRB (module docstring), summed once: O(N n²)."""

    def __init__(self, basis: ModalBasis):
        P, b0 = basis.P, basis.b0
        MP = basis.mass_nodal(P)         # Σ_j M_ij P_j (m_i P_i when lumped)
        n = basis.n_modes
        self.n = n
        self.Sb = np.einsum("ikn,il->kln", MP, b0).reshape(9, n)
        self.S = np.einsum("ikn,ilp->klnp", MP, P).reshape(9 * n, n)
        self.B0 = basis.mass_nodal(b0).T @ b0

    def second_moment(self, r) -> np.ndarray:
        """Σ_i m_i b_i b_iᵀ (3, 3) [kg m²] of the deformed body, b = b0 + P r."""
        Sr = (self.S @ r).reshape(9, self.n)
        lin = (self.Sb @ r).reshape(3, 3)
        return self.B0 + lin + lin.T + (Sr @ r).reshape(3, 3)

    def inertia(self, r) -> np.ndarray:
        """Î(r) = tr(B) 1 − B (eq. 17, 25 with deformed positions)."""
        B = self.second_moment(r)
        return np.trace(B) * np.eye(3) - B

    def fictitious(self, alpha, Omega, r, rdot) -> np.ndarray:
        """Pᵀ f_fict (n,) of eq. 22 summed over all nodes."""
        W = skew(Omega)
        A = skew(alpha) + W @ W
        Sr = (self.S @ r).reshape(9, self.n)
        Srd = (self.S @ rdot).reshape(9, self.n)
        return -A.ravel() @ (self.Sb + Sr) - 2.0 * W.ravel() @ Srd

    def relative_angular_momentum(self, r, rdot) -> np.ndarray:
        """Σ_i m_i b_i × ḃ_i (3,) in B axes; Ω·(this) is the kinetic energy coupling term."""
        Sr = (self.S @ r).reshape(9, self.n)
        M = ((self.Sb @ rdot) + (Sr @ rdot)).reshape(3, 3).T      # M[b, c] = Σ m b_b ḃ_c
        return np.einsum("abc,bc->a", _LEVI, M)


class CoupledRB:
    """Two-way coupled modal analysis + rigid-body motion of a free body (report Sec. 3.4.4).

    Parameters as :class:`~mbs.modal.SimpleRB` (``dt`` is the coupled step [s]; loads
    with ``frame="inertial"`` act through their resultant and their moment about the
    undeformed lever arms).
    """

    def __init__(self, basis: ModalBasis, loads=(), gravity=None, rayleigh=None, zeta=None,
                 u_init=None, v_init=None, r0=None, rdot0=None, position=None, velocity=(0, 0, 0),
                 orientation=None, angular_velocity=(0, 0, 0), t0=0.0, dt=1e-4):
        if basis.clamped or basis.rigid.any():
            raise ModelError("CoupledRB needs the elastic modes of a free body")
        if not dt > 0:
            raise ModelError(f"CoupledRB: dt must be positive, got {dt}")
        self.basis, self.loads, self.t0, self.dt = basis, list(loads), float(t0), float(dt)
        self.gravity = np.zeros(3) if gravity is None else np.asarray(gravity, dtype=float)
        self.sigma = decay_rates(basis.omega2, rayleigh, zeta)
        self.r0, self.rdot0 = initial_modal_state(basis, u_init, v_init, r0, rdot0)
        for ld in self.loads:
            ld.check_nodes(basis.n_nodes)
        self.rho0 = basis.center_of_mass if position is None else np.asarray(position, dtype=float)
        self.v0 = np.asarray(velocity, dtype=float)
        self.R0 = np.eye(3) if orientation is None else np.asarray(orientation, dtype=float)
        self.Om0 = np.asarray(angular_velocity, dtype=float)
        self.integrals = CouplingIntegrals(basis)

    def _per_interval(self, grid):
        """Modal external forces (K, n) and torque-deformation matrices D (K, 3, n) with
        Σ_i (P_i r) × f_i = D r, for body-frame loads on each grid interval."""
        b = self.basis
        rows = np.arange(b.n_nodes)
        loaded = np.unique(np.concatenate([ld.nodes for ld in self.loads])) if self.loads else rows[:0]
        f = loads_on_rows(self.loads, grid[:-1], loaded, b.n_nodes, "body")
        P = b.P[loaded]
        F = np.einsum("kia,ian->kn", f, P)
        D = -np.einsum("abc,kib,icn->kan", _LEVI, f, P)
        return F, D

    def solve(self, t_out, nodes="all") -> ModalResult:
        """Step to the last output time; outputs at ``t_out`` [s] on ``nodes``."""
        t_out = np.asarray(t_out, dtype=float).ravel()
        if t_out.size == 0 or t_out.min() < self.t0 or np.any(np.diff(t_out) < 0):
            raise ModelError("CoupledRB: output times must be non-empty, sorted and >= t0")
        start = time.process_time()
        b, ci = self.basis, self.integrals
        grid = time_grid(segment_starts(self.loads, self.t0, extra=t_out), t_out[-1], self.dt)
        lo = RigidLoads(self.loads, grid, b.b0, b.total_mass, self.gravity)
        F_ext, D = self._per_interval(grid)
        m = b.total_mass
        n_out = t_out.size
        rec = {k: np.empty((n_out,) + s) for k, s in
               dict(r=(b.n_modes,), rd=(b.n_modes,), rho=(3,), v=(3,), R=(3, 3), Om=(3,), I=(3, 3), h=(3,)).items()}
        rho, v, R, Om = self.rho0.copy(), self.v0.copy(), self.R0.copy(), self.Om0.copy()
        r, rd = self.r0.copy(), self.rdot0.copy()
        I = ci.inertia(r)
        alpha, ws = np.empty(3), workspace()
        steps = {}
        out_at = np.searchsorted(grid, t_out)
        j = 0
        for k in range(grid.size):
            while j < n_out and out_at[j] == k:
                for key, val in (("r", r), ("rd", rd), ("rho", rho), ("v", v), ("R", R), ("Om", Om), ("I", I)):
                    rec[key][j] = val
                rec["h"][j] = ci.relative_angular_momentum(r, rd)
                j += 1
            if k == grid.size - 1:
                break
            h = grid[k + 1] - grid[k]
            Iinv = np.linalg.inv(I)                                          # steps 2-6
            report_step(h, rho, v, R, Om, lo.F_B[k], lo.T_B[k] + D[k] @ r, lo.F_G[k], lo.B_G[k], m, I, Iinv,
                        alpha, ws)
            F = F_ext[k] + ci.fictitious(alpha, Om, r, rd)                   # step 7
            if h not in steps:
                steps[h] = transition(b.omega2, self.sigma, h)
            C11, C12, C21, C22, g1, g2 = steps[h]                            # step 8
            r, rd = C11 * r + C12 * rd + g1 * F, C21 * r + C22 * rd + g2 * F
            I = ci.inertia(r)                                                # step 9
            if not (np.isfinite(r).all() and np.isfinite(Om).all()):
                err = SimulationError(grid[k + 1], k + 1, "the coupled state became non-finite")
                err.result = self._result(t_out[:j], {key: val[:j] for key, val in rec.items()}, nodes,
                                          time.process_time() - start, k + 1)
                raise err
        return self._result(t_out, rec, nodes, time.process_time() - start, grid.size - 1)

    def _result(self, t, rec, nodes, cpu, steps) -> ModalResult:
        return ModalResult(t=t, r=rec["r"], rdot=rec["rd"], basis=self.basis,
                           nodes=self.basis.output_nodes(nodes), rho=rec["rho"], v=rec["v"], R=rec["R"],
                           Omega=rec["Om"], inertia=rec["I"], relative_angular_momentum=rec["h"],
                           stats={"cpu_s": cpu, "coupled_steps": steps})

"""SimpleRB: analytic modal deformation plus rigid-body motion, uncoupled (report Sec. 3.4.3).

1. the deformation in the body frame B by :class:`PureMA`'s exact recursion over the
   load steps (elastic modes only; the rigid-body modes are replaced by 2.);
2. the rigid-body motion of B by numerical integration (eq. 16, 19, 20, 23–28) on a
   grid that lands on every load change and output time, with steps of at most ``dt``;
3. superposition: node i is at ρ_cm + R (b0_i + P_i r) (eq. 24).

Coupling is neglected both ways (no fictitious forces on the modes, inertia and torque
from the undeformed body), which the α–Ω criterion of :mod:`mbs.modal.decision`
justifies or not (report Sec. 4.1). The rigid integrator is the report's explicit
scheme (``scheme="report"``, eq. 26–28, first order) or RKMK4 (``"rkmk4"``, fourth
order on SO(3), report Sec. 7.2 "more accurate numerical approximations"); both are
numba kernels (:mod:`mbs.modal._kernels`).

Loads in the inertial frame (report Sec. 7.2 "Forces in the G frame"): uniform gravity
enters the centre of mass only (it neither deforms a free body nor turns it); nodal
loads with ``frame="inertial"`` act on the rigid motion in O(1) per step through their
first moments and on the modes through R sampled per grid interval (then the modal
recursion runs over the grid instead of the load steps).
"""

from __future__ import annotations

import time

import numpy as np

from ffrmbs.errors import ModelError, SimulationError

from mbs.modal._kernels import rigid_motion
from mbs.modal.basis import ModalBasis
from mbs.modal.oscillator import StepResponse
from mbs.modal.pure_ma import decay_rates, initial_modal_state, loads_on_rows, projection_rows, segment_starts
from mbs.modal.result import ModalResult

SCHEMES = {"report": 0, "rkmk4": 1}


def time_grid(starts, t_end, dt) -> np.ndarray:
    """``starts`` (sorted breakpoints) up to ``t_end``, each interval split into equal steps
    of at most ``dt``; the breakpoints themselves are kept exactly."""
    pts = np.unique(np.append(starts[starts <= t_end], t_end))
    length = np.diff(pts)
    n = np.maximum(1, np.ceil(length / dt - 1e-9).astype(np.int64))
    interval = np.repeat(np.arange(length.size), n)
    k = np.arange(interval.size) - np.repeat(np.cumsum(n) - n, n) + 1
    inner = pts[interval] + length[interval] * k / n[interval]
    inner[k == n[interval]] = pts[1:]
    return np.concatenate([pts[:1], inner])


class RigidLoads:
    """Per-interval rigid-body loads on a grid: F_B, T_B, F_G (3,) and B_G (3, 3) for each
    of the n_g − 1 intervals (see :mod:`mbs.modal._kernels`)."""

    def __init__(self, loads, grid, b0, mass, gravity):
        starts = grid[:-1]
        k = starts.size
        self.F_B, self.T_B = np.zeros((k, 3)), np.zeros((k, 3))
        self.F_G = np.tile(mass * np.asarray(gravity, dtype=float), (k, 1))
        self.B_G = np.zeros((k, 3, 3))
        for ld in loads:
            j = ld.step_index(starts)
            on = j >= 0
            if ld.frame == "body":
                self.F_B[on] += ld.resultants()[j[on]]
                self.T_B[on] += ld.moments(b0)[j[on]]
            else:
                self.F_G[on] += ld.resultants()[j[on]]
                self.B_G[on] += ld.first_moments(b0)[j[on]]


class SimpleRB:
    """Uncoupled modal analysis + rigid-body motion of a free body (report Sec. 3.4.3).

    Parameters
    ----------
    basis : :class:`ModalBasis` of a free body (elastic modes only).
    loads : sequence of :class:`StepLoads`, body or inertial frame.
    gravity : (3,) [m/s²] uniform gravity in G, or None.
    rayleigh, zeta : damping of the elastic modes (see :func:`decay_rates`).
    u_init, v_init, r0, rdot0 : initial elastic state (nodal fields u_init, v_init in B, or modal r0, rdot0).
    position : initial centre of mass in G [m] (default: its mesh coordinates, so that
        displacements compare with an FE code's); velocity [m/s] in G.
    orientation : initial R (3, 3) (B → G); angular_velocity : initial Ω [rad/s] in B axes.
    dt : largest rigid-body step [s]; scheme : "rkmk4" (default) or "report".
    boundary : the boundary approach (report Sec. 4.2) for the load projection.
    """

    def __init__(self, basis: ModalBasis, loads=(), gravity=None, rayleigh=None, zeta=None,
                 u_init=None, v_init=None, r0=None, rdot0=None, position=None, velocity=(0, 0, 0),
                 orientation=None, angular_velocity=(0, 0, 0), t0=0.0, dt=1e-2, scheme="rkmk4",
                 boundary=False):
        if basis.clamped or basis.rigid.any():
            raise ModelError("SimpleRB needs the elastic modes of a free body (not clamped, "
                             "no rigid-body modes: the rigid motion is integrated separately)")
        if scheme not in SCHEMES:
            raise ModelError(f"SimpleRB: scheme must be one of {tuple(SCHEMES)}, got {scheme!r}")
        if not dt > 0:
            raise ModelError(f"SimpleRB: dt must be positive, got {dt}")
        self.basis, self.loads, self.t0, self.dt, self.scheme = basis, list(loads), float(t0), float(dt), scheme
        self.gravity = np.zeros(3) if gravity is None else np.asarray(gravity, dtype=float)
        self.sigma = decay_rates(basis.omega2, rayleigh, zeta)
        self.r0, self.rdot0 = initial_modal_state(basis, u_init, v_init, r0, rdot0)
        self.boundary = bool(boundary)
        self.rows = projection_rows(basis, self.loads, self.boundary)
        self.rho0 = basis.center_of_mass if position is None else np.asarray(position, dtype=float)
        self.v0 = np.asarray(velocity, dtype=float)
        self.R0 = np.eye(3) if orientation is None else np.asarray(orientation, dtype=float)
        if np.abs(self.R0.T @ self.R0 - np.eye(3)).max() > 1e-10 or np.linalg.det(self.R0) < 0:
            raise ModelError("SimpleRB: orientation must be a rotation matrix")
        self.Om0 = np.asarray(angular_velocity, dtype=float)

    def rigid(self, grid):
        """The rigid-body states (ρ, v, R, Ω) on ``grid`` (eq. 16, 20, 26–28 or RKMK4)."""
        b = self.basis
        lo = RigidLoads(self.loads, grid, b.b0, b.total_mass, self.gravity)
        I = b.inertia
        n = grid.size
        rho, v, R, Om = np.empty((n, 3)), np.empty((n, 3)), np.empty((n, 3, 3)), np.empty((n, 3))
        bad = rigid_motion(grid, lo.F_B, lo.T_B, lo.F_G, lo.B_G, b.total_mass, I, np.linalg.inv(I),
                           self.rho0, self.v0, self.R0, self.Om0, SCHEMES[self.scheme], rho, v, R, Om)
        if bad >= 0:
            raise SimulationError(grid[bad], bad, "the rigid-body state became non-finite")
        return rho, v, R, Om

    def modal(self, grid, R) -> StepResponse:
        """The modal recursion: over the load steps, or over the grid when inertial-frame
        nodal loads make the modal forces depend on R (sampled as the mean of the two ends)."""
        b = self.basis
        inertial = any(ld.frame == "inertial" for ld in self.loads)
        starts = grid[:-1] if inertial else segment_starts(self.loads, self.t0)
        P = b.P[self.rows]
        F = np.einsum("kia,ian->kn", loads_on_rows(self.loads, starts, self.rows, b.n_nodes, "body"), P)
        if inertial:
            f_G = loads_on_rows(self.loads, starts, self.rows, b.n_nodes, "inertial")
            C = np.einsum("kid,ian->knad", f_G, P)          # Σ_i φ_ia f_id per interval
            R_mid = 0.5 * (R[:-1] + R[1:])
            F += np.einsum("knad,kda->kn", C, R_mid)           # 𝓕 = Σ_i φ_iᵀ Rᵀ f_i
        return StepResponse(b.omega2, self.sigma, starts, F, self.r0, self.rdot0)

    def solve(self, t_out, nodes=None) -> ModalResult:
        """Run to the last output time; outputs at ``t_out`` (>= t0, any spacing) [s] on
        ``nodes`` ("all", "surface" or indices; default "surface" under the boundary approach)."""
        t_out = np.asarray(t_out, dtype=float).ravel()
        if t_out.size == 0 or t_out.min() < self.t0 or np.any(np.diff(t_out) < 0):
            raise ModelError("SimpleRB: output times must be non-empty, sorted and >= t0")
        start = time.process_time()
        grid = time_grid(segment_starts(self.loads, self.t0, extra=t_out), t_out[-1], self.dt)
        rho, v, R, Om = self.rigid(grid)
        response = self.modal(grid, R)
        r, rdot = response(t_out)
        at = np.searchsorted(grid, t_out)
        cpu = time.process_time() - start
        out = self.basis.output_nodes(("surface" if self.boundary else "all") if nodes is None else nodes)
        inertia = np.broadcast_to(self.basis.inertia, (t_out.size, 3, 3))
        return ModalResult(t=t_out, r=r, rdot=rdot, basis=self.basis, nodes=out, rho=rho[at], v=v[at],
                           R=R[at], Omega=Om[at], inertia=inertia,
                           stats={"cpu_s": cpu, "load_steps": response.starts.size, "rigid_steps": grid.size - 1})

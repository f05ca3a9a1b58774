"""PureMA: modal analysis under step loads, solved analytically (report Sec. 2, algorithm of Sec. 2.3).

1. modes from the body data (:class:`ModalBasis`);
2. initial displacement and velocity projected into modal space (eq. 8);
3. each load step projected into modal space (eq. 5, 33);
4. the recursion over load steps (eq. 10–12, :class:`StepResponse`), O(1) per load step
   and mode;
5. the solution evaluated at the requested output times only.

The body is clamped (the modes of a clamped body file), or free: then the six
rigid-body modes join with ω² = 0 and move by eq. 13 — linear, small-rotation theory;
large rotations need :class:`~mbs.modal.SimpleRB` or :class:`~mbs.modal.CoupledRB`.
"""

from __future__ import annotations

import time

import numpy as np

from ffrmbs.errors import ModelError

from mbs.modal.basis import ModalBasis
from mbs.modal.oscillator import StepResponse
from mbs.modal.result import ModalResult


def decay_rates(omega2, rayleigh=None, zeta=None) -> np.ndarray:
    """σ = ζω per mode [1/s]: Rayleigh damping C = aM + bK gives σ = (a + b ω²)/2 (report
    eq. 42, Sec. 7.1: it keeps the modal equations uncoupled); ``zeta`` gives modal
    damping ratios directly (scalar or (n,)). Rigid modes (ω² = 0) stay undamped."""
    omega2 = np.asarray(omega2, dtype=float)
    if rayleigh is not None and zeta is not None:
        raise ModelError("give Rayleigh damping or modal damping ratios, not both")
    if rayleigh is not None:
        a, b = rayleigh
        if a < 0 or b < 0:
            raise ModelError(f"Rayleigh coefficients must be non-negative, got a = {a}, b = {b}")
        sigma = 0.5 * (a + b * omega2)
    elif zeta is not None:
        z = np.broadcast_to(np.asarray(zeta, dtype=float), omega2.shape)
        if np.any(z < 0):
            raise ModelError("modal damping ratios must be non-negative")
        sigma = z * np.sqrt(omega2)
    else:
        sigma = np.zeros_like(omega2)
    return np.where(omega2 == 0.0, 0.0, sigma)


def segment_starts(loads, t0, extra=()) -> np.ndarray:
    """Sorted distinct times >= t0 where some load (or an ``extra`` time) changes, with t0 first."""
    times = [np.array([t0])] + [ld.times for ld in loads] + [np.asarray(extra, dtype=float)]
    allt = np.unique(np.concatenate(times))
    return allt[allt >= t0]


def loads_on_rows(loads, starts, rows, n_nodes, frame=None):
    """The loads of ``frame`` ("body", "inertial" or None for all) at each segment start,
    as forces on the node rows ``rows``: (K, len(rows), 3) [N]."""
    where = np.full(n_nodes, -1, dtype=np.int64)
    where[rows] = np.arange(rows.size)
    out = np.zeros((starts.size, rows.size, 3))
    for ld in loads:
        if frame is not None and ld.frame != frame:
            continue
        if np.any(where[ld.nodes] < 0):
            raise ModelError("a load acts on nodes outside the projection rows")
        j = ld.step_index(starts)
        active = j >= 0
        out[np.ix_(active, where[ld.nodes])] += ld.forces[j[active]]
    return out


def projection_rows(basis: ModalBasis, loads, boundary: bool) -> np.ndarray:
    """Node rows the load projection runs over: all N, or the surface (boundary approach,
    report Sec. 4.2.1, which requires every load on the surface)."""
    for ld in loads:
        ld.check_nodes(basis.n_nodes, basis.surface if boundary else None)
    return basis.output_nodes("surface") if boundary else np.arange(basis.n_nodes)


def initial_modal_state(basis, u_init, v_init, r0, rdot0):
    """(r0, ṙ0) from nodal fields (projected, eq. 8) or given modal coordinates."""
    if u_init is not None and r0 is not None or v_init is not None and rdot0 is not None:
        raise ModelError("give the initial state as nodal fields or as modal coordinates, not both")
    n = basis.n_modes
    r = basis.project_field(u_init) if u_init is not None else np.zeros(n) if r0 is None else np.asarray(r0, float)
    v = basis.project_field(v_init) if v_init is not None else np.zeros(n) if rdot0 is None else np.asarray(rdot0, float)
    if r.shape != (n,) or v.shape != (n,):
        raise ModelError(f"initial modal coordinates must have shape ({n},)")
    return r, v


class PureMA:
    """Modal analysis with analytic time integration under step loads (report Sec. 2).

    Parameters
    ----------
    basis : :class:`ModalBasis` (clamped modes, or free modes with ``with_rigid_modes``).
    loads : sequence of :class:`StepLoads` (their frame is irrelevant here: B = G).
    rayleigh : (a, b) Rayleigh damping C = aM + bK, or None.
    zeta : modal damping ratios (scalar or (n,)), or None.
    u_init, v_init : (N, 3) initial nodal displacement [m] and velocity [m/s] (eq. 8);
        or ``r0``, ``rdot0`` (n,) modal coordinates.
    t0 : initial time [s].
    boundary : project the loads over the surface nodes only (report Sec. 4.2); results
        are identical, the projection costs O(N_b n) instead of O(N n).
    """

    def __init__(self, basis: ModalBasis, loads=(), rayleigh=None, zeta=None, u_init=None,
                 v_init=None, r0=None, rdot0=None, t0=0.0, boundary=False):
        self.basis = basis
        self.loads = list(loads)
        self.sigma = decay_rates(basis.omega2, rayleigh, zeta)
        self.r0, self.rdot0 = initial_modal_state(basis, u_init, v_init, r0, rdot0)
        self.t0 = float(t0)
        self.boundary = bool(boundary)
        self.rows = projection_rows(basis, self.loads, self.boundary)

    def response(self) -> StepResponse:
        """Run the recursion over all load steps (steps 3–4 of Sec. 2.3)."""
        starts = segment_starts(self.loads, self.t0)
        f = loads_on_rows(self.loads, starts, self.rows, self.basis.n_nodes)
        F = np.einsum("kia,ian->kn", f, self.basis.P[self.rows])
        return StepResponse(self.basis.omega2, self.sigma, starts, F, self.r0, self.rdot0)

    def solve(self, t_out, nodes=None) -> ModalResult:
        """Evaluate at the output times ``t_out`` (>= t0, any spacing) [s]; nodal outputs
        on ``nodes`` ("all", "surface" or indices; default "surface" with the boundary
        approach, else "all")."""
        t_out = np.asarray(t_out, dtype=float).ravel()
        if t_out.size and t_out.min() < self.t0:
            raise ModelError(f"PureMA: output time {t_out.min()} s is before t0 = {self.t0} s")
        start = time.process_time()
        response = self.response()
        r, v = response(t_out)
        cpu = time.process_time() - start
        out = self.basis.output_nodes(("surface" if self.boundary else "all") if nodes is None else nodes)
        return ModalResult(t=t_out, r=r, rdot=v, basis=self.basis, nodes=out,
                           stats={"cpu_s": cpu, "load_steps": response.starts.size})

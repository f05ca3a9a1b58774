"""The scene planner: per body the cheapest formulation that meets the tolerance, and what
each run leaves out (``System.plan``, logged and applied by ``System.simulate``).

Rules, per body (first match):

1. **Frame fixed, no contact, no joint, step loads** (constant or step-table forces on
   nodes, nodal force tables, gravity): exact modal propagation, the PureMA recursion
   (report Sec. 2.3, eq. 10–12): the modes are advanced exactly from load step to load
   step, so neither their frequencies nor Δt limit anything.
2. **Free frame, the same conditions, free-free modes**: the report's α–Ω criterion
   (eq. 31–32, :mod:`mbs.modal.decision`) bounds the deformation the fictitious forces
   cause for the largest angular acceleration |α| and velocity |Ω| the loads can produce
   in the run (below). At most ``tolerance`` [m]: SimpleRB (report Sec. 3.4.3: rigid
   motion by RKMK4 with steps of at most Δt, modes exact); else the full FFR equations.
3. Everything else: the full FFR (or rigid, point-mass) equations in the time integrator.

Bounds for rule 2 (loads in the body frame, torques T_j about the centre of mass per
load row j, inertia I about it): |α_j| <= ‖I⁻¹‖ |T_j| (for loads in inertial axes
|T_j| <= Σ_i |b_i| |f_i|); Ω_max = |Ω_0| + Σ_j |α_j| τ_j over the rows' durations τ_j
within the run; |α|_max = max_j |α_j| + ‖I⁻¹‖ ‖I‖ Ω_max² (the gyroscopic term of Euler's
equation).

Modes (report Sec. 4.3, eq. 36): a body built with ``modes=None`` (all) is solved by the
modal rules on the fewest modes, ranked by their static amplitude under the loads, whose
dropped rest provably moves no node by more than half the tolerance (:func:`_modes`);
any mode with an initial state is kept, the others stay zero. A body given a mode count
or list keeps it. The other half of the tolerance bounds the neglected coupling (rule 2).

Contacts: a contact on a contour with residual flexibility acts through the static
compliance of the modes its body leaves out (:mod:`contours.residual`), which the plan
says. With two prunable contacts or more (:func:`mbs.run.bounding_spheres.pruned`), a
contour is updated, and its contact searched, only in steps where the bodies' bounding
spheres (their nodes, grown by the bound of the elastic displacement,
:meth:`~mbs.bodies.body.Body.bounding_sphere`; every contour kind but a plane on a moving
frame has one) come within the contact's broad-phase margin; the contact is open
otherwise. A single contact is searched every step: its detection tests the contours'
bounding boxes first, at about the cost of the spheres' test.

Outputs: only the requested ones, each from its own rows of Φ (a node's three rows;
the boundary approach of report Sec. 4.2.1 taken to its end). Terms that vanish: Q_v of
a frame at rest, D q̇_f of an undamped body are not evaluated.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.spatial.transform import Rotation

from preprocess.residual import clamped_nodes_of

from mbs.bodies.flexible_body import FlexibleBodyFFR
from mbs.run.bounding_spheres import MIN_PAIRS, pruned, sphere_pair

MODAL_EXACT = "exact modal propagation (PureMA)"
SIMPLE_RB = "SimpleRB (rigid motion + exact modes, uncoupled)"
INTEGRATED = "integrated"
TOLERANCE = 1e-6        # [m], the report's "negligible" deformation (Sec. 5.4)


@dataclass
class BodyPlan:
    """The plan of one body: its formulation, why, what it leaves out; for the modal
    rules the step loads and the chosen modes (indices into the body's own modes)."""

    body: object
    formulation: str
    reasons: list = field(default_factory=list)
    left_out: list = field(default_factory=list)
    loads: list = field(default_factory=list)
    modes: np.ndarray | None = None

    @property
    def modal(self) -> bool:
        return self.formulation in (MODAL_EXACT, SIMPLE_RB)


@dataclass
class Plan:
    """The scene plan: per-body plans, contacts, outputs (``str(plan)`` prints it)."""

    bodies: list
    contacts: list
    outputs: list
    tolerance: float
    forces: list = field(default_factory=list)      # force elements the modal solvers take over

    @property
    def modal_bodies(self) -> list:
        return [bp for bp in self.bodies if bp.modal]

    def __str__(self):
        lines = [f"plan (tolerance {self.tolerance:g} m):"]
        for bp in self.bodies:
            b = bp.body
            lines.append(f"  body {b.name!r} ({type(b).__name__}, {b.nu} DOF): "
                         f"{bp.formulation if bp.modal else INTEGRATED + ', ' + _equations(b)}")
            lines += [f"    because {r}" for r in bp.reasons]
            lines += [f"    leaves out {x}" for x in bp.left_out]
        lines += [f"  {c}" for c in self.contacts]
        lines += [f"  {o}" for o in self.outputs]
        return "\n".join(lines)

    # --- execution --------------------------------------------------------------------
    def solve_modal(self, system, times, q0, u0, dt) -> dict:
        """{body: (q (n, nq_b), u (n, nu_b))} of the modal bodies at ``times`` [s] from
        the initial state (q0, u0), with rigid steps of at most ``dt`` [s] (SimpleRB)."""
        return {bp.body: _history(bp, system, np.asarray(times, float), q0[bp.body.q_slice],
                                  u0[bp.body.u_slice], dt) for bp in self.modal_bodies}


def _equations(body) -> str:
    if isinstance(body, FlexibleBodyFFR):
        return "full FFR equations"
    return "rigid-body equations" if body.nu == 6 else "point-mass equations" if body.nu == 3 else "own equations"


# --- planning -----------------------------------------------------------------------------
def make_plan(system, t_end, tolerance=TOLERANCE, outputs=None) -> Plan:
    """The plan of ``system`` for a run to ``t_end`` [s] (module docstring)."""
    joined = {id(b) for c in system.constraints for b in c.bodies() if b is not None}
    touching = {id(b) for c in system.contacts for b in c.bodies()}
    plans, absorbed = [], []
    for body in system.bodies:
        own = [f for f in system.forces if body in f.bodies()]
        bp = _plan_body(system, body, own, id(body) in joined, id(body) in touching, t_end, tolerance)
        plans.append(bp)
        if bp.modal:
            absorbed += own
    kept = {id(c) for c in pruned(system.contacts)}
    contacts = [f"contact {c.name!r}: " + (f"contours updated and searched only while the bodies' bounding spheres "
                                           f"come within {_margin(c)} (broad phase), open otherwise"
                                           if id(c) in kept else "contours updated and searched every step"
                                           + _unpruned(c, system.contacts)) + _correction(c)
                for c in system.contacts]
    names = sorted(outputs or {})
    out = [f"outputs: {', '.join(names) if names else 'none'} requested; each evaluated from its own "
           "rows of the mode shapes (no full-field recovery)"]
    return Plan(plans, contacts, out, tolerance, absorbed)


def _correction(contact) -> str:
    """What a contact on contours with residual flexibility adds to its plan line."""
    notes = []
    for contour in contact.contours():
        if getattr(contour, "residual_flexibility", False):
            body = contour.body
            clamped = clamped_nodes_of(body.data).size
            n_dof = 3 * (body.data.n_nodes - clamped) - (0 if clamped else 6)     # the FE model's modes
            notes.append(f"; on {contour.name!r} it acts through the static compliance of all the modes body "
                         f"{body.name!r} leaves out (residual flexibility: {body.n_modes} of its FE model's "
                         f"{n_dof} modes kept, no extra coordinates)")
    return "".join(notes)


def _unpruned(contact, contacts) -> str:
    """Why a contact is searched every step (:func:`mbs.run.bounding_spheres.pruned`)."""
    if not contact.unilateral:
        return " (a point kept on a curve)"
    if getattr(contact, "margin", None) is None:
        return " (margin off)"
    if sphere_pair(contact) is None:
        return " (its contours have no bounding sphere)"
    return f" (fewer than {MIN_PAIRS} prunable contacts: its detection's own box test is the broad phase)"


def _margin(contact) -> str:
    margin = getattr(contact, "margin", None)
    return "any distance (margin off)" if margin is None else f"{margin:g} m"


def _plan_body(system, body, forces, joined, touching, t_end, tolerance) -> BodyPlan:
    if not isinstance(body, FlexibleBodyFFR):
        return BodyPlan(body, INTEGRATED, [f"a {type(body).__name__} has no modes to propagate"])
    terms = _vanishing_terms(body)
    blockers = (["it has a joint"] if joined else []) + (["it takes part in a contact"] if touching else [])
    loads = [f.step_loads() for f in forces]
    if any(len(set(f.bodies())) > 1 for f in forces):
        blockers.append("a force element links it to another body")
    elif any(ld is None for ld in loads):
        blockers.append("a load on it is not a step function of time on its nodes "
                        "(a callable, a linear table or a torque)")
    if body.motion is not None and not body.frame_at_rest:
        blockers.append("its frame moves on a prescribed path")
    if body.geometric_stiffening and not body.frame_at_rest:
        blockers.append("its geometric stiffening follows the frame's motion")
    if body.is_free and (body.data.params or {}).get("clamp"):
        blockers.append("its modes are clamped, not free-free")
    if blockers:
        return BodyPlan(body, INTEGRATED, blockers, terms)
    loads = [ld for ld in loads if ld.nodes.size]
    if system.gravity.any():
        loads.append(_gravity_loads(body, system.gravity))
    modes, mode_note = _modes(body, loads, 0.5 * tolerance)
    left = terms + ([mode_note] if mode_note else [])
    if body.frame_at_rest:
        return BodyPlan(body, MODAL_EXACT, ["the frame is fixed and no contact or joint acts on it"],
                        left + ["the time steps of the modes (exact between load steps)"], loads, modes)
    d, alpha, omega = _coupling(body, loads, t_end)
    why = (f"the α–Ω criterion (report eq. 31–32) bounds the coupling deformation by {d:.3g} m "
           f"(|α| <= {alpha:.3g} rad/s², |Ω| <= {omega:.3g} rad/s over {t_end:g} s)")
    if d > 0.5 * tolerance:
        return BodyPlan(body, INTEGRATED, [why + f" > half the tolerance, {0.5 * tolerance:g} m"], terms)
    return BodyPlan(body, SIMPLE_RB, [why + f" <= half the tolerance, {0.5 * tolerance:g} m"],
                    left + ["the fictitious forces on the modes and the deformed inertia"], loads, modes)


def _vanishing_terms(body) -> list:
    out = []
    if body.frame_at_rest:
        out.append("Q_v (frame at rest)")
    if not body.damped:
        out.append("D q̇_f (no damping)")
    return out


def _gravity_loads(body, gravity):
    """Gravity as nodal forces w_j g from t = 0 (inertial axes; body axes on a frame at rest),
    w = M_s 1 the row sums of the body's mass (its lumped masses when lumped): the
    consistent load M (1 ⊗ g), so φᵀ f is exact for either mass."""
    from mbs.modal import StepLoads

    g = gravity if body.is_free else body.orientation(body.q_init).T @ gravity
    f = body.data.node_weights()[:, None] * g[None, :]
    return StepLoads([0.0], np.arange(body.data.n_nodes), f[None], "inertial" if body.is_free else "body")


def _modes(body, loads, tolerance):
    """(indices into the body's modes, note): the modes ranked by their static amplitude
    under the loads, |φ_kᵀ f| / ω_k² (the static effective mass of report eq. 36), and
    the fewest kept so that the bound on what the others can add to any node,

        Σ_k dropped  2 Σ_loads Σ_j |Δa_kj| max_i |Φ_ik|,   a_kj = φ_kᵀ f_j / ω_k²,

    stays within ``tolerance`` [m] (an undamped mode's response to a load step Δa is
    Δa (1 − cos ω t), at most 2 |Δa|). Modes with an initial state are kept."""
    n = body.n_modes
    if body.modes_fixed or not loads or not n:
        return np.arange(n), None
    omega2 = np.diag(body.K_ff)
    bound = np.zeros(n)
    for ld in loads:
        f = np.zeros((ld.times.size, body.data.n_nodes, 3))
        f[:, ld.nodes] = ld.forces
        a = (f.reshape(ld.times.size, -1) @ body.phi) / omega2
        bound += 2.0 * np.abs(np.diff(a, axis=0, prepend=0.0)).sum(axis=0)
    bound *= body.mode_reach
    ranked = np.argsort(-bound, kind="stable")
    tail = np.cumsum(bound[ranked][::-1])[::-1]          # what dropping ranked[k:] costs
    keep = int(np.argmax(np.append(tail, 0.0) <= tolerance))
    chosen = set(ranked[:keep].tolist())
    chosen |= set(np.flatnonzero(body.q_init[body.q_f_slice] != 0).tolist())
    chosen |= set(np.flatnonzero(body.u_init[body.u_f_slice] != 0).tolist())
    idx = np.array(sorted(chosen), dtype=int)
    if idx.size == n:
        return idx, None
    dropped = bound.sum() - bound[idx].sum()
    return idx, (f"{n - idx.size} of {n} modes: what they can add to any node under these loads is "
                 f"bounded by {dropped:.3g} m <= {tolerance:g} m (ranked by static amplitude, report eq. 36)")


def _coupling(body, loads, t_end):
    """(deformation bound d [m], |α|max [rad/s²], |Ω|max [rad/s]) of rule 2 (module docstring).

    d = 2 (d_α |α| + d_Ω |Ω|²) with the quasi-static responses of report eq. 32 as
    derived in :mod:`mbs.modal.decision`: d_α = max_n σ_max(U_α,n) exactly, and for
    d_Ω the bound max_n ‖H_n‖₂ >= max_n |H_n q(Ω̂)| (|q(Ω̂)|² = 1 − Σ_k<l Ω̂_k² Ω̂_l² <= 1),
    so no search over directions is needed."""
    from mbs.modal import ModalBasis
    from mbs.modal.decision import alpha_response, omega_response

    basis = ModalBasis.from_body(body.data, body.mode_indices)
    b, inertia, m = basis.b0, basis.inertia, basis.mass
    inv = np.linalg.inv(inertia)
    n_inv, n_I = np.linalg.norm(inv, 2), np.linalg.norm(inertia, 2)
    starts = np.unique(np.concatenate([ld.times for ld in loads] + [[0.0]]))
    starts = starts[(starts >= 0.0) & (starts < t_end)]
    durations = np.diff(np.append(starts, t_end))
    torque = np.zeros(starts.size)
    for ld in loads:
        j = ld.step_index(starts)
        on = j >= 0
        if ld.frame == "body":
            moments = np.linalg.norm(ld.moments(b), axis=1)
        else:
            moments = (np.linalg.norm(b[ld.nodes], axis=1)[None] * np.linalg.norm(ld.forces, axis=2)).sum(axis=1)
        torque[on] += moments[j[on]]
    alpha_rows = n_inv * torque
    w = body.frame_state(body.q_init, body.u_init)[3]
    omega = float(np.linalg.norm(w) + alpha_rows @ durations)
    alpha = float(alpha_rows.max() + n_inv * n_I * omega ** 2)
    omega2 = np.diag(body.K_ff).copy()
    d_alpha = np.linalg.norm(alpha_response(b, m, body.phi, omega2), 2, axis=(1, 2)).max()
    d_omega = np.linalg.norm(omega_response(b, m, body.phi, omega2), 2, axis=(1, 2)).max()
    return 2.0 * (d_alpha * alpha + d_omega * omega ** 2), alpha, omega


# --- execution ----------------------------------------------------------------------------
def _history(bp, system, times, q0, u0, dt):
    """(q, u) histories of one modal body at ``times`` (rules 1 and 2)."""
    from mbs.modal import ModalBasis, PureMA, SimpleRB

    body, idx = bp.body, bp.modes
    basis = ModalBasis.from_body(body.data, body.mode_indices[idx])
    zeta = body.modal_damping
    if zeta is not None and np.ndim(zeta):
        zeta = np.asarray(zeta, dtype=float)[idx]
    f, fu = body.q_f_slice, body.u_f_slice
    common = dict(loads=bp.loads, rayleigh=body.rayleigh, zeta=zeta, r0=q0[f][idx], rdot0=u0[fu][idx])
    q, u = np.zeros((times.size, body.nq)), np.zeros((times.size, body.nu))
    if bp.formulation == MODAL_EXACT:
        res = PureMA(basis, **common).solve(times, nodes=[])
    else:
        R, A, v, w, _ = body.frame_state(q0, u0)
        c = body.integrals.I1 / body.mass
        res = SimpleRB(basis, gravity=system.gravity, position=R + A @ c, velocity=v + A @ np.cross(w, c),
                       orientation=A, angular_velocity=w, dt=dt, scheme="rkmk4", **common).solve(times, nodes=[])
        Ac = np.einsum("nij,j->ni", res.R, c)
        q[:, :3] = res.rho - Ac
        u[:, :3] = res.v - np.einsum("nij,nj->ni", res.R, np.cross(res.Omega, c))
        q[:, body.q_r_slice], u[:, 3:6] = _orientation_coordinates(body.param, res.R, res.Omega)
    q[:, f.start + idx] = res.r
    u[:, fu.start + idx] = res.rdot
    return q, u


def _orientation_coordinates(param, R, Omega):
    """(q_r (n, nr), u_r (n, 3)) of orientations R (n, 3, 3) and body-frame angular
    velocities Ω (n, 3) in the body's parametrization (quaternions vectorized)."""
    if param.name == "quaternion":
        xyzw = Rotation.from_matrix(R).as_quat()
        p = np.concatenate((xyzw[:, 3:], xyzw[:, :3]), axis=1)
        return p * np.where(p[:, :1] < 0.0, -1.0, 1.0), Omega
    qr = np.array([param.coordinates(A) for A in R])
    return qr, np.array([param.velocity_coordinates(c, w) for c, w in zip(qr, Omega)])

"""Static equilibrium as the initial state: the bodies at rest under gravity and the loads
at time t, held by their joints, springs, prescribed frames and resting contacts (what
MBSim and Adams compute before a run).

Unknowns: the increments Δu of the chosen bodies' coordinates (q ⊕ Δu, exact for
rotations), the multipliers λ of the joints and of the resting contacts. At rest (u = 0)
the equations of motion M u̇ = h + W λ (:mod:`mbs.system`) reduce to

    h(q, 0, t) + W λ = 0,      g(q) = 0,                                   (S1)

g the joints' residuals and the gaps g_N of the resting contacts, W = [C_qᵀ, W_N].
Newton's method on (S1) with ∂h/∂Δu by forward differences (exact to rounding when h is
affine in q, as for a body on a fixed frame) and the step of the bordered system

    [∂h/∂Δu  W] [Δu]   [−h]
    [Wᵀ      0] [λ⁺] = [−g]                                                 (S2)

solved by the null-space method in the least-squares sense (:func:`_newton_step`: a
direction with neither stiffness nor load stays put; a statically indeterminate support,
e.g. a rigid block on four points, takes the multipliers of least norm). For a clamped FFR body (a fixed
frame) h = Q_f − K_ff q_f is affine and (S1) is K_ff q_f = Q_f: the modal static
deflection, exact in the modal basis, in one Newton step (the second confirms it).

Contacts: a unilateral set-valued contact (impact or Coulomb law) closed at the given
state (its own rule, :meth:`contact.Contact.locate`) is a resting contact: its gap is
held at zero (rows W_N) and its normal force λ_N must come out compressive (>= 0). With
the impact law it is frictionless; with the Coulomb law it also sticks (rows W_T, the
contact point does not slide: W_Tᵀ Δu = 0) and its friction force must lie in the cone,
|λ_T| <= μ λ_N. A contact open at the given state must stay open at the static one. A
closed contact with a penalty law, one on a contour with residual flexibility, or a
bilateral curve constraint is not supported (a ModelError names it).
"""

from __future__ import annotations

import numpy as np

from ffrmbs.errors import ModelError

#: forward-difference step of ∂h/∂Δu [the unit of each velocity coordinate]
FD_STEP = 1e-7
#: singular values below this fraction of the largest count as zero (least-squares solves)
RANK_TOL = 1e-12
#: a generalized force left unbalanced by a Newton step, relative to the largest load at the start
UNBALANCED_TOL = 1e-6


def static_equilibrium(system, t=0.0, bodies=None, tol=1e-10, max_iter=30):
    """The static equilibrium (S1) of ``bodies`` (default: all of ``system``'s) at time
    ``t`` [s], the others held at their initial state; returns (q, u) with u = 0 on the
    chosen bodies and sets their initial state to it (``q_init``, ``u_init``).

    ``tol``: the residual ‖h + W λ‖∞ relative to the largest generalized force at the
    start, and the gaps and joint residuals [m, rad]. ModelError when there is no
    equilibrium (a body nothing holds against its loads), when Newton's method does not
    converge in ``max_iter`` iterations, or for an unsupported contact (module
    docstring)."""
    chosen = _chosen(system, bodies)
    q, u = system.initial_state()
    if not chosen:
        return q, u
    cols = np.concatenate([np.arange(b.u_slice.start, b.u_slice.stop) for b in chosen])
    for b in chosen:
        u[b.u_slice] = 0.0
    ids = {id(b) for b in chosen}
    contacts = [c for c in system.contacts if any(id(b) in ids for b in c.bodies())]
    resting = [c for c in contacts if _closed(c, q, u, t)]
    for c in resting:
        _check_resting(c)
    equations = system.equations()
    h = equations.h(t, q, u)[cols]
    scale = max(float(np.abs(h).max(initial=0.0)), np.finfo(float).tiny)
    lam = np.zeros(0)
    for _ in range(max_iter + 1):
        W, g = _constraints(system, resting, q, u, t, cols)
        if lam.size != g.size:
            lam = np.zeros(g.size)
        r = h + W @ lam
        if np.abs(r).max(initial=0.0) <= tol * scale and np.abs(g).max(initial=0.0) <= tol:
            break
        du, lam = _newton_step(system, chosen, equations, q, u, t, cols, h, W, g, scale)
        q = equations.increment(q, du)
        equations.normalize(q)
        h = equations.h(t, q, u)[cols]
    else:
        raise ModelError(f"static equilibrium of {_names(chosen)}: Newton's method did not converge in {max_iter} "
                         f"iterations (residual {np.abs(r).max():.3g} of the loads' {scale:.3g})")
    _check_contacts(contacts, resting, lam[lam.size - sum(c.dim for c in resting):], q, u, t)
    for b in chosen:
        b.q_init[:] = q[b.q_slice]
        b.u_init[:] = 0.0
    return q, u


def _chosen(system, bodies):
    """The bodies of ``system`` named or given in ``bodies`` (all when None), in system order."""
    if bodies is None:
        return list(system.bodies)
    by_name = {b.name: b for b in system.bodies}
    chosen = []
    for b in bodies:
        body = by_name.get(b) if isinstance(b, str) else b
        if body is None or not any(body is s for s in system.bodies):
            raise ModelError(f"static equilibrium: {b!r} is not a body of the system "
                             f"(bodies: {', '.join(by_name)})")
        chosen.append(body)
    return [b for b in system.bodies if any(b is c for c in chosen)]


def _names(bodies) -> str:
    return ", ".join(repr(b.name) for b in bodies)


def _update_contours(contact, q, u, t):
    """Update both contours of ``contact`` at (q, u, t) (ground contours at t)."""
    for contour in contact.contours():
        b = contour.body
        if b is None:
            contour.update(None, None, t)
        else:
            contour.update(q[b.q_slice], u[b.u_slice], t)


def _closed(contact, q, u, t) -> bool:
    """Whether ``contact`` is closed at (q, u, t) by its own rule."""
    _update_contours(contact, q, u, t)
    return bool(contact.locate())


def _check_resting(contact):
    """A resting contact must be unilateral, set-valued and without residual flexibility."""
    what = None
    if not contact.unilateral:
        what = "a point kept on a curve"
    elif not contact.set_valued:
        what = "a closed contact with a single-valued (penalty) law"
    elif any(getattr(c, "residual_flexibility", False) for c in contact.contours()):
        what = "a closed contact through residual flexibility"
    if what is not None:
        raise ModelError(f"static equilibrium: contact {contact.name!r} is {what}, which the static solve does not "
                         "support (it supports resting contacts with the impact law, frictionless, or the Coulomb law, "
                         "sticking): "
                         "start the body apart from it, or without initial = \"static\"")


def _constraints(system, resting, q, u, t, cols):
    """(W (n_cols, m), g (m,)): the joints' C_qᵀ and the resting contacts' W_N (and W_T of
    a Coulomb contact) restricted to the chosen bodies' columns, and their residuals (g_N;
    zero for W_T: the increments do not slide; joints not touching the bodies left out)."""
    columns, residuals = [], []
    if system.n_c:
        C = system.constraint_jacobian(t, q)[:, cols]
        keep = np.abs(C).max(axis=1) > 0.0
        columns.append(C[keep].T)
        residuals.append(system.constraint_residual(t, q)[keep])
    for c in resting:
        _update_contours(c, q, u, t)
        k = c.kinematics
        if not k.update(velocity=False, jacobians=True):
            raise ModelError(f"static equilibrium: the resting contact {c.name!r} lost its contact point "
                             "(it left the contour's domain)")
        columns.append(k.W_N()[cols, None])
        residuals.append([k.g_N])
        if c.dim == 3:                          # Coulomb: the point sticks (no position-level slip)
            columns.append(k.W_T()[cols])
            residuals.append([0.0, 0.0])
    if not columns:
        return np.zeros((len(cols), 0)), np.zeros(0)
    return np.hstack(columns), np.concatenate(residuals)


def _newton_step(system, chosen, equations, q, u, t, cols, h, W, g, scale):
    """(Δu (nu,), λ⁺) of (S2) by the null-space method: Δu = Δu_g + Z z with Wᵀ Δu_g = −g
    (least norm), Z an orthonormal basis of the null space of Wᵀ, the reduced equations
    Zᵀ ∂h/∂Δu Z z = −Zᵀ (h + ∂h/∂Δu Δu_g) in the least-squares sense (directions without
    stiffness and without load stay put), then W λ⁺ = −(h + ∂h/∂Δu Δu) (least norm for a
    statically indeterminate support). ModelError naming the body whose reduced equations
    have no solution (a load along a direction nothing holds)."""
    n = len(cols)
    J = np.empty((n, n))
    du = np.zeros(system.nu)
    for k, col in enumerate(cols):
        du[col] = FD_STEP
        J[:, k] = (equations.h(t, equations.increment(q, du), u)[cols] - h) / FD_STEP
        du[col] = 0.0
    du_g, Z = np.zeros(n), np.eye(n)
    if g.size:
        _, sv, Vt = np.linalg.svd(W.T)
        rank = int(np.sum(sv > RANK_TOL * sv.max())) if sv.size else 0
        Z = Vt[rank:].T
        du_g = np.linalg.lstsq(W.T, -g, rcond=RANK_TOL)[0]
    b = Z.T @ (h + J @ du_g)
    J_r = Z.T @ J @ Z
    z = np.linalg.lstsq(J_r, -b, rcond=RANK_TOL)[0]
    unbalanced = Z @ (J_r @ z + b)
    if np.abs(unbalanced).max(initial=0.0) > UNBALANCED_TOL * scale:
        worst = cols[int(np.argmax(np.abs(unbalanced)))]
        body = next(b for b in chosen if b.u_slice.start <= worst < b.u_slice.stop)
        raise ModelError(f"static equilibrium: body {body.name!r} has none: nothing holds it against its loads "
                         "(add a joint, a spring or a resting contact — frictionless with the impact law, sticking "
                         "with the coulomb law — or start it from its given state)")
    step = du_g + Z @ z
    lam = np.linalg.lstsq(W, -(h + J @ step), rcond=RANK_TOL)[0] if g.size else np.zeros(0)
    du[cols] = step
    return du, lam


def _check_contacts(contacts, resting, lam, q, u, t):
    """Resting contacts press (λ_N >= 0) and stick inside their friction cone
    (|λ_T| <= μ λ_N; ``lam`` their multipliers, [N] or [N, T1, T2] each); the others are
    open at the static state."""
    at = 0
    for c in resting:
        lam_N, lam_T = lam[at], lam[at + 1:at + c.dim]
        at += c.dim
        if lam_N < 0.0:
            raise ModelError(f"static equilibrium: contact {c.name!r} would have to pull ({-lam_N:.3g} N): the "
                             "body does not rest on it; start it apart from the contact")
        if lam_T.size and np.linalg.norm(lam_T) > c.law.mu * lam_N:
            raise ModelError(f"static equilibrium: contact {c.name!r} would slide: friction {np.linalg.norm(lam_T):.3g} "
                             f"N needed, mu lambda_N = {c.law.mu * lam_N:.3g} N")
    for c in contacts:
        if not any(c is r for r in resting) and _closed(c, q, u, t):
            raise ModelError(f"static equilibrium: the static deflection closes contact {c.name!r}, open at the "
                             "given state: start the body resting on it (gap 0) or farther from it")

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

    [∂h/∂Δu  W] [Δu]   [−h − W λ]
    [Wᵀ      0] [λ⁺] = [−g      ]                                           (S2)

solved in the least-squares sense (a statically indeterminate support, e.g. a rigid block
on four points, takes the multipliers of least norm). For a clamped FFR body (a fixed
frame) h = Q_f − K_ff q_f is affine and (S1) is K_ff q_f = Q_f: the modal static
deflection, exact in the modal basis, in one Newton step (the second confirms it).

Contacts: a unilateral set-valued contact (impact or Coulomb law) closed at the given
state (its own rule, :meth:`contact.Contact.locate`) is a resting contact: its gap is
held at zero and its normal force λ_N must come out compressive (>= 0), frictionless.
A contact open at the given state must stay open at the static one. A closed contact
with a penalty law, one on a contour with residual flexibility, or a bilateral curve
constraint is not supported (a ModelError names it).
"""

from __future__ import annotations

import numpy as np

from ffrmbs.errors import ModelError

#: forward-difference step of ∂h/∂Δu [the unit of each velocity coordinate]
FD_STEP = 1e-7


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
        du, lam = _newton_step(system, chosen, equations, q, u, t, cols, h, W, r, g, scale, tol)
        q = equations.increment(q, du)
        equations.normalize(q)
        h = equations.h(t, q, u)[cols]
    else:
        raise ModelError(f"static equilibrium of {_names(chosen)}: Newton's method did not converge in {max_iter} "
                         f"iterations (residual {np.abs(r).max():.3g} of the loads' {scale:.3g})")
    _check_contacts(contacts, resting, lam[lam.size - len(resting):], q, u, t)
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
                         "support (it supports resting contacts with the impact or Coulomb law, frictionless): "
                         "start the body apart from it, or without initial = \"static\"")


def _constraints(system, resting, q, u, t, cols):
    """(W (n_cols, m), g (m,)): the joints' C_qᵀ and the resting contacts' W_N restricted
    to the chosen bodies' columns, and their residuals (joints not touching them left out)."""
    columns, residuals = [], []
    if system.n_c:
        C = system.constraint_jacobian(t, q)[:, cols]
        keep = np.abs(C).max(axis=1) > 0.0
        columns.append(C[keep].T)
        residuals.append(system.constraint_residual(t, q)[keep])
    if resting:
        W_N = np.empty((len(cols), len(resting)))
        g_N = np.empty(len(resting))
        for j, c in enumerate(resting):
            _update_contours(c, q, u, t)
            if not c.kinematics.update(velocity=False, jacobians=True):
                raise ModelError(f"static equilibrium: the resting contact {c.name!r} lost its contact point "
                                 "(it left the contour's domain)")
            W_N[:, j] = c.kinematics.W_N()[cols]
            g_N[j] = c.kinematics.g_N
        columns.append(W_N)
        residuals.append(g_N)
    if not columns:
        return np.zeros((len(cols), 0)), np.zeros(0)
    return np.hstack(columns), np.concatenate(residuals)


def _newton_step(system, chosen, equations, q, u, t, cols, h, W, r, g, scale, tol):
    """(Δu (nu,), λ⁺) of (S2); ModelError naming the bodies whose equations (S2) cannot
    satisfy (nothing holds them against their loads)."""
    n, m = len(cols), g.size
    J = np.empty((n, n))
    du = np.zeros(system.nu)
    for k, col in enumerate(cols):
        du[col] = FD_STEP
        J[:, k] = (equations.h(t, equations.increment(q, du), u)[cols] - h) / FD_STEP
        du[col] = 0.0
    A = np.zeros((n + m, n + m))
    A[:n, :n], A[:n, n:], A[n:, :n] = J, W, W.T
    rhs = np.concatenate([-h, -g])
    x = np.linalg.lstsq(A, rhs, rcond=1e-12)[0]
    left = A @ x - rhs
    if np.abs(left[:n]).max(initial=0.0) > 1e-6 * scale or np.abs(left[n:]).max(initial=0.0) > max(tol, 1e-9):
        worst = cols[int(np.argmax(np.abs(left[:n])))] if n else 0
        body = next(b for b in chosen if b.u_slice.start <= worst < b.u_slice.stop)
        raise ModelError(f"static equilibrium: body {body.name!r} has none: nothing holds it against its loads "
                         "(add a joint, a spring or a resting contact, or start it from its given state)")
    du[cols] = x[:n]
    return du, x[n:]


def _check_contacts(contacts, resting, lam_N, q, u, t):
    """Resting contacts press (λ_N >= 0); the others are open at the static state."""
    for c, lam in zip(resting, lam_N):
        if lam < 0.0:
            raise ModelError(f"static equilibrium: contact {c.name!r} would have to pull ({-lam:.3g} N): the body "
                             "does not rest on it; start it apart from the contact")
    for c in contacts:
        if not any(c is r for r in resting) and _closed(c, q, u, t):
            raise ModelError(f"static equilibrium: the static deflection closes contact {c.name!r}, open at the "
                             "given state: start the body resting on it (gap 0) or farther from it")

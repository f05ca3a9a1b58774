"""numba kernels of the step's stages (:mod:`mbs.run.stages`): which contours and contacts
the contour and detection stages visit, in one call each instead of a Python loop over
every contact (far-apart pairs cost nothing per step); the closed contacts' columns of W
and gap-closing terms from their kinematics in Data (:func:`contact_rows_into`, over the
Model's contact table); the contact problem's products (G, ξ_free, γ⁻), the velocity
update and the impulses' work, each one call.

Plain-Python or numpy references in the docstrings; ``tests/unit/mbs/test_stages.py`` compares them.
"""

from __future__ import annotations

from numba import njit

from contact.kinematics import ACTIVE_AT, G_N_AT
from mbs.run.linalg_kernels import block_cho_solve_vector

# columns of Model.contact_table, one row per contact: where its kinematics buffer lies in
# Data's contact_f, the offsets of w_N1, w_N2, w_T1, w_T2 in it (contact.kinematics.buffer_layout),
# the bodies' velocity counts and first rows in u (−1: the ground), its rows of Λ (0:
# single-valued) and the first of them in Data.lam_prev, whether it is unilateral, a point
# kept on a curve (W = [w_N, w_T2]), a contact through residual flexibility (compliant)
(KIN_AT, W_N1_AT, W_N2_AT, W_T1_AT, W_T2_AT, NU1, NU2, START1, START2, DIM, LAM_AT, UNILATERAL,
 ON_CURVE, COMPLIANT, TABLE_COLUMNS) = range(15)


@njit(cache=True)
def contours_in_use(owner_at, owners, live, out):
    """Indices of the contours with a live owner into ``out``; returns their number.
    Contour k's owning contacts are owners[owner_at[k]:owner_at[k + 1]]. Reference:
    ``[k for k in range(n) if any(live[i] for i in owners of k)]``."""
    n = 0
    for k in range(owner_at.shape[0] - 1):
        for j in range(owner_at[k], owner_at[k + 1]):
            if live[owners[j]]:
                out[n] = k
                n += 1
                break
    return n


@njit(cache=True)
def live_contacts(live, out):
    """Indices i of the live contacts (live[i] True) into ``out``, in order; returns
    their number. Reference: ``np.flatnonzero(live)``."""
    n = 0
    for i in range(live.shape[0]):
        if live[i]:
            out[n] = i
            n += 1
    return n


@njit(cache=True)
def contact_problem_into(W, MW, u_free, u, offset, closing, G, xi_free, gamma_pre):
    """The contact problem of stage 5 from W (nu, m) and M̂⁻¹W (nu, m): G = Wᵀ M̂⁻¹ W
    (m, m) [1/kg], ξ_free = Wᵀ u_free + offset + closing, γ⁻ = Wᵀ u_k + offset (m,)
    [m/s]. Numpy reference: ``W.T @ MW``, ``W.T @ u_free`` ... (``tests/unit/mbs/test_stages.py``)."""
    nu, m = W.shape
    for i in range(m):
        for j in range(m):
            s = 0.0
            for k in range(nu):
                s += W[k, i] * MW[k, j]
            G[i, j] = s
        a = 0.0
        b = 0.0
        for k in range(nu):
            a += W[k, i] * u_free[k]
            b += W[k, i] * u[k]
        xi_free[i] = a + offset[i] + closing[i]
        gamma_pre[i] = b + offset[i]


@njit(cache=True)
def velocity_into(u_free, MW, lam, u):
    """u = u_free + M̂⁻¹W Λ (nu,) [m/s] (stage 7; numpy reference ``u_free + MW @ lam``)."""
    nu, m = MW.shape
    for k in range(nu):
        s = 0.0
        for j in range(m):
            s += MW[k, j] * lam[j]
        u[k] = u_free[k] + s


@njit(cache=True)
def impulse_work(lam, gamma_plus, closing, gamma_pre):
    """Λᵀ(γ⁺ − closing + γ⁻)/2 [J]: the impulses' work over the step (stage 6)."""
    s = 0.0
    for i in range(lam.shape[0]):
        s += lam[i] * ((gamma_plus[i] - closing[i]) + gamma_pre[i])
    return 0.5 * s


@njit(cache=True)
def free_velocity(L, blocks, idle, h, dt, u, u_free):
    """u_free = u_k + M̂⁻¹ h Δt (nu,) [m/s] (stage 5) with M̂'s block factor ``L``
    (:func:`mbs.run.linalg_kernels.block_cholesky_into` over ``blocks``, zero on the rows
    ``idle``), h [N], Δt [s]. Numpy reference: ``u + cho_solve(L, h * dt)`` with the same
    roundings (h Δt, the solve in place, the sum)."""
    for i in range(h.shape[0]):
        u_free[i] = h[i] * dt
    block_cho_solve_vector(L, blocks, idle, u_free, u_free)
    for i in range(u.shape[0]):
        u_free[i] = u[i] + u_free[i]


@njit(cache=True)
def free_velocity_update(u, u_free, u_prev):
    """Stage 7 with nothing closed: u_prev = u_k, u = u_free (nu,) [m/s]."""
    for i in range(u.shape[0]):
        u_prev[i] = u[i]
        u[i] = u_free[i]


@njit(cache=True)
def warm_start_into(table, closed_idx, n_closed, warm, lam_prev, n_c, lam):
    """Λ (m,) of stage 6 from the last step's: the block of each of the first ``n_closed``
    contacts of ``closed_idx`` (rows n_c.. in order, contact i's block at
    lam_prev[table[i, LAM_AT]:][:table[i, DIM]], the contact table's columns) when
    ``warm[i]``, else zero; the joints' rows [0, n_c) zero (the caller copies theirs).
    Python reference: :func:`mbs.run.stages.warm_start`'s loop."""
    for r in range(lam.shape[0]):
        lam[r] = 0.0
    row = n_c
    for j in range(n_closed):
        i = closed_idx[j]
        at, dim = table[i, LAM_AT], table[i, DIM]
        if warm[i]:
            for k in range(dim):
                lam[row + k] = lam_prev[at + k]
        row += dim


@njit(cache=True)
def keep_warm_start_into(table, closed_idx, n_closed, lam, n_c, warm, lam_prev):
    """The closed contacts' blocks of Λ (rows n_c.. in order) into ``lam_prev`` and
    ``warm[i]`` True for them, False for every other contact (the inverse of
    :func:`warm_start_into`)."""
    for i in range(warm.shape[0]):
        warm[i] = False
    row = n_c
    for j in range(n_closed):
        i = closed_idx[j]
        at, dim = table[i, LAM_AT], table[i, DIM]
        for k in range(dim):
            lam_prev[at + k] = lam[row + k]
        warm[i] = True
        row += dim


@njit(cache=True)
def path_power(theta, u, u_prev, Q):
    """vᵀQ with v = θ u_{k+1} + (1 − θ) u_k (nu,) [m/s] the velocity the step's positions
    advance with (stage 8: q_{k+1} = q_k ⊕ Δt v) and Q (nu,) [N] generalized forces:
    their power [W] along the step (:mod:`mbs.run.step_work`). Numpy reference:
    ``(theta * u + (1 - theta) * u_prev) @ Q``."""
    s = 0.0
    for i in range(Q.shape[0]):
        s += (theta * u[i] + (1.0 - theta) * u_prev[i]) * Q[i]
    return s


@njit(cache=True)
def damping_power(theta, u, u_prev, rows, D):
    """vᵀ D v [W] over the damped rows ``rows`` (k,) of u, D (k, k) [N s/m] the damping
    on them and v = θ u_{k+1} + (1 − θ) u_k as in :func:`path_power`. Numpy reference:
    ``v[rows] @ D @ v[rows]``."""
    s = 0.0
    for a in range(rows.shape[0]):
        va = theta * u[rows[a]] + (1.0 - theta) * u_prev[rows[a]]
        t = 0.0
        for b in range(rows.shape[0]):
            t += D[a, b] * (theta * u[rows[b]] + (1.0 - theta) * u_prev[rows[b]])
        s += va * t
    return s


@njit(cache=True)
def pressed_contacts(table, warm, lam_prev, comp_force, closed, force_N):
    """The contacts that transmit a force in the last step: a set-valued contact (rows of
    Λ: table[i, DIM] > 0) closed in it (``warm``) with a non-zero impulse Λ or spring force
    F (compliant contacts) in its block lam_prev[table[i, LAM_AT]:][:table[i, DIM]], a
    single-valued one closed with a non-zero normal force. Reference: the same loop in
    Python."""
    n = 0
    for i in range(warm.shape[0]):
        at, dim = table[i, LAM_AT], table[i, DIM]
        if dim > 0:
            if warm[i]:
                for k in range(dim):
                    if lam_prev[at + k] != 0.0 or comp_force[at + k] != 0.0:
                        n += 1
                        break
        elif closed[i] and force_N[i] != 0.0:
            n += 1
    return n


@njit(cache=True)
def spring_energy(table, warm, force, delta):
    """½ Σ Fᵀ δ [J] over the compliant contacts closed in the last step (table[i, COMPLIANT]
    and ``warm[i]``), each with its block force[table[i, LAM_AT]:][:table[i, DIM]] [N] of
    spring forces and the same block of ``delta`` [m] of deflections. Reference:
    ``Σ 0.5 * force[block] @ delta[block]`` over those contacts."""
    e = 0.0
    for i in range(warm.shape[0]):
        if table[i, COMPLIANT] != 0 and warm[i]:
            at, dim = table[i, LAM_AT], table[i, DIM]
            s = 0.0
            for k in range(dim):
                s += force[at + k] * delta[at + k]
            e += 0.5 * s
    return e


@njit(cache=True)
def closed_set(located, live_idx, n_live, table, contact_f, warm, comp_force, comp_delta, closed, closed_idx, n_c):
    """Stage 4's bookkeeping over the live contacts live_idx[:n_live], each located
    (``located[i]``: g_N <= its closing tolerance): closed[i] — located, or a compliant
    contact apart only by its spring's deflection (warm, spring force comp_force > 0, its
    kinematics active in ``contact_f``: the spring must release first) —; the closed
    set-valued contacts into closed_idx; their penetration max(0, −g_N) (−g_N − δ of a
    compliant one: its effective gap). Returns (closed set-valued contacts, rows m from
    n_c on, the largest penetration [m] or 0). Reference: the loop it replaced in
    :func:`mbs.run.stages.detect`."""
    n_closed, m, largest = 0, n_c, 0.0
    for j in range(n_live):
        i = live_idx[j]
        kin, at = table[i, KIN_AT], table[i, LAM_AT]
        spring = table[i, COMPLIANT] != 0 and warm[i]
        c = located[i] or (spring and comp_force[at] > 0.0 and contact_f[kin + ACTIVE_AT] != 0.0)
        closed[i] = c
        if not c:
            continue
        if table[i, DIM] > 0:
            closed_idx[n_closed] = i
            n_closed += 1
            m += table[i, DIM]
        if table[i, UNILATERAL]:
            pen = -contact_f[kin + G_N_AT]
            if spring:
                pen -= comp_delta[at]
            largest = max(largest, pen)
    return n_closed, m, largest


@njit(cache=True)
def contact_rows_into(W, closing, contact_f, table, closed_idx, n_closed, n_c, warm, dt):
    """Stage 5's columns of the closed set-valued contacts: for each contact i of
    closed_idx[:n_closed], from its kinematics in ``contact_f`` (rows of ``table``, the
    columns above), W[:, row:row + dim] += [w_N] (dim 1), [w_N, W_T] (dim 3) or
    [w_N, w_T2] (a point kept on a curve) at each body's rows of u (eq. 3.8; body 1's
    then body 2's, both may be one body), and closing[row] = g_N/Δt [m/s] for a unilateral
    contact resting within its closing tolerance (g_N > 0 while warm[i]); rows from n_c on.
    W and closing zero on entry. Reference: ``Contact.jacobian`` and ``kinematics.g_N / dt``
    per closed contact."""
    row = n_c
    for j in range(n_closed):
        i = closed_idx[j]
        kin, dim = table[i, KIN_AT], table[i, DIM]
        for side in range(2):
            start = table[i, START1 + side]
            if start < 0:
                continue
            w_N, w_T = kin + table[i, W_N1_AT + side], kin + table[i, W_T1_AT + side]
            for k in range(table[i, NU1 + side]):
                W[start + k, row] += contact_f[w_N + k]
                if table[i, ON_CURVE]:
                    W[start + k, row + 1] += contact_f[w_T + 2 * k + 1]
                elif dim == 3:
                    W[start + k, row + 1] += contact_f[w_T + 2 * k]
                    W[start + k, row + 2] += contact_f[w_T + 2 * k + 1]
        g_N = contact_f[kin + G_N_AT]
        if table[i, UNILATERAL] and g_N > 0.0 and warm[i]:
            closing[row] = g_N / dt
        row += dim


"""numba kernels of the prox iterations of :mod:`contact.solver` (Studer 2009, ch. 6).

The contact problem is encoded in arrays: ``kinds`` (n_e,) int64 of the entries
(``BILATERAL`` one scalar row, ``UNILATERAL`` one normal row, ``COULOMB`` rows
[N, T1, T2]), their first rows ``offsets`` (n_e,) int64 and friction coefficients
``mu`` (n_e,). The law's velocity is affine in Λ: ξ = c + G Λ with
c = ξ_free + ε γ⁻ (m,) [m/s]; ``r`` (m,) [kg] holds the prox factors (equal on T1, T2).
Every kernel works in place and allocates nothing. The sweeps return the largest scaled
change max_i |Λ_i^new − Λ_i| / r_i [m/s] of a sweep, the natural-map residual of the rows
as they were visited. The plain-numpy references of the sweeps, built on the laws'
``project``, are in the tests.
"""

from __future__ import annotations

import math

from numba import njit

BILATERAL = 0
UNILATERAL = 1
COULOMB = 2
ROUNDING = 8.0 * 2.0 ** -52   # 8 x machine epsilon of float64
ADAPT_WINDOW = 50             # sweeps between the checks for progress of prox_iterate
MAX_HALVINGS = 20             # of the r-factors in one prox_iterate (r >= 1e-6 r0)
NORMAL_PHASE_FACTOR = 4       # with friction: a normal phase every this many subspace intervals
NORMAL_PHASE_WINDOW = 4       # normal phases between the checks for progress (friction)
NEWTON_EVERY = 20             # with friction: sweeps between the Newton phases
NEWTON_STEPS = 30             # most steps of one Newton phase
NEWTON_R_SCALE = 1000.0       # the Newton phase's prox factors: this times the sweeps' r
NEWTON_MIN_STEP = 1e-6        # smallest line-search step of the Newton phase
ARMIJO_SIGMA = 1e-4           # sufficient decrease of |F|² in the Newton phase
PIVOT_TOL = 1e-13             # pivots below this times the first: the rank of the Newton matrix


@njit(cache=True)
def _row_velocity(G, c, lam, i):
    """(ξ_i = c_i + Σ_j G_ij Λ_j, its scale |c_i| + Σ_j |G_ij Λ_j|) [m/s]."""
    s = c[i]
    a = abs(c[i])
    for j in range(lam.shape[0]):
        t = G[i, j] * lam[j]
        s += t
        a += abs(t)
    return s, a


@njit(cache=True)
def _disk(z1, z2, radius):
    """Projection of (z1, z2) onto the disk of radius ``radius`` >= 0."""
    norm = math.hypot(z1, z2)
    if norm > radius:
        scale = radius / norm
        return z1 * scale, z2 * scale
    return z1, z2


@njit(cache=True)
def _finite(x):
    for v in x:
        if not math.isfinite(v):
            return False
    return True


@njit(cache=True)
def velocities(G, c, lam, xi):
    """ξ = c + G Λ into ``xi`` (m,); returns the scale max_i (|c_i| + Σ_j |G_ij Λ_j|) [m/s]."""
    scale = 0.0
    for i in range(lam.shape[0]):
        xi[i], a = _row_velocity(G, c, lam, i)
        scale = max(scale, a)
    return scale


@njit(cache=True)
def prox_step(xi, r, kinds, offsets, mu, lam, update):
    """Λ ← prox_C(Λ − r ξ) for all entries at once from the given ``xi`` (Jacobi).

    With ``update`` False ``lam`` is left alone and the return value is the natural-map
    residual max_i |Λ_i − prox_C(Λ − r ξ)_i| / r_i [m/s] of the current Λ.
    """
    change = 0.0
    for k in range(kinds.shape[0]):
        o = offsets[k]
        z = lam[o] - r[o] * xi[o]
        if kinds[k] != BILATERAL:
            z = max(z, 0.0)
        change = max(change, abs(z - lam[o]) / r[o])
        if kinds[k] == COULOMB:
            z1, z2 = _disk(lam[o + 1] - r[o + 1] * xi[o + 1],
                           lam[o + 2] - r[o + 2] * xi[o + 2], mu[k] * z)
            change = max(change, abs(z1 - lam[o + 1]) / r[o + 1],
                         abs(z2 - lam[o + 2]) / r[o + 2])
            if update:
                lam[o + 1] = z1
                lam[o + 2] = z2
        if update:
            lam[o] = z
    return change


@njit(cache=True)
def _first_row(G, c, r, kind, o, lam):
    """Project the first row ``o`` of an entry of ``kind`` (normal: onto Λ ≥ 0; bilateral:
    free) with the newest Λ, in place; returns (|ΔΛ_o| / r_o, |c_o| + Σ_j |G_oj Λ_j|)."""
    xi, a = _row_velocity(G, c, lam, o)
    z = lam[o] - r[o] * xi
    if kind != BILATERAL:
        z = max(z, 0.0)
    change = abs(z - lam[o]) / r[o]
    lam[o] = z
    return change, a


@njit(cache=True)
def gauss_seidel_sweep(G, c, r, kinds, offsets, mu, lam):
    """One projected Gauss–Seidel sweep over the entries, in place.

    Each row's ξ_i uses the newest Λ; in a Coulomb entry the normal row goes first and
    the tangential pair then uses the new Λ_N both in ξ_T and in the disk radius μ Λ_N.
    Returns (scaled change, max_i (|c_i| + Σ_j |G_ij Λ_j|) over the rows as visited).
    """
    change = 0.0
    scale = 0.0
    for k in range(kinds.shape[0]):
        o = offsets[k]
        d, a = _first_row(G, c, r, kinds[k], o, lam)
        change, scale = max(change, d), max(scale, a)
        z = lam[o]
        if kinds[k] == COULOMB:
            xi1, a1 = _row_velocity(G, c, lam, o + 1)
            xi2, a2 = _row_velocity(G, c, lam, o + 2)
            scale = max(scale, a1, a2)
            z1, z2 = _disk(lam[o + 1] - r[o + 1] * xi1, lam[o + 2] - r[o + 2] * xi2, mu[k] * z)
            change = max(change, abs(z1 - lam[o + 1]) / r[o + 1],
                         abs(z2 - lam[o + 2]) / r[o + 2])
            lam[o + 1] = z1
            lam[o + 2] = z2
    return change, scale


@njit(cache=True)
def threshold(tol, c_ref, m, v_terms):
    """tol · c_ref + ROUNDING · (m + 1) · v_terms [m/s] (see :func:`prox_iterate`)."""
    return tol * c_ref + ROUNDING * (m + 1) * v_terms


@njit(cache=True)
def _active(kind, lam_o):
    """Whether a frictionless entry is free in the subspace step: bilateral, or Λ > 0."""
    return kind == BILATERAL or lam_o > 0.0


@njit(cache=True)
def subspace_step(G, c, r, kinds, offsets, lam, rho, p, q, accuracy, max_steps):
    """Conjugate gradients on the rows the sweeps left active, in place, for a problem
    without friction or with the tangential impulses held (:func:`normal_phase`); only
    the entries' first rows (normal, bilateral) move.

    Λ ≥ 0 on the unilateral rows with ξ = c + G Λ is the minimum of the convex quadratic
    f(Λ) = ½ Λᵀ G Λ + cᵀ Λ (∇f = ξ) on that box; a sweep is a projected coordinate
    descent of f. With the active set A (bilateral rows and Λ_i > 0) fixed and the other
    rows at 0, f is minimized over Λ_A by conjugate gradients preconditioned with
    ``r`` (∝ 1 / G_ii) from the current Λ (Hestenes & Stiefel 1952; the subspace
    minimization of PGS-SM, Silcowitz, Niebe & Erleben 2010, and of GPCG, Moré & Toraldo
    1991). A step that would make a unilateral Λ_i negative stops at Λ_i = 0 and ends the
    step. Each step is an exact line minimization of f or shorter, so f never increases.
    G_AA may be singular (more contacts than the bodies' velocities, e.g. a face of
    point contacts on a plane); the system G_AA Λ_A = −c_A − … is then still consistent
    (c lies in the range of Wᵀ) and conjugate gradients reach it in at most rank G_AA
    steps in exact arithmetic. Stops when max_A |ξ_i| ≤ ``accuracy`` [m/s], after
    ``max_steps`` or when pᵀ G p ≤ 0. ``rho``, ``p``, ``q`` (m,) are work arrays.
    Returns the steps taken (one G p each).
    """
    steps = 0
    while steps < max_steps:                 # a restart after each row that reached 0
        velocities(G, c, lam, rho)
        p[:] = 0.0                           # the tangential rows of Coulomb entries stay
        rz = 0.0
        largest = 0.0
        for k in range(kinds.shape[0]):
            o = offsets[k]
            rho[o] = -rho[o] if _active(kinds[k], lam[o]) else 0.0
            p[o] = r[o] * rho[o]
            rz += rho[o] * p[o]
            largest = max(largest, abs(rho[o]))
        hit = -1
        while largest > accuracy and steps < max_steps:
            steps += 1
            hit = _conjugate_gradient_step(G, kinds, offsets, r, lam, rho, p, q, rz)
            if hit != -1:
                break
            rz_new = 0.0
            largest = 0.0
            for k in range(kinds.shape[0]):
                o = offsets[k]
                if _active(kinds[k], lam[o]):
                    rz_new += r[o] * rho[o] * rho[o]
                    largest = max(largest, abs(rho[o]))
            beta = rz_new / rz
            rz = rz_new
            for k in range(kinds.shape[0]):
                o = offsets[k]
                p[o] = r[o] * rho[o] + beta * p[o] if _active(kinds[k], lam[o]) else 0.0
        if hit < 0:
            break
    return steps


@njit(cache=True)
def _conjugate_gradient_step(G, kinds, offsets, r, lam, rho, p, q, rz):
    """Λ_A += a p, ρ −= a G p with a = ρᵀ z / pᵀ G p (``rz`` = ρᵀ z) or shorter, where a
    unilateral Λ_i reaches 0 (that row is then set to 0). Returns −1 after a full step,
    the row that reached 0, or −2 when pᵀ G p ≤ 0 (nothing done)."""
    pq = 0.0
    for k in range(kinds.shape[0]):
        o = offsets[k]
        q[o] = 0.0
        if _active(kinds[k], lam[o]):
            s = 0.0
            for j in range(lam.shape[0]):
                s += G[o, j] * p[j]
            q[o] = s
            pq += p[o] * s
    if not pq > 0.0:
        return -2
    a = rz / pq
    hit = -1
    for k in range(kinds.shape[0]):
        o = offsets[k]
        if kinds[k] != BILATERAL and lam[o] > 0.0 and p[o] < 0.0 and -lam[o] / p[o] < a:
            a = -lam[o] / p[o]
            hit = o
    for k in range(kinds.shape[0]):
        o = offsets[k]
        if _active(kinds[k], lam[o]):
            lam[o] = lam[o] + a * p[o] if kinds[k] == BILATERAL else max(lam[o] + a * p[o], 0.0)
            rho[o] -= a * q[o]
    if hit >= 0:
        lam[hit] = 0.0
    return hit


@njit(cache=True)
def normal_sweep(G, c, r, kinds, offsets, lam):
    """One projected Gauss–Seidel sweep over the entries' first rows (normal, bilateral),
    the tangential impulses of Coulomb entries held; returns the scaled change and the
    scale as :func:`gauss_seidel_sweep`."""
    change = 0.0
    scale = 0.0
    for k in range(kinds.shape[0]):
        d, a = _first_row(G, c, r, kinds[k], offsets[k], lam)
        change, scale = max(change, d), max(scale, a)
    return change, scale


@njit(cache=True)
def normal_phase(G, c, r, kinds, offsets, lam, xi, p, q, tol, c_ref, subspace_every, max_steps):
    """The normal problem with the tangential impulses held, solved in place: ξ_N = c_N +
    G_NN Λ_N + G_NT Λ_T is a frictionless problem in Λ_N, a box-constrained convex quadratic
    program, whose sweeps (:func:`normal_sweep`) with a subspace step every
    ``subspace_every`` of them find the closed set and the impulses on it where the
    coupled sweeps crawl (the normal half of the staggered projections, Kaufman, Sueda,
    James & Pai 2008). Stops when the scaled change is within the threshold of
    :func:`prox_iterate` or after ``max_steps`` sweeps and conjugate-gradient steps;
    returns their number."""
    steps = 0
    sweeps = 0
    while steps < max_steps:
        steps += 1
        sweeps += 1
        change, v_terms = normal_sweep(G, c, r, kinds, offsets, lam)
        accuracy = threshold(tol, c_ref, c.shape[0], v_terms)
        if change <= accuracy:
            break
        if sweeps % subspace_every == 0 and steps < max_steps:
            steps += subspace_step(G, c, r, kinds, offsets, lam, xi, p, q, accuracy, max_steps - steps)
    return steps


@njit(cache=True)
def _local_projection(kind, mu_k, z, P, D):
    """prox_C of one entry at z (its rows) into P and its generalized derivative ∂P/∂z
    into D (3, 3): bilateral P = z; unilateral P = max(z, 0); Coulomb P_N = max(z_N, 0),
    P_T = z_T inside the disk of radius μ P_N, else μ P_N n (n = z_T / |z_T|), whose
    derivative is μ P_N / |z_T| (I − n nᵀ) in z_T and μ n in z_N (z_N > 0)."""
    D[:, :] = 0.0
    if kind == BILATERAL:
        P[0] = z[0]
        D[0, 0] = 1.0
        return
    P[0] = max(z[0], 0.0)
    D[0, 0] = 1.0 if z[0] > 0.0 else 0.0
    if kind != COULOMB:
        return
    radius = mu_k * P[0]
    norm = math.hypot(z[1], z[2])
    if norm <= radius and radius > 0.0:
        P[1], P[2] = z[1], z[2]
        D[1, 1] = D[2, 2] = 1.0
    elif norm > 0.0:
        n1, n2 = z[1] / norm, z[2] / norm
        P[1], P[2] = radius * n1, radius * n2
        f = radius / norm
        D[1, 1], D[1, 2], D[2, 1], D[2, 2] = f * (1.0 - n1 * n1), -f * n1 * n2, -f * n1 * n2, f * (1.0 - n2 * n2)
        if z[0] > 0.0:
            D[1, 0], D[2, 0] = mu_k * n1, mu_k * n2
    else:
        P[1] = P[2] = 0.0


@njit(cache=True)
def natural_map(G, c, r, scale, kinds, offsets, mu, lam, F, J, jacobian, local):
    """The natural map F(Λ) = (Λ − prox_C(Λ − s r ξ)) / (s r) [m/s], ξ = c + G Λ, s =
    ``scale``, into ``F`` (m,); zero exactly at a solution (Alart & Curnier 1991; Acary &
    Brogliato 2008, sec. 12.5). With ``jacobian``, a generalized Jacobian ∂F/∂Λ =
    (I − D (I − s R G)) / (s r) into ``J`` (m, m) (D the block diagonal of the entries'
    ∂P/∂z, :func:`_local_projection`). ``local`` (5, 3) work (z, P, D of an entry).
    Returns |F|² [m²/s²]."""
    m = lam.shape[0]
    z = local[0]
    P = local[1]
    D = local[2:5]
    psi = 0.0
    for k in range(kinds.shape[0]):
        o = offsets[k]
        rows = 3 if kinds[k] == COULOMB else 1
        for a in range(rows):
            xi, _ = _row_velocity(G, c, lam, o + a)
            z[a] = lam[o + a] - scale * r[o + a] * xi
        _local_projection(kinds[k], mu[k], z, P, D)
        for a in range(rows):
            ra = scale * r[o + a]
            F[o + a] = (lam[o + a] - P[a]) / ra
            psi += F[o + a] * F[o + a]
            if jacobian:
                for col in range(m):
                    v = 1.0 if col == o + a else 0.0
                    for b in range(rows):
                        e = 1.0 if col == o + b else 0.0
                        v -= D[a, b] * (e - scale * r[o + b] * G[o + b, col])
                    J[o + a, col] = v / ra
    return psi


@njit(cache=True)
def complete_pivoting_solve(A, b, x, perm_r, perm_c, tol):
    """A basic solution of A x = b (A (m, m), overwritten, as is ``b``) by Gaussian
    elimination with complete pivoting; elimination stops where the largest remaining
    pivot is below ``tol`` times the first (the numerical rank k), and the unknowns past
    k are zero (Golub & Van Loan 2013, sec. 3.4.8). For a consistent singular system
    (more contacts than velocities) this is an exact solution. ``perm_r``, ``perm_c`` (m,)
    int64 work. Returns k."""
    m = b.shape[0]
    for i in range(m):
        perm_r[i] = i
        perm_c[i] = i
    first = 0.0
    rank = m
    for k in range(m):
        p, q, big = k, k, -1.0
        for i in range(k, m):
            for j in range(k, m):
                v = abs(A[perm_r[i], perm_c[j]])
                if v > big:
                    p, q, big = i, j, v
        if k == 0:
            first = big
        if not big > tol * first or big == 0.0:
            rank = k
            break
        perm_r[k], perm_r[p] = perm_r[p], perm_r[k]
        perm_c[k], perm_c[q] = perm_c[q], perm_c[k]
        pr, pc = perm_r[k], perm_c[k]
        for i in range(k + 1, m):
            ri = perm_r[i]
            f = A[ri, pc] / A[pr, pc]
            if f != 0.0:
                for j in range(k + 1, m):
                    A[ri, perm_c[j]] -= f * A[pr, perm_c[j]]
                b[ri] -= f * b[pr]
    for j in range(m):
        x[j] = 0.0
    for k in range(rank - 1, -1, -1):
        pr = perm_r[k]
        s = b[pr]
        for j in range(k + 1, rank):
            s -= A[pr, perm_c[j]] * x[perm_c[j]]
        x[perm_c[k]] = s / A[pr, perm_c[k]]
    return rank


@njit(cache=True)
def newton_phase(G, c, r, kinds, offsets, mu, lam, F, d, trial, J, perm_r, perm_c, local, max_steps):
    """Semismooth Newton steps on the natural map with prox factors NEWTON_R_SCALE · r
    (:func:`natural_map`), in place: the direction solves J d = −F
    (:func:`complete_pivoting_solve`), the step is the largest s = 2^-k >= NEWTON_MIN_STEP
    with |F(Λ + s d)|² <= (1 − ARMIJO_SIGMA s) |F(Λ)|² (Qi & Sun 1993; De Luca, Facchinei
    & Kanzow 1996). Ends after ``max_steps`` steps or where the line search fails (Λ is
    then the last accepted iterate). ``F``, ``d``, ``trial`` (m,), ``J`` (m, m), ``local``
    (5, 3) work.
    Returns the steps taken (one solve each)."""
    m = lam.shape[0]
    scale = NEWTON_R_SCALE
    psi = natural_map(G, c, r, scale, kinds, offsets, mu, lam, F, J, bool(True), local)
    steps = 0
    while steps < max_steps and psi > 0.0:
        for i in range(m):
            trial[i] = -F[i]
        complete_pivoting_solve(J, trial, d, perm_r, perm_c, PIVOT_TOL)
        steps += 1
        s = 1.0
        accepted = False
        while s >= NEWTON_MIN_STEP:
            for i in range(m):
                trial[i] = lam[i] + s * d[i]
            psi_trial = natural_map(G, c, r, scale, kinds, offsets, mu, trial, F, J, bool(False), local)
            if psi_trial <= (1.0 - ARMIJO_SIGMA * s) * psi:
                accepted = True
                break
            s *= 0.5
        if not accepted or not _finite(trial):
            break
        for i in range(m):
            lam[i] = trial[i]
        psi = natural_map(G, c, r, scale, kinds, offsets, mu, lam, F, J, bool(True), local)
    return steps


@njit(cache=True)
def _project_admissible(kinds, offsets, mu, lam):
    """Λ onto the admissible impulses, in place: Λ_N >= 0, |Λ_T| <= μ Λ_N (a Newton
    iterate within the tolerance may leave them by a rounding-sized amount)."""
    for k in range(kinds.shape[0]):
        o = offsets[k]
        if kinds[k] == BILATERAL:
            continue
        lam[o] = max(lam[o], 0.0)
        if kinds[k] == COULOMB:
            lam[o + 1], lam[o + 2] = _disk(lam[o + 1], lam[o + 2], mu[k] * lam[o])


@njit(cache=True)
def _solved_after_newton(G, c, r, kinds, offsets, mu, lam, xi, tol, c_ref):
    """(residual [m/s], whether Λ is within the threshold of :func:`prox_iterate`); a Λ
    within it is projected onto the admissible impulses and checked again."""
    m = c.shape[0]
    v_terms = velocities(G, c, lam, xi)
    residual = prox_step(xi, r, kinds, offsets, mu, lam, bool(False))
    if residual > threshold(tol, c_ref, m, v_terms):
        return residual, False
    _project_admissible(kinds, offsets, mu, lam)
    v_terms = velocities(G, c, lam, xi)
    residual = prox_step(xi, r, kinds, offsets, mu, lam, bool(False))
    return residual, residual <= threshold(tol, c_ref, m, v_terms)


@njit(cache=True)
def _newton_phase_counted(G, c, r, kinds, offsets, mu, lam, F, d, trial, J, perm_r, perm_c, local, budget):
    """:func:`newton_phase` of at most min(NEWTON_STEPS, ``budget``) steps; returns them."""
    return newton_phase(G, c, r, kinds, offsets, mu, lam, F, d, trial, J, perm_r, perm_c, local,
                        min(NEWTON_STEPS, budget))


@njit(cache=True)
def prox_iterate(G, c, r, kinds, offsets, mu, lam, xi, r_work, jacobi, tol, max_iter, subspace_every, p, q,
                 newton_first, J, perm_r, perm_c, local):
    """Sweep until the scaled change and then the natural residual are <= the threshold

        tol · max_i |c_i| + ROUNDING · (m + 1) · max_i (|c_i| + Σ_j |G_ij Λ_j|)   [m/s],

    the requested accuracy of the velocities plus a bound of the rounding error of
    ξ = c + G Λ (Higham 2002, eq. 3.5, times 8), which dominates when large impulses
    cancel (a stack of very different masses). The bound's scale comes from the sweep
    for the change and from the final Λ for the residual.

    The sweeps use the factors ``r_work`` (m,), initialized from ``r``. With friction
    the prox map can be expansive and the iteration cycle: when the change is no
    smaller than a window of sweeps before (ADAPT_WINDOW sweeps; with normal phases
    NORMAL_PHASE_WINDOW of their intervals, the change taken just before one: the sweeps
    after a normal phase need not shrink the change at once), ``r_work`` is halved
    (at most MAX_HALVINGS times; the r-factor reduction of MBSim, after M. Förg,
    dissertation TU München 2007, p. 80 ff.). Frictionless problems converge without it
    (projected SOR) and keep their r. The residual is always measured with ``r``. ``xi``
    (m,) is a work array. Without friction, every ``subspace_every`` sweeps (0: never) a
    subspace step (:func:`subspace_step`) minimizes the problem's quadratic on the rows
    the sweeps found active; with friction, every NORMAL_PHASE_FACTOR · ``subspace_every``
    sweeps a normal phase (:func:`normal_phase`) solves the normal problem with the
    tangential impulses held, and every NEWTON_EVERY sweeps a Newton phase
    (:func:`newton_phase`, also before the first sweep with ``newton_first``) takes
    semismooth Newton steps on the natural map, where the sweeps converge linearly at a
    rate set by the conditioning of G (a face whose few carrying contacts slide by
    velocities 1e-4 of ξ_free). Their sweeps, conjugate-gradient iterations and Newton
    steps count as sweeps (one G p, one row pass or one solve each); they work in ``p``,
    ``q`` (m,), and the Newton phase also in ``xi``, ``J`` (m, m), ``perm_r``, ``perm_c``
    (m,) int64 and ``local`` (5, 3).
    Returns (sweeps, residual [m/s], converged); the residual is the natural-map
    residual of the returned Λ (one extra G Λ per check).
    """
    m = c.shape[0]
    c_ref = 0.0
    for i in range(m):
        c_ref = max(c_ref, abs(c[i]))
        r_work[i] = r[i]
    halvings_left = 0
    for k in range(kinds.shape[0]):
        if kinds[k] == COULOMB:
            halvings_left = MAX_HALVINGS
    frictional = halvings_left > 0
    interval = subspace_every * (NORMAL_PHASE_FACTOR if frictional else 1)   # sweeps between subspace steps
    window = NORMAL_PHASE_WINDOW * interval if frictional and subspace_every > 0 else ADAPT_WINDOW   # progress checks
    window_change = math.inf
    it = 0
    sweeps = 0
    newton = frictional and subspace_every > 0
    if newton and newton_first:
        it += _newton_phase_counted(G, c, r, kinds, offsets, mu, lam, xi, p, q, J, perm_r, perm_c, local,
                                    max_iter - it)
        residual, solved = _solved_after_newton(G, c, r, kinds, offsets, mu, lam, xi, tol, c_ref)
        if solved:
            return it, residual, True
    while it < max_iter:
        it += 1
        sweeps += 1
        if jacobi:
            v_terms = velocities(G, c, lam, xi)
            change = prox_step(xi, r_work, kinds, offsets, mu, lam, bool(True))
        else:
            change, v_terms = gauss_seidel_sweep(G, c, r_work, kinds, offsets, mu, lam)
        if not _finite(lam):
            return it, math.inf, False
        if halvings_left > 0 and sweeps % window == 0:
            if change >= (1.0 - 1e-12) * window_change:   # no progress: cycling
                for i in range(m):
                    r_work[i] *= 0.5
                halvings_left -= 1
                window_change = math.inf
            else:
                window_change = change
        if change <= threshold(tol, c_ref, m, v_terms):
            v_terms = velocities(G, c, lam, xi)
            residual = prox_step(xi, r, kinds, offsets, mu, lam, bool(False))
            if residual <= threshold(tol, c_ref, m, v_terms):
                return it, residual, True
        elif subspace_every > 0 and sweeps % interval == 0 and it < max_iter:
            if frictional:
                it += normal_phase(G, c, r, kinds, offsets, lam, xi, p, q, tol, c_ref, subspace_every, max_iter - it)
            else:
                it += subspace_step(G, c, r, kinds, offsets, lam, xi, p, q, threshold(tol, c_ref, m, v_terms),
                                    max_iter - it)
        if newton and sweeps % NEWTON_EVERY == 0 and it < max_iter:
            it += _newton_phase_counted(G, c, r, kinds, offsets, mu, lam, xi, p, q, J, perm_r, perm_c, local,
                                        max_iter - it)
            residual, solved = _solved_after_newton(G, c, r, kinds, offsets, mu, lam, xi, tol, c_ref)
            if solved:
                return it, residual, True
    v_terms = velocities(G, c, lam, xi)
    residual = prox_step(xi, r, kinds, offsets, mu, lam, bool(False))
    return max_iter, residual, residual <= threshold(tol, c_ref, m, v_terms)


@njit(cache=True)
def diagonal_floor(G, tiny, d):
    """diag(G) into ``d`` (m,) with rows that touch no mass (G_ii <= tiny · max G_jj)
    replaced by max G_jj, all ones when no G_jj is positive (the diagonal scaling of
    the prox factors; numpy reference :func:`contact.solver.diagonal_reference`)."""
    d_max = 0.0
    for i in range(d.shape[0]):
        d[i] = G[i, i]
        if d[i] > d_max:
            d_max = d[i]
    if d_max <= 0.0:
        d[:] = 1.0
        return
    for i in range(d.shape[0]):
        if not d[i] > tiny * d_max:
            d[i] = d_max


@njit(cache=True)
def gauss_seidel_solve(G, xi_free, gamma_pre, restitution, kinds, offsets, mu, tangent_at, alpha, tiny, tol,
                       max_iter, subspace_every, lam, gamma_plus, work, newton_first, J, pivots, local):
    """The projected Gauss–Seidel solve of :meth:`contact.solver.ProxSolver.solve_into`
    with automatic r, whole: c = ξ_free + ε γ⁻ (Λ = 0 when c = 0); r_i = α / G_ii
    (:func:`diagonal_floor`), a Coulomb contact's tangential rows α / max(λ_max(G_TT),
    G_T1T1, G_T2T2); :func:`prox_iterate` from the warm start in ``lam``; γ⁺ = ξ_free + G Λ.
    ``tangent_at``: the first tangential row of every Coulomb contact; ``work`` (6, m)
    scratch (c, r, ξ, the sweeps' r, the subspace step's p and q); ``newton_first``, ``J``
    (m, m), ``pivots`` (2, m) int64 and ``local`` (5, 3): the Newton phases of a problem
    with friction (:func:`prox_iterate`). Returns (sweeps, residual [m/s], converged).
    Numpy reference: the same steps with ``np.multiply``, ``np.add``, ``np.matmul``
    (``tests/unit/contact/test_contact_solver.py``)."""
    m = G.shape[0]
    c = work[0]
    r = work[1]
    xi = work[2]
    r_work = work[3]
    nonzero = False
    for i in range(m):
        c[i] = xi_free[i] + restitution[i] * gamma_pre[i]
        if c[i] != 0.0:
            nonzero = True
    if not nonzero:                 # Λ = 0 solves every law
        for i in range(m):
            lam[i] = 0.0
            gamma_plus[i] = xi_free[i]
        return 0, 0.0, True
    diagonal_floor(G, tiny, r)
    for i in range(m):
        r_work[i] = r[i]            # the diagonal, kept for the tangential rows
        r[i] = alpha / r[i]
    for k in range(tangent_at.shape[0]):
        t = tangent_at[k]
        a = G[t, t]
        b = G[t, t + 1]
        e = G[t + 1, t + 1]
        lam_max = 0.5 * (a + e) + math.hypot(0.5 * (a - e), b)
        r[t] = r[t + 1] = alpha / max(lam_max, r_work[t], r_work[t + 1])
    it, residual, converged = prox_iterate(G, c, r, kinds, offsets, mu, lam, xi, r_work, bool(False), tol, max_iter,
                                           subspace_every, work[4], work[5], newton_first, J, pivots[0], pivots[1],
                                           local)
    for i in range(m):
        s = 0.0
        for j in range(m):
            s += G[i, j] * lam[j]
        gamma_plus[i] = xi_free[i] + s
    return it, residual, converged

"""The eight stages of one Moreau step (DESIGN, "the data flow of one Moreau step";
thesis eq. 3.1, 4.1; the θ-method of Moreau–Jean, Acary & Brogliato 2008, Sec. 10.1).

Each stage is a function ``stage(model, data, dt)`` of a :class:`~mbs.run.model.Model` and
its :class:`~mbs.run.model.Data` that reads the arrays the previous stages wrote:

1. :func:`midpoint`: t_θ = t_k + θΔt, q_θ = q_k ⊕ θΔt u_k (θ = ½: the thesis's midpoint
   q_m), orientations renormalized → ``t_m``, ``q_m``;
2. :func:`bodies`: h (and M unless M̂ is constant) at (t_θ, q_θ, u_k) → ``h``, ``M``;
3. :func:`contours`: in a planned run the contacts whose contours' bounding spheres
   come within the margin (the others open, counted as pruned) → ``live``; every
   contour of a live contact updated at (t_θ, q_θ, u_k), each once — but those of
   contacts with a fused detection (``model.fused``), which stage 4 updates;
4. :func:`detect`: the live contacts located (broad phase by bounding boxes, search,
   g_N, frame, point Jacobians; a fused detection, :mod:`mbs.run.fused_detection`, updates
   its contours and does all this in one compiled call); a unilateral contact is closed where
   g_N(q_θ) <= its ``closing_tol``, or while the spring of a compliant contact still
   pushes (:mod:`contact.compliance`: the effective gap is g_N + δ) → ``closed``, the
   closed set-valued contacts in ``closed_idx``, the largest penetration;
5. :func:`constraints`: the contact laws at the located contacts — single-valued
   (penalty) forces into h; M̂ = M + θΔt D + θ²Δt² K factored (once per step size when
   constant) and a penalty contact's stiffness checked against the step;
   u_free = u_k + M̂⁻¹ h Δt; for joints and closed set-valued contacts W (nu, m),
   M̂⁻¹W, G = Wᵀ M̂⁻¹ W, ξ_free = Wᵀ u_free + ∂g/∂t + closing, γ⁻ = Wᵀ u_k + ∂g/∂t
   (closing = g_N/Δt for a resting contact still apart within closing_tol);
6. :func:`impulses`: Λ of the laws on velocity level (:meth:`ProxSolver.solve_into`,
   warm-started with the last step's Λ of contacts closed again), the impulses' work
   Λᵀ(γ⁺ + γ⁻)/2, the warm starts kept;
7. :func:`velocity`: u_{k+1} = u_free + M̂⁻¹ W Λ;
8. :func:`position`: q_{k+1} = q_θ ⊕ Δt (θ u_{k+1} + (1 − 2θ) u_k), renormalized;
   t_{k+1} = t_k + Δt.

Why the θ-method, the gap-closing term and the explicit penalty check:
:mod:`mbs.integrators.moreau`. A stage that cannot complete the step raises
:class:`~mbs.run.step_failure.StepFailure`. With the Gauss–Seidel solver and bodies
the body stage writes in place (point masses, FFR bodies on a fixed frame), a steady
step allocates no numpy array.
"""

from __future__ import annotations

import numpy as np
from scipy.linalg.lapack import dpotrf, dpotrs

from contact.compliance import compliant_problem, compliant_update
from contact.laws import Bilateral
from contact.solver import ContactSet

from mbs.bodies import _kernels as BK
from mbs.run import _stage_kernels as K
from mbs.run import residual_contact
from mbs.run.linalg_kernels import block_cho_solve_matrix, block_cho_solve_vector, block_iteration_factor
from mbs.run.step_failure import StepFailure

STAGES = ("midpoint", "bodies", "contours", "detect", "constraints", "impulses", "velocity", "position")


def midpoint(model, data, dt):
    """Stage 1: t_m = t + θΔt, q_m = q ⊕ θΔt u, renormalized."""
    th_dt = model.theta * dt
    data.t_m = data.t + th_dt
    model.body_stage.advance(data.q, data.u, th_dt, data.du, data.q_m)


def bodies(model, data, dt):
    """Stage 2: h (and M when M̂ is not constant) at (t_m, q_m, u)."""
    if model.constant_iteration:
        model.body_stage.h_only(data.t_m, data.q_m, data.u, data.h)
    else:
        model.body_stage.mass_and_h(data.t_m, data.q_m, data.u, data.M, data.h)


def contours(model, data, dt):
    """Stage 3: the live contacts (planned runs: bounding spheres within the margin) and
    their contours updated at (t_m, q_m, u) (but those of fused detections)."""
    if not model.contacts:
        return
    t, q, u, live = data.t_m, data.q_m, data.u, data.live
    if model.prune and len(model.spheres):
        if not data.spheres_started:
            model.spheres.start(q, t, data.sphere_centres, data.sphere_radii)
            data.spheres_started = True
        pruned, data.n_live = model.spheres.prune(q, t, data.sphere_centres, data.sphere_radii, live, data.closed,
                                                  data.live_idx)
        data.stats["pruned_contacts"] += pruned
    n_contours = K.contours_in_use(model.owner_at, model.owners, live, data.contour_idx) if model.owners.size else 0
    for j in range(n_contours):
        contour, owners, qs, us = model.contours[data.contour_idx[j]]
        if qs is None:
            contour.update(None, None, t)
        else:
            contour.update(q[qs], u[us], t)


def detect(model, data, dt):
    """Stage 4: locate the live contacts; closed flags, the closed set-valued contacts
    (``closed_idx``, ``n_closed``, ``m`` rows with the joints) and the largest
    penetration max(0, −g_N) [m] (−g_N − δ of a compliant contact: its effective gap),
    the bookkeeping one kernel over the contact table (:func:`._stage_kernels.closed_set`)."""
    fused, located = model.fused, data.located
    for j in range(data.n_live):
        i = data.live_idx[j]
        f = fused[i]
        located[i] = model.contacts[i].locate() if f is None else f.locate(data.q_m, data.u, data.t_m)
    data.n_closed, data.m, pen = K.closed_set(located, data.live_idx, data.n_live, model.contact_table,
                                              data.contact_f, data.warm, data.comp_force, data.comp_delta,
                                              data.closed, data.closed_idx, model.n_c)
    last = data.last
    if pen > last[1]:
        last[1] = pen
    if model.contacts and last[1] > data.stats["max_penetration"]:
        data.stats["max_penetration"] = last[1]


def constraints(model, data, dt):
    """Stage 5: single-valued contact forces into h; M̂ factored; u_free; the contact
    problem (W, M̂⁻¹W, G, ξ_free, γ⁻, closing) of the joints and closed contacts."""
    for i in model.single_valued:
        if data.live[i]:
            data.force_N[i] = model.contacts[i].add_forces(data.h) if data.closed[i] else 0.0
    factor = iteration_factor(model, data, dt)
    if model.penalty:
        check_penalty(model, data, factor, dt)
    if model.blocks is not None:
        K.free_velocity(factor, model.blocks, model.idle_rows, data.h, dt, data.u, data.u_free)
    else:
        BK.scaled_into(data.h, dt, data.u_free)
        solve(model, data, factor, data.u_free)
        np.add(data.u, data.u_free, out=data.u_free)
    m = data.m
    if m == 0:
        return
    nu, n_c = model.nu, model.n_c
    W, MW, G, lam, gamma_plus, xi_free, gamma_pre, closing, offset = data.problem(nu, m)
    W.fill(0.0)
    closing.fill(0.0)
    offset.fill(0.0)
    eq = model.equations
    if n_c:
        W[:, :n_c] = eq.constraint_jacobian(data.t_m, data.q_m).T
        offset[:n_c] = eq.constraint_velocity_term(data.t_m, data.q_m)
    K.contact_rows_into(W, closing, data.contact_f, model.contact_table, data.closed_idx, data.n_closed, n_c,
                        data.warm, dt)     # the closed contacts' columns; closing for those resting within closing_tol
    solve_matrix(model, data, factor, W, MW)
    K.contact_problem_into(W, MW, data.u_free, data.u, offset, closing, G, xi_free, gamma_pre)
    data.comp_r = 0
    if model.residual is not None and residual_contact.assemble(model, data, dt):
        r = data.comp_r
        compliant_problem(G, xi_free, gamma_pre, data.comp_rows[:r], data.compliance(r), data.comp_F[:r],
                          data.comp_d[:r], data.comp_dd[:r], data.comp_fresh[:r], dt, model.theta,
                          data.comp_lam0[:r])


def impulses(model, data, dt):
    """Stage 6: Λ of the contact problem (warm-started), the solver's counters, the
    impulses' work, the warm starts of the next step."""
    m = data.m
    if m == 0:
        if data.warm_joints:                 # a problem was solved last step (Data: warm ⊆ warm_joints)
            data.warm.fill(False)            # nothing closed: no warm start, no resting contact
            data.warm_joints = False
        return
    W, MW, G, lam, gamma_plus, xi_free, gamma_pre, closing, offset = data.problem(model.nu, m)
    warm_start(model, data, lam)
    work, newton = data.solver_scratch(m)
    it, residual, converged = model.solver.solve_into(contact_set(model, data), G, xi_free, gamma_pre, lam,
                                                      gamma_plus, work, newton)
    if not converged:
        raise StepFailure(f"contact problem not solved: residual {residual:.3g} m/s after "
                          f"{it} iterations ({data.n_closed} closed contacts)")
    keep_warm_start(model, data, lam)
    r = data.comp_r
    if r:
        compliant_update(lam, gamma_plus, gamma_pre, data.comp_rows[:r], data.comp_normal[:r], data.compliance(r),
                         data.comp_F[:r], data.comp_d[:r], data.comp_dd[:r], dt, model.theta, data.comp_lam0[:r])
        residual_contact.store(model, data)
    last = data.last
    data.stats["solver_iterations"] += it
    last[2] += it
    last[3] = max(last[3], residual)
    last[4] += K.impulse_work(lam, gamma_plus, closing, gamma_pre)


def velocity(model, data, dt):
    """Stage 7: u_{k+1} = u_free + M̂⁻¹ W Λ (u_k kept in ``u_prev``)."""
    m = data.m
    if m == 0:
        K.free_velocity_update(data.u, data.u_free, data.u_prev)
    else:
        data.u_prev[:] = data.u
        W, MW, G, lam = data.problem(model.nu, m)[:4]
        K.velocity_into(data.u_free, MW, lam, data.u)
    n_closed = data.n_closed
    if n_closed:
        data.stats["closed_contacts"] += n_closed
        if n_closed > data.last[0]:
            data.last[0] = n_closed


def position(model, data, dt):
    """Stage 8: q_{k+1} = q_m ⊕ Δt (θ u_{k+1} + (1 − 2θ) u_k), renormalized; t += Δt."""
    th = model.theta
    if th == 0.5:
        model.body_stage.advance(data.q_m, data.u, th * dt, data.du, data.q)
    else:
        BK.scaled_into(data.u, th * dt, data.du)
        BK.scaled_into(data.u_prev, (1.0 - 2.0 * th) * dt, data.work_u)
        data.du += data.work_u
        model.body_stage.increment(data.q_m, data.du, data.q)
        model.body_stage.normalize(data.q)
    data.t += dt
    data.h_last = dt


def step(model, data, dt):
    """One Moreau step: the eight stages in order."""
    midpoint(model, data, dt)
    bodies(model, data, dt)
    contours(model, data, dt)
    detect(model, data, dt)
    constraints(model, data, dt)
    impulses(model, data, dt)
    velocity(model, data, dt)
    position(model, data, dt)


# --- pieces of the stages -------------------------------------------------------------
def iteration_factor(model, data, dt):
    """The Cholesky factor of M̂ = M + θΔt D + θ²Δt² K at (t_m, q_m) on the active rows
    (Fortran order); for a constant M̂ the factor of this step size, computed once (steps
    landing on output times differ by rounding: within 1e-12 Δt they share it)."""
    if model.constant_iteration:
        if dt == data.factor_dt:             # the last step's size
            return data.factor_last
        for step_size, factor in data.factors:
            if abs(step_size - dt) <= 1e-12 * dt:
                data.factor_dt, data.factor_last = dt, factor
                return factor
        if len(data.factors) > 8:            # step-size control: keep the latest few
            data.factors.clear()
        data.M[...] = model.equations.mass_matrix(data.t_m, data.q_m)
        factor = _factor(model, data, dt, _factor_array(model))
        data.factors.append((dt, factor))
        data.factor_dt, data.factor_last = dt, factor
        return factor
    if data.factor is None:
        data.factor = _factor_array(model)
    return _factor(model, data, dt, data.factor)


def _factor_array(model):
    """Storage of a factor of M̂: (nu, nu) for the block factor, else (n_act, n_act)
    Fortran order (LAPACK)."""
    if model.blocks is not None:
        return np.zeros((model.nu, model.nu))
    return np.empty((model.n_act, model.n_act), order="F")


def _factor(model, data, dt, out):
    """Cholesky factor of M̂ (tangents at q_m) into ``out``, M̂ into ``data.D``: block by
    block over the active bodies, M̂ from the bodies' constant tangents in the same
    kernel (:func:`~mbs.run.linalg_kernels.block_iteration_factor`), when M̂ is block diagonal
    (``model.blocks``), else from the body stage's tangents and LAPACK's factor on the
    active rows."""
    th = model.theta
    K, D, M = data.K, data.D, data.M
    stage = model.body_stage
    if model.blocks is not None:            # block-diagonal tangents: M̂ and its factor in one kernel
        if stage.varying_body_tangents:
            stage.tangents(data.t_m, data.q_m, data.u, K, D)
            info = block_iteration_factor(M, K, D, th * dt, th * th * dt * dt, model.blocks, D, out)
        else:
            info = block_iteration_factor(M, stage.K0, stage.D0, th * dt, th * th * dt * dt, model.blocks, D, out)
        if info != 0:
            raise StepFailure(f"M + θΔt D + θΔt² K is not positive definite (pivot of row {info - 1})")
        return out
    stage.tangents(data.t_m, data.q_m, data.u, K, D)
    np.multiply(D, th * dt, out=D)
    np.add(M, D, out=D)
    np.multiply(K, th * th * dt * dt, out=K)
    np.add(D, K, out=D)                     # M̂ = M + θΔt D + θ²Δt² K
    if model.active_u is None:
        out[...] = D
    else:
        act = model.active_u
        out[...] = D[np.ix_(act, act)]
    factor, info = dpotrf(out, lower=True, overwrite_a=True)
    if info != 0:
        raise StepFailure(f"M + θΔt D + θΔt² K is not positive definite (LAPACK dpotrf info {info})")
    if factor is not out:
        out[...] = factor
    return out


def solve(model, data, factor, b):
    """b ← M̂⁻¹ b in place (nu,); on the active rows only when the plan left bodies out
    (zero on theirs: their blocks of M̂ are decoupled from the rest)."""
    if model.blocks is not None:
        block_cho_solve_vector(factor, model.blocks, model.idle_rows, b, b)
        return
    if model.active_u is None:
        dpotrs(factor, b, lower=True, overwrite_b=True)
        return
    act, x = model.active_u, data.rhs_act
    np.take(b, act, out=x)
    dpotrs(factor, x, lower=True, overwrite_b=True)
    b.fill(0.0)
    b[act] = x


def solve_matrix(model, data, factor, W, MW):
    """M̂⁻¹ W (nu, m) into MW (C order; LAPACK solves in a Fortran-order scratch)."""
    if model.blocks is not None:
        block_cho_solve_matrix(factor, model.blocks, model.idle_rows, W, MW)
        return
    if model.active_u is None:
        X = data.lapack_matrix(model.nu, W.shape[1])
        X[...] = W
        dpotrs(factor, X, lower=True, overwrite_b=True)
        MW[...] = X
        return
    act = model.active_u
    x = dpotrs(factor, W[act], lower=True)[0]
    MW.fill(0.0)
    MW[act] = x


def check_penalty(model, data, factor, dt):
    """Stop when a closed single-valued contact is too stiff for its explicit force:
    ω Δt = Δt √(k w_Nᵀ M̂⁻¹ w_N) > 2, k = −∂F_N/∂g_N at the contact point."""
    for i in model.penalty:
        c = model.contacts[i]
        if not (data.closed[i] and data.force_N[i] > 0.0 and data.live[i]):
            continue
        k = c.kinematics
        stiffness = -float(c.law.derivatives(k.g_N, k.gd_N)[0])
        w = k.W_N(data.w_N)
        data.rhs[:] = w
        solve(model, data, factor, data.rhs)
        s2 = stiffness * dt * dt * float(w @ data.rhs)
        if s2 > 4.0:
            raise StepFailure(f"penalty contact {c.name!r} too stiff for the step: ω Δt = {s2 ** 0.5:.3g} > 2 "
                              f"(k = {stiffness:.3g} N/m); take Δt < {2.0 * dt / s2 ** 0.5:.3g} s or a "
                              "set-valued law")


def contact_set(model, data):
    """The ContactSet of the joints and the closed contacts, built once per closed set."""
    key = tuple(data.closed_idx[:data.n_closed].tolist()) if data.n_closed != 1 else int(data.closed_idx[0])
    cs = data.contact_sets.get(key)
    if cs is None:
        laws = [Bilateral(model.n_c)] if model.n_c else []
        laws += [model.contacts[i].law for i in data.closed_idx[:data.n_closed]]
        cs = data.contact_sets[key] = ContactSet(laws)
    return cs


def warm_start(model, data, lam):
    """Λ of the last step for the joints and the contacts closed again, else zero
    (:func:`mbs.run._stage_kernels.warm_start_into`)."""
    n_c = model.n_c
    K.warm_start_into(model.contact_table, data.closed_idx, data.n_closed, data.warm, data.lam_prev, n_c, lam)
    if n_c and data.warm_joints:
        lam[:n_c] = data.lam_joints


def keep_warm_start(model, data, lam):
    """This step's Λ becomes the warm start of the next: the joints' and the closed
    contacts' (the others lose theirs; :func:`mbs.run._stage_kernels.keep_warm_start_into`)."""
    n_c = model.n_c
    if n_c:
        data.lam_joints[:] = lam[:n_c]
    data.warm_joints = True
    K.keep_warm_start_into(model.contact_table, data.closed_idx, data.n_closed, lam, n_c, data.warm, data.lam_prev)

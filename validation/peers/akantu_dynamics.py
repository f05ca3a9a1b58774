"""Akantu's explicit dynamics (central differences, lumped mass) as a peer code; optional.

:func:`explicit_dynamics` runs the full FE model of a tet4 / tet10 mesh through
Akantu's ``SolidMechanicsModel`` with ``_explicit_lumped_mass``: the reference the
report compares its modal solvers against (report Sec. 5.7 and 6, "Akantu"), and
ours likewise. Linear elastic, small strain: the displacement is a linear function
of the loads, large rotations produce spurious strains (Akantu's linear model,
as in the report).

Route
-----
:func:`validation.peers.akantu_fe.build_model` hands mesh and material to Akantu
(gmsh 2.2 file, material file, node matching by coordinates, mass checks) and
initializes the model for explicit dynamics; the step is
``time_step_factor * model.getStableTimeStep()``; the clamped nodes' three DOFs are
set in Akantu's blocked-DOF array; each step is one ``model.solveStep()``. The
displacement, velocity, acceleration, external-force and blocked-DOF arrays are
numpy views of Akantu's memory and are read and written in place.

The scheme (found with akantu 5.0.7, and checked by tests/integration/test_akantu_dynamics.py)
----------------------------------------------------------------------------------------------
Akantu's explicit solver is Newmark-β with β = 0, γ = 1/2 (central differences).
One ``solveStep`` from t_n to t_{n+1} = t_n + Δt does

    u_{n+1} = u_n + Δt v_n + Δt²/2 a_n                  (predictor)
    a_{n+1} = M⁻¹ (f_ext − f_int(u_{n+1}))              (with the f_ext set now)
    v_{n+1} = v_n + Δt/2 (a_n + a_{n+1})                (corrector)

on the free DOFs (blocked DOFs keep u = v = a = 0). So the external force set
before that call is the one of t_{n+1}: we set f(t_{n+1}) there, and the equation
of motion ``M a_n + K u_n = f(t_n)`` holds at every step time t_n = n Δt with the
load of that time. Akantu starts from a_0 = 0 (for which even a constant load is
integrated wrongly in the first step); we set the consistent ``a_0 = M⁻¹ f(0)``
(u_0 = 0) before the first step, so the scheme is exact for constant accelerations.

Loads
-----
A step table in the inertial frame: ``f(t) = 0`` for t < τ_0 and
``f(t) = F_j`` for τ_j ≤ t < τ_{j+1}. A load time within 1e-9 Δt of a step time
counts as reached at that step. With ``follower=True`` the table holds body-fixed
forces (the body frame is the inertial one at t = 0) and step n applies
``R_n F_j(t_n)`` to every node, where R_n is the best-fit rotation of the
configuration x_n = X + u_n (known before the step from the predictor):
the rotation factor of the polar decomposition of

    H = Σ_i m_i (x_i − c)(X_i − C)ᵀ = Σ_i m_i x_i (X_i − C)ᵀ

(Kabsch with the lumped masses m_i; c, C the current and initial centres of mass),
``R = U diag(1, 1, det(U Vᵀ)) Vᵀ`` from ``H = U S Vᵀ``.

Outputs and timing
------------------
States at ``output_times`` are interpolated linearly between the bracketing steps
(an output time within 1e-9 Δt of a step time gives that step exactly). ``cpu_s``
is the process CPU time of the whole call (mesh and model set-up included),
``loop_cpu_s`` that of the time-stepping loop only. Both are measured on the
process clock, so other threads of the process count too.

Cache
-----
With ``cache_dir`` the result is stored as ``akantu_dynamics_<sha256>.npz``, the
hash taken over every input array (dtype, shape, bytes), every scalar input, the
akantu version and this adapter's cache version; an identical call reloads it
(``cached=True``, timings those of the stored run). Files are written atomically.
"""

from __future__ import annotations

import hashlib
import os
import tempfile
import time
from pathlib import Path

import numpy as np

from validation.peers.akantu_fe import available, build_model, check_mesh

__all__ = ["available", "explicit_dynamics"]

_SNAP = 1.0e-9  # times within _SNAP * dt of a step time are that step time
_CACHE_VERSION = 1  # bump when the results of identical inputs change

_CHECK_EVERY = 64   # steps between finiteness checks (a NaN spreads; the check costs little)


def _check_inputs(points, tets, density, young, poisson, load_times, load_forces, t_end,
                  output_times, clamped_nodes, initial_velocity, time_step_factor):
    """Validated, normalized copies of the inputs of :func:`explicit_dynamics`."""
    points, tets = check_mesh(points, tets, density, young, poisson)
    n = len(points)
    load_times = np.ascontiguousarray(load_times, dtype=float)
    if load_times.ndim != 1 or len(load_times) == 0:
        raise ValueError(f"load_times must be a non-empty 1-D array, not shape {load_times.shape}")
    if not np.all(np.isfinite(load_times)):
        raise ValueError("load_times must be finite")
    if np.any(np.diff(load_times) <= 0):
        raise ValueError("load_times must be strictly increasing")
    load_forces = np.ascontiguousarray(load_forces, dtype=float)
    if load_forces.shape != (len(load_times), n, 3):
        raise ValueError(f"load_forces must have shape (n_t, N, 3) = {(len(load_times), n, 3)}, "
                         f"not {load_forces.shape}")
    if not np.all(np.isfinite(load_forces)):
        raise ValueError("load_forces must be finite")
    if not (np.isfinite(t_end) and t_end > 0):
        raise ValueError(f"t_end must be a positive time, not {t_end}")
    output_times = np.ascontiguousarray(output_times, dtype=float)
    if output_times.ndim != 1 or len(output_times) == 0:
        raise ValueError(f"output_times must be a non-empty 1-D array, "
                         f"not shape {output_times.shape}")
    if not np.all(np.isfinite(output_times)):
        raise ValueError("output_times must be finite")
    if np.any(np.diff(output_times) < 0):
        raise ValueError("output_times must be increasing")
    if output_times[0] < 0 or output_times[-1] > t_end:
        raise ValueError(f"output_times must lie within [0, t_end] = [0, {t_end}], "
                         f"got [{output_times[0]}, {output_times[-1]}]")
    if clamped_nodes is None:
        clamped = np.zeros(0, dtype=np.int64)
    else:
        clamped = np.asarray(clamped_nodes)
        if clamped.ndim != 1 or (len(clamped) and not np.issubdtype(clamped.dtype, np.integer)):
            raise ValueError("clamped_nodes must be a 1-D array of node indices")
        clamped = np.unique(clamped.astype(np.int64))
        if len(clamped) and (clamped[0] < 0 or clamped[-1] >= n):
            raise ValueError(f"clamped_nodes must be node indices in [0, {n})")
    if initial_velocity is None:
        velocity0 = np.zeros((n, 3))
    else:
        velocity0 = np.ascontiguousarray(initial_velocity, dtype=float)
        if velocity0.shape != (n, 3):
            raise ValueError(f"initial_velocity must have shape (N, 3) = {(n, 3)}, "
                             f"not {velocity0.shape}")
        if not np.all(np.isfinite(velocity0)):
            raise ValueError("initial_velocity must be finite")
        if np.any(velocity0[clamped] != 0):
            raise ValueError("initial_velocity must be zero on the clamped nodes")
    if not (np.isfinite(time_step_factor) and time_step_factor > 0):
        raise ValueError(f"time_step_factor must be positive, not {time_step_factor}")
    return (points, tets, load_times, load_forces, float(t_end), output_times, clamped,
            velocity0, float(time_step_factor))


def _cache_path(cache_dir, arrays, scalars):
    """``cache_dir / akantu_dynamics_<sha256>.npz`` for these inputs and this akantu."""
    import akantu

    digest = hashlib.sha256()
    digest.update(f"akantu_dynamics cache v{_CACHE_VERSION}; akantu "
                  f"{akantu.__version__}".encode())
    for name, array in arrays.items():
        array = np.ascontiguousarray(array)
        digest.update(f"|{name}:{array.dtype.str}:{array.shape}|".encode())
        digest.update(array.tobytes())
    for name, value in scalars.items():
        digest.update(f"|{name}={value!r}".encode())
    return Path(cache_dir) / f"akantu_dynamics_{digest.hexdigest()}.npz"


def _load_cached(path):
    """The result dict stored at ``path``, with ``cached=True``."""
    with np.load(path) as data:
        result = {key: data[key] for key in data.files}
    for key in ("dt", "cpu_s", "loop_cpu_s"):
        result[key] = float(result[key])
    result["n_steps"] = int(result["n_steps"])
    result["cached"] = True
    return result


def _store(path, result):
    """Write ``result`` (arrays and numbers) to ``path`` atomically."""
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=path.stem, suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as fh:
            np.savez(fh, **{k: v for k, v in result.items() if k != "cached"})
        os.replace(tmp, path)
    except BaseException:
        os.unlink(tmp)
        raise


def _step_index(times, dt):
    """Index of the first step time n dt ≥ each of ``times`` (snapped within _SNAP dt)."""
    return np.maximum(np.ceil(times / dt - _SNAP), 0).astype(np.int64)


def _best_fit_rotation(H):
    """Rotation factor of the polar decomposition of the 3x3 matrix ``H`` (Kabsch)."""
    U, _, Vt = np.linalg.svd(H)
    if np.linalg.det(U @ Vt) < 0:
        U[:, 2] = -U[:, 2]
    return U @ Vt


def explicit_dynamics(points, tets, density, young, poisson, *, load_times, load_forces,
                      t_end, output_times, clamped_nodes=None, initial_velocity=None,
                      follower=False, time_step_factor=0.8, cache_dir=None) -> dict:
    """Simulate a linear elastic tet mesh with Akantu's explicit central differences
    (lumped mass) under step loads; return all node displacements at ``output_times``.

    Solves ``M ü + K u = f(t)`` (M Akantu's lumped mass, K its linear elastic
    stiffness) from u(0) = 0, u̇(0) = ``initial_velocity``, with the scheme, load
    timing and follower rotation of the module docstring.

    Parameters
    ----------
    points : (N, 3) undeformed node coordinates [m].
    tets : (E, 4) tet4 or (E, 10) tet10 connectivity, 0-based, VTK/meshio node order
        (as :func:`validation.peers.akantu_fe.assemble`), positively oriented.
    density, young, poisson : ρ [kg/m³], E [Pa], ν [-] of the isotropic material.
    load_times : (n_t,) strictly increasing times τ_j [s] at which the load changes.
    load_forces : (n_t, N, 3) nodal forces [N]: F_j acts for τ_j ≤ t < τ_{j+1}, the last
        one holds, and no force acts before τ_0. Inertial frame, or body frame when
        ``follower``.
    t_end : end time [s] (> 0); the run takes ``n_steps`` steps, the first step time
        at or after t_end being the last.
    output_times : (n_out,) increasing times in [0, t_end] [s].
    clamped_nodes : node indices whose three DOFs are blocked (u = 0), or None.
    initial_velocity : (N, 3) node velocities at t = 0 [m/s] (zero on clamped nodes),
        or None for rest.
    follower : when True the forces are body-fixed and turn with the best-fit rotation
        of the current configuration.
    time_step_factor : the step is ``time_step_factor * model.getStableTimeStep()``;
        above 1 the scheme may be unstable.
    cache_dir : directory for the result cache (see the module docstring), or None.

    Returns
    -------
    dict with ``t`` (n_out,) [s]; ``displacement`` and ``velocity`` (n_out, N, 3) [m],
    [m/s] in the caller's node numbering; ``dt`` the step [s]; ``n_steps``; ``cpu_s``
    process CPU time of the call [s]; ``loop_cpu_s`` that of the time-stepping loop
    [s]; ``masses`` (N,) Akantu's lumped masses [kg]; ``cached`` True when reloaded
    from ``cache_dir``.

    Raises ImportError when akantu is not installed, ValueError on malformed input,
    RuntimeError when the displacement becomes non-finite (with time and step) or a
    consistency check on Akantu's model fails.
    """
    import akantu as aka

    cpu0 = time.process_time()
    (points, tets, load_times, load_forces, t_end, output_times, clamped, velocity0,
     time_step_factor) = _check_inputs(points, tets, density, young, poisson, load_times,
                                       load_forces, t_end, output_times, clamped_nodes,
                                       initial_velocity, time_step_factor)
    path = None
    if cache_dir is not None:
        path = _cache_path(
            cache_dir,
            {"points": points, "tets": tets, "load_times": load_times,
             "load_forces": load_forces, "output_times": output_times, "clamped": clamped,
             "initial_velocity": velocity0},
            {"density": float(density), "young": float(young), "poisson": float(poisson),
             "t_end": t_end, "follower": bool(follower), "time_step_factor": time_step_factor})
        if path.exists():
            return _load_cached(path)

    n = len(points)
    model, perm, masses = build_model(points, tets, density, young, poisson,
                                      aka._explicit_lumped_mass)
    dt = time_step_factor * model.getStableTimeStep()
    model.setTimeStep(dt)
    n_steps = int(_step_index(np.array([t_end]), dt)[0])

    # everything below in Akantu's node order: caller's node i is Akantu's perm[i]
    inv = np.empty(n, dtype=np.int64)
    inv[perm] = np.arange(n)
    table = np.ascontiguousarray(load_forces[:, inv])
    mass_aka = masses[inv]
    u = model.getDisplacement()
    v = model.getVelocity()
    a = model.getAcceleration()
    f = model.getExternalForce()
    blocked = model.getBlockedDOFs()
    blocked[perm[clamped], :] = True
    free = ~blocked
    v[...] = velocity0[inv]

    # load index per step: j(n) = last j with first_step[j] <= n (-1: no load yet)
    first_step = _step_index(load_times, dt)
    changes = {int(s): j for j, s in enumerate(first_step) if s <= n_steps}  # last j wins
    j0 = int(np.searchsorted(first_step, 0, side="right")) - 1
    if follower:
        X = points[inv]
        W = mass_aka[:, None] * (X - mass_aka @ X / mass_aka.sum())
        H0 = X.T @ W
        half_dt2 = 0.5 * dt * dt
        u_next = np.empty_like(table[0])
        work = np.empty_like(table[0])
    f[...] = table[j0] if j0 >= 0 else 0.0  # R_0 = identity
    a[...] = np.where(free, f / mass_aka[:, None], 0.0)  # consistent a_0 (u_0 = 0)

    # outputs: state (1 - w) S_k + w S_{k+1}, w = 0 when t_out is (within _SNAP) a step time
    steps_out = output_times / dt
    on_step = np.abs(steps_out - np.rint(steps_out)) <= _SNAP
    k_out = np.where(on_step, np.rint(steps_out), np.floor(steps_out)).astype(np.int64)
    w_out = np.where(on_step, 0.0, steps_out - k_out)
    n_out = len(output_times)
    disp = np.empty((n_out, n, 3))
    vel = np.empty((n_out, n, 3))
    u_prev = np.empty_like(disp[0])
    v_prev = np.empty_like(disp[0])
    k_out_list = [int(k) for k in k_out] + [-1]  # sentinel
    w_out_list = [float(w) for w in w_out]

    p = 0  # next output to record
    j = j0
    loop0 = time.process_time()
    for step in range(1, n_steps + 1):
        # before the step the state is S_{step-1}
        while k_out_list[p] == step - 1:
            if w_out_list[p] == 0.0:
                disp[p] = u
                vel[p] = v
                p += 1
            else:  # needs S_{step-1} and S_step
                np.copyto(u_prev, u)
                np.copyto(v_prev, v)
                break
        if step in changes:
            j = changes[step]
            if not follower:
                f[...] = table[j]
        if follower and j >= 0:  # before the first load time f stays 0
            np.multiply(v, dt, out=u_next)
            u_next += u
            np.multiply(a, half_dt2, out=work)
            u_next += work  # u at this step's end: Akantu's predictor
            R = _best_fit_rotation(H0 + u_next.T @ W)
            np.matmul(table[j], R.T, out=f)
        model.solveStep()
        if (step % _CHECK_EVERY == 0 or step == n_steps) and not np.isfinite(u.sum()):
            raise RuntimeError(f"the displacement became non-finite at t = {step * dt:.6g} s "
                               f"(step {step} of {n_steps}, checked every {_CHECK_EVERY}; dt = {dt:.6g} s); "
                               f"time_step_factor = {time_step_factor} may be too large")
        while k_out_list[p] == step - 1:  # interpolated outputs inside (t_{step-1}, t_step)
            w = w_out_list[p]
            np.multiply(u_prev, 1.0 - w, out=disp[p])
            disp[p] += w * u
            np.multiply(v_prev, 1.0 - w, out=vel[p])
            vel[p] += w * v
            p += 1
    while k_out_list[p] == n_steps:  # outputs at the last step time
        disp[p] = u
        vel[p] = v
        p += 1
    loop_cpu = time.process_time() - loop0
    del model, u, v, a, f, blocked  # the views die with the model
    if p != n_out:
        raise RuntimeError(f"recorded {p} of {n_out} outputs (adapter error)")

    result = {
        "t": output_times.copy(),
        "displacement": disp[:, perm],
        "velocity": vel[:, perm],
        "dt": float(dt),
        "n_steps": n_steps,
        "cpu_s": time.process_time() - cpu0,
        "loop_cpu_s": loop_cpu,
        "masses": masses,
        "cached": False,
    }
    if path is not None:
        _store(path, result)
    return result

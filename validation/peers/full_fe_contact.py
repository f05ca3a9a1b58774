"""Full finite-element reference of the point mass dropped on the clamped beam (issue 21).

The scene of :mod:`ffrmbs_app.scenes.point_mass_beam` (thesis Sec. 5.2) run on EVERY DOF
of a tet10 mesh — no modes — as an independent reference for the reduced FFR model:
beam 250 x 50 x 50 mm, ρ = 920 kg/m³, E = 50 MPa, ν = 0.3, clamped at x = 0; point mass
m_p = 0.5 kg at setup A (0.235, 0.052, 0.025) m or B (0.235, 0.052, 0.040) m with
v = (0, −0.2, 0) m/s, no gravity, hitting the top face y = 0.05 m at t ≈ 10 ms.

Model
-----
Mesh ``preprocess.geometry.box(LX, LY, LZ, None, order=2, divisions=(nx, ny, nz))``
(structured tet10, :data:`ELEMENT_SIZES`: 25 mm (10, 2, 2), 12.5 mm (20, 4, 4),
6.25 mm (40, 8, 8); nz even so that node 19 at (0.25, 0.05, 0.025) m is a node), K from
:func:`preprocess.fe.stiffness_matrix`, lumped M from :func:`preprocess.fe.lumped_masses`
(HRZ); the same mesh as ``default_beam_data(divisions=..., order=2)`` of the scene, so
ffrmbs's reduced body of it can be compared node for node. Linear elastic, small strain.

Time integration: central differences (leapfrog), lumped mass
-------------------------------------------------------------

    v_{n+1/2} = v_{n−1/2} + Δt a_n,   u_{n+1} = u_n + Δt v_{n+1/2},
    M a_n = −K u_n + W_n λ_n

for mesh and point mass alike (the point mass is a free particle but for λ), clamped DOFs
fixed. The critical step of the mesh is Δt_crit = 2 / ω_max, ω_max² the largest
eigenvalue of K_ff φ = ω² M_ff φ found by **scipy's eigsh** (Lanczos, ``which="LA"``) on
the symmetric M^-1/2 K_ff M^-1/2 (:func:`critical_step`); the step is
Δt ≤ ``safety`` · Δt_crit (default 0.9), shortened to divide the output interval
t_end / (n_out − 1) into whole steps, so the outputs are step states (no interpolation).
Outputs at a step n use v_n = v_{n−1/2} + Δt/2 a_n (= the mean of the two half-step
velocities).

Contact: penalty on the quadratic top face, semi-implicit
---------------------------------------------------------
The mass is projected on the deformed 6-node triangles of y = 0.05 (all flat at rest)
along their reference normal e_y (:func:`validation.peers._full_fe_kernels.project_on_faces`):
the face and (ξ, η) where the deformed face x_face(ξ, η) has the mass's x and z, and the
gap g = y_p − y_face(ξ, η). Not the closest point: where the mass sits on an element
edge (setup A, z = 25 mm, is a mesh line) the point load folds the faces into a valley
along it, where the closest point is ambiguous and jumps between the two faces; along
the fixed ray the face point is unique and continuous across edges (the face is C0).
The gap's exact gradient (ξ moves with x_p and the face nodes' x, z) is
∂g/∂x_p = m, ∂g/∂x_a = −N_a m, with m = (−∂y_face/∂x, 1, −∂y_face/∂z) the deformed
face's normal scaled to unit y-component, so the force below is the gradient of the
penalty potential ½ k max(0, −g)². (With e_y in place of m — the slope, ~1e-2, dropped —
the force is not a gradient: at 6.25 mm in setup B the energy then rose by 0.3 %,
whatever k and Δt; with m it falls by the contact losses only.)
The penalty force
λ = k max(0, −g) acts as λ m on the mass and −N_a(ξ, η) λ m on the face's 6 nodes
(consistent distribution), i.e. through the gap Jacobian W (W = m on the mass's DOFs,
−N_a m on node a's). An explicit λ_n = k max(0, −g_n) would limit the step to
Δt < 2/√(k w) with w = Wᵀ M⁻¹ W = |m|² (1/m_p + Σ_a N_a²/m_a) (HRZ corner masses of tet10 are
tiny: w ~ 10⁴–10⁶ 1/kg), far below the mesh's step for k = 1e8–1e10 N/m. Instead the
force of step n is that of the **end-of-step gap**:

    λ_n = k max(0, −g_{n+1}),   g_{n+1} ≈ g_n + Wᵀ (x_{n+1} − x_n) = g_n + Δt Wᵀ v_{n+1/2},

W frozen at step n. With the contact-free prediction
ṽ = v_{n−1/2} + Δt M⁻¹(−K u_n), v_{n+1/2} = ṽ + Δt M⁻¹ W λ_n, so

    g_{n+1} = g̃ + Δt² w λ_n,   g̃ = g_n + Δt Wᵀ ṽ,

and λ = k max(0, −g̃ − Δt² w λ) has one root (the right side falls as λ grows):

    λ_n = 0 if g̃ ≥ 0,   λ_n = −k g̃ / (1 + k Δt² w) if g̃ < 0.

- k Δt² w ≪ 1: the explicit penalty force of the predicted gap.
- k → ∞: λ_n → −g̃/(Δt² w), g_{n+1} = 0: the forward-increment Lagrange multiplier
  contact of Carpenter, Taylor & Katona (1991) — hard contact. So k is a regularization
  with a finite limit; the change from k to 10 k measures the distance to it.
- No step limit from k: for one mass m on a spring K (explicit) and the contact spring k
  (at n + 1), the step's characteristic equation (m/Δt² + k) z² + (K − 2m/Δt²) z + m/Δt²
  = 0 has complex roots with |z|² = (m/Δt²)/(m/Δt² + k) < 1 whenever the explicit part is
  stable (K Δt² ≤ 4m), for every k ≥ 0.
- Energy: k x_{n+1} = k (x_{n+1} + x_n)/2 + (k Δt/2) v_{n+1/2} — the energy-conserving
  trapezoidal spring plus a numerical damper c = k Δt/2 on the gap rate. In the hard
  limit an impact loses at most the relative kinetic energy of the mass and the face
  nodes under it, ½ ġ²/w (1/w ≈ the nodal masses, ~1e-4 kg against m_p = 0.5 kg); the
  energy history shows it.

Energy: central differences conserve exactly, for the linear elastic forces,

    E_n = ½ v_{n−1/2}ᵀ M v_{n+1/2} + ½ u_nᵀ K u_n

(E_{n+1} − E_n = ½ v_{n+1/2}ᵀ(M(v_{n+3/2} − v_{n−1/2}) + K(u_{n+1} + u_n)Δt) = 0), which
is what :class:`FullFEResult` reports (plus the point mass's ½ m_p v_{p,n−1/2}·v_{p,n+1/2}
and the penalty's ½ k max(0, −g_n)²): the mean velocity's ½ v_nᵀ M v_n exceeds its
kinetic part by Δt²/8 a_nᵀ M a_n, a large share of the energy of the mesh's highest modes
(ω Δt near 2) that an impact on a node excites. So E changes only by the contact's work:
the damper's loss above, and the work ½ λ_n Wᵀ(x_{n+1} − x_{n−1}) of the linearized
constraint, not exactly zero when W changes from step to step (the contact point moves
over the face's nodes, or crosses an element edge, where W kinks). Measured at
k = 1e9 N/m, E(0.1 s)/E(0) − 1 with the contact open: 25 mm −1.0 % setup A, −0.45 % B;
12.5 mm −0.17 % A, −0.08 % B (falling monotonically: impact losses, which shrink with the
nodal masses under the mass); 6.25 mm −0.006 % B, but +0.20 % A — there the mass sits on
an element edge (z = 25 mm) folded into a valley, and the constraint's work across the
kink is not yet understood: treat setup A at 6.25 mm with that caveat.

Outputs, cache, cost
--------------------
:func:`simulate` returns a :class:`FullFEResult` at ``n_out`` uniform samples on
[0, t_end]: t [s], mass y [m], mass v_y [m/s], node-19 u_y [m], the energy terms [J], and
per-step extremes (lowest mass y, node-19 peak |u_y|, most negative gap). Results are
cached as ``full_fe_contact-<sha256 of the JSON recipe>.npz``
(:mod:`validation.peers.result_cache`). The step loop is numba (:mod:`validation.peers._full_fe_kernels`:
CSR mat-vec, projection, contact). :func:`convergence` states the run's own convergence
in penalty (k vs 10 k) and step (Δt vs Δt/2). A tqdm bar (:mod:`ffrmbs_app.progress`)
shows long runs on a terminal.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as sla

from ffrmbs.errors import ModelError
from ffrmbs_app.progress import ProgressCallback
from ffrmbs_app.scenes import point_mass_beam as pmb
from validation.peers import _full_fe_kernels as kern
from validation.peers import result_cache

NAME = "full_fe_contact"
CACHE_VERSION = 3         # 3: ray along e_y, W the gap's gradient, the conserved energy
ELEMENT_SIZES = {0.025: (10, 2, 2), 0.0125: (20, 4, 4), 0.00625: (40, 8, 8)}   # [m] -> divisions
SAFETY = 0.9              # Δt ≤ SAFETY · Δt_crit
PENALTY_K = 1e9           # [N/m], deep in the hard-contact regime (convergence())
FACE_TOL = 1e-2           # projection tolerance outside a triangle, barycentric units
TOP_AXES = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0]])   # the top face's plane (z, x): its ray is e_y
T_END, N_OUT = 0.1, 1001  # [s], samples
IMPACT_SPEED = 0.2        # [m/s], the scale of the velocity errors


@dataclass(frozen=True)
class FullFEModel:
    """The fixed part of a run: mesh, K, lumped masses, the top face and node 19.

    ``points`` (N, 3) [m]; ``stiffness`` K (3N, 3N) CSR [N/m] (unconstrained);
    ``masses`` (N,) [kg]; ``inv_m3`` (3N,) [1/kg], 0 on the clamped DOFs (face x = 0);
    ``faces`` (T, 6) the quadratic triangles of the top face y = 0.05 m; ``node19`` the
    index of the node at (0.25, 0.05, 0.025) m; ``omega_max`` [rad/s] of
    :func:`critical_step`.
    """

    divisions: tuple
    points: np.ndarray
    stiffness: sp.csr_matrix
    masses: np.ndarray
    inv_m3: np.ndarray
    faces: np.ndarray
    node19: int
    omega_max: float

    @property
    def dt_crit(self) -> float:
        """The critical step 2 / ω_max [s] of central differences on the mesh."""
        return 2.0 / self.omega_max

    @property
    def free(self) -> np.ndarray:
        """Boolean mask (3N,) of the DOFs that move."""
        return self.inv_m3 > 0.0


def check_divisions(divisions) -> tuple:
    """``divisions`` as a tuple of three ints >= 1 with nz even (node 19 at z = 25 mm is
    then a node), else a ModelError."""
    try:
        d = tuple(int(n) for n in divisions)
        ok = len(d) == 3 and all(n >= 1 and n == m for n, m in zip(d, divisions))
    except (TypeError, ValueError):
        ok = False
    if not ok or d[2] % 2:
        raise ModelError(f"divisions must be three integers >= 1 with nz even (node 19 at z = 25 mm), "
                         f"not {divisions!r}")
    return d


def critical_step(stiffness, masses, free) -> float:
    """ω_max [rad/s]: the square root of the largest eigenvalue of K_ff φ = ω² M_ff φ
    (lumped M = diag(m3), ``free`` (3N,) the moving DOFs), by scipy's eigsh (Lanczos,
    largest algebraic) on the symmetric A = M_ff^-1/2 K_ff M_ff^-1/2, from a fixed start
    vector (deterministic)."""
    s = 1.0 / np.sqrt(np.repeat(masses, 3)[free])
    A = sp.diags(s) @ stiffness[free][:, free] @ sp.diags(s)
    v0 = np.random.default_rng(0).standard_normal(A.shape[0])
    lam = sla.eigsh(A, k=1, which="LA", v0=v0, tol=1e-8, return_eigenvectors=False)
    return float(math.sqrt(lam[0]))


def build_model(divisions=ELEMENT_SIZES[0.0125]) -> FullFEModel:
    """Mesh, K, masses and top face of the beam with ``divisions`` (nx, ny, nz), tet10;
    the last model built is kept (read-only arrays: do not modify them)."""
    return _build_model(check_divisions(divisions))


@lru_cache(maxsize=1)
def _build_model(divisions) -> FullFEModel:
    from preprocess import fe
    from preprocess.geometry import box
    from preprocess.modes import clamped_dofs

    mesh = box(pmb.LENGTH, pmb.HEIGHT, pmb.WIDTH, None, order=2, divisions=divisions)
    K = fe.stiffness_matrix(mesh, pmb.YOUNG, pmb.POISSON)
    masses = fe.lumped_masses(mesh, pmb.DENSITY)
    free = ~clamped_dofs(3 * mesh.n_nodes, mesh.group("x0"))
    inv_m3 = np.where(free, 1.0 / np.repeat(masses, 3), 0.0)
    triangles = mesh.surface_triangles()
    faces = triangles[np.isin(triangles, mesh.group("y1")).all(axis=1)]
    node19 = int(np.argmin(np.linalg.norm(mesh.points - np.array(pmb.NODE_19), axis=1)))
    return FullFEModel(divisions, mesh.points, K, masses, inv_m3, np.ascontiguousarray(faces, dtype=np.int64),
                       node19, critical_step(K, masses, free))


@dataclass
class FullFEResult:
    """A full-FE run at ``n_out`` samples ``t`` (n_out,) [s]: the mass's ``y`` [m] and
    ``vy`` [m/s] (v_n, the mean of the half-step velocities), node 19's displacement
    ``node19`` u_y [m], the energy terms [J] ``kinetic`` ½ v_{n−1/2}ᵀ M v_{n+1/2} (mesh and
    mass), ``elastic`` ½ u_nᵀ K u_n and ``penalty`` ½ k max(0, −g_n)² (their sum is
    conserved by central differences but for the contact's work: module docstring);
    per-step extremes ``min_y`` [m] (lowest
    mass position), ``node19_peak`` [m] (max |u_y| of node 19), ``min_gap`` [m] (most
    negative gap: the deepest penetration); ``dt`` [s], ``steps``, ``wall_s`` [s] of the
    stepping (for a cached result: of the run that made it), ``recipe`` (the cache key),
    ``cached``."""

    t: np.ndarray
    y: np.ndarray
    vy: np.ndarray
    node19: np.ndarray
    kinetic: np.ndarray
    elastic: np.ndarray
    penalty: np.ndarray
    min_y: float
    node19_peak: float
    min_gap: float
    dt: float
    steps: int
    wall_s: float
    recipe: dict = field(default_factory=dict)
    cached: bool = False

    ARRAYS = ("t", "y", "vy", "node19", "kinetic", "elastic", "penalty")
    SCALARS = ("min_y", "node19_peak", "min_gap", "dt", "steps", "wall_s")

    @property
    def energy(self) -> np.ndarray:
        """Total energy (n_out,) [J]: kinetic + elastic + penalty."""
        return self.kinetic + self.elastic + self.penalty

    @property
    def rebound_velocity(self) -> float:
        """The mass's v_y at t_end [m/s]."""
        return float(self.vy[-1])


def step_size(model: FullFEModel, t_end, n_out, dt=None, safety=SAFETY) -> tuple[float, int]:
    """(Δt [s], steps per output interval): the largest step ≤ ``dt`` (default
    ``safety`` · Δt_crit) dividing the output interval t_end / (n_out − 1) into whole
    steps. A ModelError when the requested step exceeds Δt_crit."""
    target = safety * model.dt_crit if dt is None else float(dt)
    if not (math.isfinite(target) and 0.0 < target <= model.dt_crit):
        raise ModelError(f"the time step must lie in (0, Δt_crit = {model.dt_crit:.4g} s], not {target!r}")
    interval = t_end / (n_out - 1)
    n_sub = max(1, math.ceil(interval / target * (1.0 - 1e-12)))
    return interval / n_sub, n_sub


def run(model: FullFEModel, position, velocity, k=PENALTY_K, t_end=T_END, n_out=N_OUT, dt=None,
        safety=SAFETY, u0=None, mass=pmb.MASS, desc="full FE") -> FullFEResult:
    """Integrate the mesh and the point mass (``position`` (3,) [m], ``velocity`` (3,)
    [m/s], ``mass`` [kg]) with penalty ``k`` [N/m] from rest (or the displacement ``u0``
    (3N,) [m], zero on clamped DOFs, at zero velocity) to ``t_end`` [s]; ``n_out``
    uniform samples; step of :func:`step_size`. Not cached (:func:`simulate` is).

    The start: a_0 from the state at t = 0 and v_{−1/2} = v_0 − Δt/2 a_0, so the first
    half-step velocity is v_0 + Δt/2 a_0 (central differences' starting step).
    """
    for name, value in (("penalty k", k), ("t_end", t_end), ("point mass", mass)):
        if not (math.isfinite(value) and value > 0):
            raise ModelError(f"{name} must be positive and finite, not {value!r}")
    if int(n_out) != n_out or n_out < 2:
        raise ModelError(f"n_out must be a whole number >= 2, not {n_out!r}")
    n_out = int(n_out)
    dt, n_sub = step_size(model, t_end, n_out, dt, safety)
    K = model.stiffness
    n_dof = K.shape[0]
    u = np.zeros(n_dof) if u0 is None else np.array(u0, dtype=float)
    if u.shape != (n_dof,) or np.any(u[~model.free] != 0.0):
        raise ModelError(f"u0 must be ({n_dof},) with zeros on the clamped DOFs")
    v, a, f = np.zeros(n_dof), np.zeros(n_dof), np.zeros(n_dof)
    xp, vp, ap = np.array(position, dtype=float), np.array(velocity, dtype=float), np.zeros(3)
    work = np.zeros(30)
    args = (dt, float(k), float(mass), K.indptr, K.indices, K.data, model.inv_m3, model.points, model.faces,
            TOP_AXES, FACE_TOL)
    gap = kern.forces(*args, u, v, xp, vp, f, a, ap, work)[1]
    v -= 0.5 * dt * a
    vp -= 0.5 * dt * ap
    node_dof = 3 * model.node19 + 1
    track = np.array([xp[1], abs(u[node_dof]), gap, gap])
    m3 = np.repeat(model.masses, 3)
    out = {name: np.zeros(n_out) for name in FullFEResult.ARRAYS}
    out["t"] = np.linspace(0.0, t_end, n_out)

    def sample(i):
        vpn = vp + 0.5 * dt * ap
        out["y"][i], out["vy"][i], out["node19"][i] = xp[1], vpn[1], u[node_dof]
        out["kinetic"][i] = 0.5 * (m3 @ (v * (v + dt * a)) + mass * vp @ (vp + dt * ap))
        out["elastic"][i] = 0.5 * u @ f
        out["penalty"][i] = 0.5 * k * max(0.0, -track[3]) ** 2

    sample(0)
    start = time.perf_counter()
    with ProgressCallback(t_end, desc) as progress:
        for i in range(1, n_out):
            kern.advance(n_sub, *args, u, v, a, xp, vp, ap, f, work, node_dof, track)
            sample(i)
            progress(out["t"][i])
    wall = time.perf_counter() - start
    return FullFEResult(**out, min_y=float(track[0]), node19_peak=float(track[1]), min_gap=float(track[2]),
                        dt=dt, steps=n_sub * (n_out - 1), wall_s=wall)


def recipe(setup="A", divisions=ELEMENT_SIZES[0.0125], k=PENALTY_K, t_end=T_END, n_out=N_OUT, dt=None,
           safety=SAFETY) -> dict:
    """The JSON-able cache key of :func:`simulate`: scene, mesh, material, contact and
    time-stepping parameters, and :data:`CACHE_VERSION`."""
    if setup not in pmb.SETUPS:
        raise ModelError(f"setup must be one of {sorted(pmb.SETUPS)}, not {setup!r}")
    return {"peer": NAME, "version": CACHE_VERSION, "size": [pmb.LENGTH, pmb.HEIGHT, pmb.WIDTH],
            "material": [pmb.DENSITY, pmb.YOUNG, pmb.POISSON], "clamp": "x0", "order": 2,
            "divisions": list(check_divisions(divisions)), "mass": pmb.MASS, "position": list(pmb.SETUPS[setup]),
            "velocity": list(pmb.VELOCITY), "k": float(k), "t_end": float(t_end), "n_out": int(n_out),
            "dt": None if dt is None else float(dt), "safety": float(safety), "face_tol": FACE_TOL}


def cache_path(key: dict) -> Path:
    """``cache_dir() / full_fe_contact-<first 16 hex of sha256(JSON key)>.npz``."""
    return result_cache.cache_path(NAME, key)


def _store(path: Path, result: FullFEResult) -> None:
    """Write ``result`` to ``path`` (:func:`validation.peers.result_cache.store`)."""
    result_cache.store(path, result.recipe, {**{n: getattr(result, n) for n in FullFEResult.ARRAYS},
                                             **{n: np.array(getattr(result, n)) for n in FullFEResult.SCALARS}})


def _load(path: Path, key: dict):
    """The cached result at ``path`` if it exists and holds ``key``, else None."""
    z = result_cache.load(path, key)
    if z is None:
        return None
    scalars = {n: z[n].item() for n in FullFEResult.SCALARS}
    return FullFEResult(**{n: z[n] for n in FullFEResult.ARRAYS}, **scalars, recipe=key, cached=True)


def simulate(setup="A", divisions=ELEMENT_SIZES[0.0125], k=PENALTY_K, t_end=T_END, n_out=N_OUT, dt=None,
             safety=SAFETY, cache=True) -> FullFEResult:
    """The full-FE run of setup ``"A"`` or ``"B"`` on the tet10 mesh ``divisions`` with
    penalty ``k`` [N/m] to ``t_end`` [s] (``n_out`` samples, step of :func:`step_size`),
    from the cache when ``cache`` and present, else run and stored."""
    key = recipe(setup, divisions, k, t_end, n_out, dt, safety)
    path = cache_path(key)
    if cache and (hit := _load(path, key)) is not None:
        return hit
    model = build_model(divisions)
    result = run(model, pmb.SETUPS[setup], pmb.VELOCITY, k, t_end, n_out, dt, safety,
                 desc=f"full FE {setup} {model.divisions}")
    result.recipe = key
    if cache:
        _store(path, result)
    return result


def figures(result: FullFEResult) -> dict:
    """The compared figures of a run: rebound v_y at t_end [m/s], lowest mass y [m],
    node-19 peak |u_y| [m]."""
    return {"rebound_vy": result.rebound_velocity, "min_y": result.min_y, "node19_peak": result.node19_peak}


def convergence(setup="A", divisions=ELEMENT_SIZES[0.0125], k=PENALTY_K, t_end=T_END, n_out=N_OUT,
                cache=True) -> dict:
    """The run's own convergence: the base run (k, Δt) against (10 k, Δt) and (k, Δt/2).

    Returns {"runs": {label: figures + dt, wall_s, energy drop}, "changes": {label:
    {"rebound_vy / 0.2 m/s": |Δ v_y(t_end)| / 0.2, "min_y [m]": |Δ min y|,
    "node19_peak rel": |Δ peak| / peak}}, "table": markdown}.
    """
    base = simulate(setup, divisions, k, t_end, n_out, cache=cache)
    runs = {f"k = {k:g}, Δt = {base.dt:.3g}": base,
            f"k = {10 * k:g}": simulate(setup, divisions, 10 * k, t_end, n_out, cache=cache),
            f"Δt = {base.dt / 2:.3g}": simulate(setup, divisions, k, t_end, n_out, dt=base.dt / 2, cache=cache)}
    ref = figures(base)
    out = {"runs": {}, "changes": {}}
    lines = [f"Full FE, setup {setup}, divisions {tuple(divisions)}, t_end = {t_end} s:", "",
             "| run | Δt [s] | wall [s] | v_y(t_end) [m/s] | min y [m] | node-19 peak [m] | energy lost |",
             "|---|---|---|---|---|---|---|"]
    for label, res in runs.items():
        fig = figures(res)
        lost = (res.energy[0] - res.energy[-1]) / res.energy[0]
        out["runs"][label] = {**fig, "dt": res.dt, "wall_s": res.wall_s, "energy_lost": lost}
        lines.append(f"| {label} | {res.dt:.3g} | {res.wall_s:.1f} | {fig['rebound_vy']:.5f} | "
                     f"{fig['min_y']:.6f} | {fig['node19_peak']:.4e} | {lost:.2e} |")
        if res is not base:
            out["changes"][label] = {
                "rebound_vy / 0.2 m/s": abs(fig["rebound_vy"] - ref["rebound_vy"]) / IMPACT_SPEED,
                "min_y [m]": abs(fig["min_y"] - ref["min_y"]),
                "node19_peak rel": abs(fig["node19_peak"] - ref["node19_peak"]) / ref["node19_peak"]}
    lines += ["", "| change against the base run | Δv_y(t_end) / 0.2 m/s | Δ min y [m] | Δ node-19 peak / peak |",
              "|---|---|---|---|"]
    for label, c in out["changes"].items():
        lines.append(f"| {label} | {c['rebound_vy / 0.2 m/s']:.2e} | {c['min_y [m]']:.2e} | "
                     f"{c['node19_peak rel']:.2e} |")
    out["table"] = "\n".join(lines)
    return out

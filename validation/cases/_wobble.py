"""The report's beam scenes shared by the ``wobble_*`` cases (report Sec. 5, Fig. 5–6, Sec. 6).

The 1 × 1 × 5 m steel beam (ρ = 8000 kg/m³, E = 200 GPa, ν = 0; report Table 1: the
gmsh box of element size 0.5, 579 nodes, 254 tet10), node A at the mesh origin, and
its four load cases as body-frame :class:`~mbs.modal.StepLoads`:

* shear: 500 N along y on the face z = 5, clamped at z = 0 (Fig. 6a);
* rotation: +F along y on z = 5 and −F on z = 0 (Fig. 6b, F = 100 N);
* complex: F1 on z = 5 and F2 on z = 0 along y, (−100, 100) N then (500, 300) N from
  0.5 s (Fig. 6c);
* case study: 100 N along +x and 10 N along +z, shared equally by the nodes of the face
  x = 0 with y > 0.3 and z > 4.1 (the report's boolean-mask force files), for 10 ms (Sec. 6).

Face loads are spread by area (:func:`preprocess.face_load`).
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from mbs.modal import StepLoads
from preprocess import box, build_body, face_load
from validation.cases.cantilever import MATERIAL, REPORT_MESH_SIZE

T_SWITCH = 0.5          # complex forcing switch time [s] (Fig. 6c)
IMPACT = 0.01           # case-study load duration [s] (Sec. 6)


@lru_cache(maxsize=8)
def beam(mesh_size=REPORT_MESH_SIZE, n_modes=10, clamp=None):
    """(mesh, BodyData) of the report's beam; free unless ``clamp`` names a face group."""
    mesh = box(1.0, 1.0, 5.0, mesh_size, order=2)
    return mesh, build_body(mesh, MATERIAL, n_modes, clamp=clamp)


def node_a(mesh) -> int:
    """Index of node A, the corner at the mesh origin (report Sec. 5)."""
    return int(np.argmin(np.linalg.norm(mesh.points, axis=1)))


def shear_loads(mesh, force=500.0) -> StepLoads:
    return StepLoads.from_nodal([0.0], face_load(mesh, mesh.group("z1"), [0.0, force, 0.0])[None])


def rotation_loads(mesh, force=100.0) -> StepLoads:
    f = face_load(mesh, mesh.group("z1"), [0.0, force, 0.0]) + face_load(mesh, mesh.group("z0"), [0.0, -force, 0.0])
    return StepLoads.from_nodal([0.0], f[None])


def complex_loads(mesh) -> StepLoads:
    top = face_load(mesh, mesh.group("z1"), [0.0, 1.0, 0.0])
    bottom = face_load(mesh, mesh.group("z0"), [0.0, 1.0, 0.0])
    return StepLoads.from_nodal([0.0, T_SWITCH], np.stack([-100.0 * top + 100.0 * bottom,
                                                         500.0 * top + 300.0 * bottom]))


def impact_nodes(mesh) -> np.ndarray:
    """Nodes of the face x = 0 with y > 0.3 and z > 4.1 (report Sec. 6)."""
    face = mesh.group("x0")
    p = mesh.points[face]
    return face[(p[:, 1] > 0.3) & (p[:, 2] > 4.1)]


def case_study_loads(mesh) -> StepLoads:
    nodes = impact_nodes(mesh)
    f = np.tile([100.0, 0.0, 10.0], (nodes.size, 1)) / nodes.size
    return StepLoads([0.0, IMPACT], nodes, np.stack([f, 0.0 * f]))


def warm_up():
    """Compile (or load from numba's cache) the solvers' kernels, so timings exclude it."""
    from mbs.modal import ModalBasis, SimpleRB

    mesh, data = beam(mesh_size=1.0, n_modes=2)
    basis = ModalBasis.from_body(data)
    for scheme in ("report", "rkmk4"):
        SimpleRB(basis, [rotation_loads(mesh)], dt=0.5, scheme=scheme).solve([0.0, 1.0])


def nodal_history(loads: StepLoads, n_nodes) -> tuple[np.ndarray, np.ndarray]:
    """(times, forces (n_t, N, 3)) of a load on all nodes, e.g. for an FE peer."""
    forces = np.zeros((loads.n_steps, n_nodes, 3))
    forces[:, loads.nodes] = loads.forces
    return loads.times, forces


def akantu_run(mesh, data, loads: StepLoads, t_out, follower):
    """Akantu's explicit FE run of the scene (see :mod:`validation.peers.akantu_dynamics`),
    loads as nodal step tables, outputs at ``t_out``; the peer's result dict."""
    from validation.peers import akantu_dynamics

    times, forces = nodal_history(loads, data.n_nodes)
    mat = data.material
    return akantu_dynamics.explicit_dynamics(
        mesh.points, mesh.tets, mat["density"], mat["young"], mat["poisson"], load_times=times,
        load_forces=forces, t_end=t_out[-1], output_times=t_out, follower=follower)


def akantu_reference(result, make_loads, t_out, follower, n_modes=30):
    """The free report beam with ``n_modes`` modes, its loads ``make_loads(mesh)`` and
    Akantu's run of the scene at ``t_out``: (mesh, data, loads, peer result dict). Without
    Akantu: None, with the skip noted in ``result``. Warms up our kernels first."""
    from validation.peers import akantu_dynamics

    if not akantu_dynamics.available():
        result.skipped.append("akantu: skipped: akantu not installed (pip install '.[peers]')")
        return None
    warm_up()
    mesh, data = beam(n_modes=n_modes)
    loads = make_loads(mesh)
    return mesh, data, loads, akantu_run(mesh, data, loads, t_out, follower)


def rms_error(u, u_ref) -> tuple[np.ndarray, float]:
    """RMS error over the nodes as a fraction of the reference's RMS displacement (report
    Fig. 17, 19): per output time (n_t,) and over the whole history (one number)."""
    diff = np.sum((u - u_ref) ** 2, axis=(1, 2))
    ref = np.sum(u_ref ** 2, axis=(1, 2))
    with np.errstate(invalid="ignore", divide="ignore"):
        per_time = np.sqrt(diff / ref)
    return per_time, float(np.sqrt(diff.sum() / ref.sum()))

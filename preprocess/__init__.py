"""Preprocessing: mesh -> FE model -> mode shapes -> body files (thesis Sec. 4.2, report Sec. 2).

Public surface::

    mesh = box(1, 1, 5, mesh_size=0.5)                 # or read_mesh("part.msh" | ".geo" | ".step" | ".inp")
    body = build_body(mesh, Material(8000, 200e9, 0.0), n_modes=10, clamp="z0")
    write_body("beam/", body)                          # u0.dat, modeShapeMatrix.dat, mij.dat,
    body = read_body("beam/body.h5")                   # stiffnessMatrix.dat and body.h5
"""

from preprocess.body import BodyData
from preprocess.bodyfiles import read_body, write_body
from preprocess.fe import consistent_mass_matrix, face_load, lumped_masses, stiffness_matrix
from preprocess.geometry import box, cylinder, grooved_block, spherical_cap, stepped_beam
from preprocess.mesh import Mesh
from preprocess.mesh_files import read_mesh
from preprocess.modes import clamped_modes, free_modes
from preprocess.pipeline import Material, build_body, mesh_source
from preprocess.statics import solve_static

__all__ = [
    "BodyData", "Material", "Mesh", "box", "build_body", "clamped_modes", "consistent_mass_matrix", "cylinder",
    "face_load",
    "free_modes", "grooved_block", "lumped_masses", "mesh_source", "read_body", "read_mesh",
    "solve_static", "spherical_cap", "stepped_beam", "stiffness_matrix", "write_body",
]

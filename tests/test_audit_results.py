"""Results that a new user and a fault audit can trust (issue 18, findings 1, 3, 11, 14, 19):
ParaView export of tet4 and tet10 bodies, the README's plot command on the default scene,
a full disk, kill -9 at any moment, units on every dataset.

Oracles: deformed positions computed here from the body data and the quaternion formula;
file bytes before and after; the errno's own text; the file read back with h5py.
"""

from __future__ import annotations

import errno
import os
import random
import signal
import subprocess
import sys
import time

import h5py
import meshio
import numpy as np
import pytest

from ffrmbs import cli
from ffrmbs.errors import FfrmbsError
from ffrmbs.export import export_paraview
from mbs import FlexibleBodyFFR, System
from mbs.result_file import ResultRecorder, load_result
from preprocess import Material, build_body
from preprocess.geometry import box

ENV = {**os.environ, "OPENBLAS_NUM_THREADS": "1"}


# --- finding 1: ParaView export of tet4 and tet10 bodies ------------------------------------------

def quaternion_matrix(p):
    """A of the unit quaternion p = (p0, p1, p2, p3), written out (Shabana's form)."""
    e0, e1, e2, e3 = p
    return np.array([[e0**2 + e1**2 - e2**2 - e3**2, 2 * (e1 * e2 - e0 * e3), 2 * (e1 * e3 + e0 * e2)],
                     [2 * (e1 * e2 + e0 * e3), e0**2 - e1**2 + e2**2 - e3**2, 2 * (e2 * e3 - e0 * e1)],
                     [2 * (e1 * e3 - e0 * e2), 2 * (e2 * e3 + e0 * e1), e0**2 - e1**2 - e2**2 + e3**2]])


@pytest.mark.parametrize("order, corners", [(1, 3), (2, 6)])
def test_export_writes_the_deformed_surface_of_tet4_and_tet10_bodies(tmp_path, order, corners):
    data = build_body(box(0.2, 0.04, 0.04, None, order=order, divisions=(4, 1, 1)),
                      Material(7800.0, 2e11, 0.3), n_modes=3)
    assert data.surface_triangles.shape[1] == corners
    system = System()
    body = system.add(FlexibleBodyFFR(data, name="box"))
    body.set_initial(v=(0.1, 0.0, 0.0), omega=(0.0, 0.0, 3.0), qdot_f=(40.0, -30.0, 20.0))
    path = tmp_path / "box.h5"
    system.simulate(0.02, 1e-3, integrator="generalized-alpha", t_out=np.linspace(0.0, 0.02, 5), plan=False,
                    recorder=ResultRecorder(path, {"scene": "box"}))
    pvd = export_paraview(path)

    res, _ = load_result(path)
    q = res.q                                     # the free frame's q: R (3), quaternion (4), q_f (3)
    phi = data.phi.reshape(data.n_nodes, 3, data.n_modes)
    for k in range(len(res.t)):
        mesh = meshio.read(pvd.parent / "box" / f"box_{k:06d}.vtu")
        kinds = {c.type: len(c.data) for c in mesh.cells}
        assert kinds == {("triangle" if order == 1 else "triangle6"): len(data.surface_triangles)}
        nodes = mesh.point_data["node"]
        R, A, q_f = q[k, :3], quaternion_matrix(q[k, 3:7]), q[k, 7:]
        expected = R + (data.u0[nodes] + phi[nodes] @ q_f) @ A.T
        assert np.allclose(mesh.points, expected, rtol=0, atol=1e-12)
        cells = mesh.cells[0].data                 # the body's own faces, node order kept
        assert set(map(tuple, nodes[cells])) == set(map(tuple, data.surface_triangles))
    assert np.abs(q[-1, 7:]).max() > 1e-6          # the body did deform

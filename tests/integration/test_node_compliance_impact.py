"""A face of point contacts that carry their nodes' residual flexibility
(contours.residual.NodeCompliance): a free steel rod (20 × 20 × 100 mm, tet4, 20 modes)
lands at v = 1 m/s on its end face on a rigid plane, a point contact with Newton's law
(e = 0) at each of the face's 25 nodes.

Oracle: the elastic bar on a rigid wall (Saint-Venant): one contact interval of 2L/c
(c = √(E/ρ), 38.7 µs) and no energy lost — the bar leaves with its energy in rigid motion
and vibration. With the points' compliance the face keeps one interval of that length
and the energy to 0.5 %; without it (the nodes rigid at the contact) the first instant
of contact stops the face's lumped masses plastically and the rod loses over 10 %.
"""

from __future__ import annotations

import numpy as np
import pytest

from contact import Contact, ContactKinematicsPointPlane, UnilateralNewtonImpact
from contours import PlaneContour, PointContour
from mbs import FlexibleBodyFFR, System, ground_frame
from preprocess import Material, build_body
from preprocess.geometry import box

E, RHO = 2.1e11, 7850.0
SIDE, LENGTH, V, MODES = 0.02, 0.1, 1.0, 20
T_END, DT = 6e-5, 5e-7                       # [s]
WAVE = 2.0 * LENGTH / np.sqrt(E / RHO)       # 2L/c [s]


@pytest.fixture(scope="module")
def rod_data():
    return build_body(box(SIDE, SIDE, LENGTH, None, order=1, divisions=(4, 4, 12)), Material(RHO, E, 0.3),
                      n_modes=MODES)


def landing(data, residual):
    """(energy at the end / at the start, the contact intervals [(on, off)] [s], the
    Result) of the rod landing 1 µm above the plane."""
    system = System()
    rod = FlexibleBodyFFR(data, modes=MODES, name="rod")
    rod.q_init[2], rod.u_init[2] = 1e-6, -V
    system.add(rod)
    plane = PlaneContour(ground_frame())
    for j in rod.node_group("z0"):
        point = PointContour(rod.node(int(j)), residual_flexibility=residual)
        system.add(Contact(ContactKinematicsPointPlane(point, plane), UnilateralNewtonImpact(0.0), name=f"node {j}"))
    res = system.simulate(T_END, DT, integrator="moreau", t_out=np.linspace(0.0, T_END, 121), energies=True,
                          trace=True)
    energy = res.energy["kinetic"] + res.energy["potential"]
    t, pressed = res.trace["t"], res.trace["pressed"] > 0
    edges = np.flatnonzero(np.diff(pressed.astype(int)))
    intervals = [(t[a + 1], t[b]) for a, b in zip(edges[::2], edges[1::2])]
    return energy[-1] / (0.5 * rod.mass * V ** 2), intervals, res


def test_a_face_of_compliant_points_keeps_one_interval_of_2l_over_c_and_the_energy(rod_data):
    kept, intervals, _ = landing(rod_data, residual=True)
    assert len(intervals) == 1, intervals
    (on, off), = intervals
    assert off - on == pytest.approx(WAVE, rel=0.1)
    assert kept == pytest.approx(1.0, abs=5e-3)
    rigid = landing(rod_data, residual=False)[0]
    assert rigid < 0.9


def test_the_node_blocks_kernel_is_the_pair_loop(rod_data, monkeypatch):
    """The face's landing with its compliance assembled by the one kernel over all pairs
    of sides at nodes (ResidualContacts.node_G) equals, bit for bit, the landing with the
    pair loop over ``between`` and ``add_contact_block`` (node_G switched off)."""
    from mbs.run import residual_contact

    kernel = landing(rod_data, residual=True)[2]
    monkeypatch.setattr(residual_contact, "_node_table", lambda compliances: (None, {}))
    loop = landing(rod_data, residual=True)[2]
    assert kernel.trace["pressed"].any()
    assert np.array_equal(kernel.q, loop.q) and np.array_equal(kernel.u, loop.u)

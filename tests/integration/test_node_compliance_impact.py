"""A face of point contacts that carry their nodes' residual flexibility
(contours.residual.NodeCompliance): a free steel rod (20 × 20 × 100 mm, tet4, 20 modes)
lands at v = 1 m/s on its end face on a rigid plane, a point contact with Newton's law
(e = 0) at each of the face's 25 nodes — set up by hand, and as one face contact
(``connect(face, plane, …)``, contact.face.FaceContact), which gives the same run.

Oracle: the elastic bar on a rigid wall (Saint-Venant): one contact interval of 2L/c
(c = √(E/ρ), 38.7 µs) and no energy lost — the bar leaves with its energy in rigid motion
and vibration. With the points' compliance the face keeps one interval of that length
and the energy to 0.5 %; without it (the nodes rigid at the contact) the first instant
of contact stops the face's lumped masses plastically and the rod loses over 10 %. The
face's recorded resultant integrates to the rod's change of momentum, and its mean over
the interval is the bar's ρ c A v (to 10 %: the 3D rod is no 1D bar).
"""

from __future__ import annotations

import numpy as np
import pytest

from contact import Contact, ContactKinematicsPointPlane, UnilateralNewtonImpact, connect
from contours import Contour2sNeutralFFR, PlaneContour, PointContour
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


def landing(data, residual, face=False):
    """(energy at the end / at the start, the contact intervals [(on, off)] [s], the
    Result) of the rod landing 1 µm above the plane; the points one face contact with
    ``face`` (then its resultant and the rod's momentum are recorded)."""
    system = System()
    rod = FlexibleBodyFFR(data, modes=MODES, name="rod")
    rod.q_init[2], rod.u_init[2] = 1e-6, -V
    system.add(rod)
    plane = PlaneContour(ground_frame())
    if face:
        face = system.add(connect(Contour2sNeutralFFR(rod, "z0", residual_flexibility=residual), plane,
                                  UnilateralNewtonImpact(0.0), name="end"))
    else:
        for j in rod.node_group("z0"):
            point = PointContour(rod.node(int(j)), f"end node {j}", residual_flexibility=residual)
            system.add(Contact(ContactKinematicsPointPlane(point, plane), UnilateralNewtonImpact(0.0), name=f"end node {j}"))
    res = system.simulate(T_END, DT, integrator="moreau", t_out=np.linspace(0.0, T_END, 121), energies=True,
                          trace=True, contacts=bool(face),
                          outputs={"p_z": lambda t, q, u: system.linear_momentum(t, q, u)[2]})
    res.face = face
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


def test_the_compliance_kernel_is_the_pair_loop(rod_data, monkeypatch):
    """The face's landing with its compliance assembled by the one kernel over all pairs of
    sides (ResidualContacts.table_G) equals, bit for bit, the landing with the pair loop
    over ``between`` and ``add_contact_block`` (residual_contact.table_blocks_reference)."""
    kernel = landing(rod_data, residual=True)[2]
    _with_the_pair_loop(monkeypatch)
    loop = landing(rod_data, residual=True)[2]
    assert kernel.trace["pressed"].any()
    assert np.array_equal(kernel.q, loop.q) and np.array_equal(kernel.u, loop.u)


def _with_the_pair_loop(monkeypatch):
    """The compliance assembled by the reference pair loop instead of the kernel."""
    from mbs.run import residual_contact

    def loop(rc, data, entries, n_e, C):
        residual_contact.table_blocks_reference(entries, n_e, C, data.comp_c, data.comp_work)
    monkeypatch.setattr(residual_contact, "_table_blocks", loop)


def test_the_compliance_kernel_on_a_corrected_surface_is_the_pair_loop(rod_data, monkeypatch):
    """The rod's corrected face landing on a corrected 2s face of a clamped plate (sides
    at nodes and on a neutral contour, in series): the kernel gives the loop's run bit
    for bit (the same weight blocks, the same sums)."""
    from contours.residual import NodeCompliance
    from mbs import PrescribedFrameMotion
    from mbs.run import residual_contact

    plate_data = build_body(box(0.06, 0.06, 0.01, None, order=1, divisions=(6, 6, 2)), Material(RHO, E, 0.3),
                            n_modes=10, clamp="x0")

    def run():
        system = System()
        plate = system.add(FlexibleBodyFFR(plate_data, modes=10, frame=PrescribedFrameMotion.fixed(), name="plate"))
        rod = FlexibleBodyFFR(rod_data, modes=MODES, name="rod")
        rod.q_init[:3], rod.u_init[2] = (0.02, 0.02, 0.01 + 1e-6), -V
        system.add(rod)
        face = system.add(connect(Contour2sNeutralFFR(rod, "z0", residual_flexibility=True),
                                  Contour2sNeutralFFR(plate, "z1", residual_flexibility=True),
                                  UnilateralNewtonImpact(0.0), name="end"))
        res = system.simulate(3e-5, DT, integrator="moreau", t_out=np.linspace(0.0, 3e-5, 61), trace=True)
        return res, face

    kernel, face = run()
    assert isinstance(face.points[0].kinematics.contour1, PointContour)
    assert any(isinstance(rc, NodeCompliance) for rc in residual_contact.ResidualContacts(
        face.points, [True] * len(face.points)).compliances.values())
    _with_the_pair_loop(monkeypatch)
    loop, _ = run()
    assert kernel.trace["pressed"].max() > 10
    assert np.array_equal(kernel.q, loop.q) and np.array_equal(kernel.u, loop.u)


def test_a_face_contact_is_its_points_and_records_its_resultant(rod_data):
    """connect(2s face, plane, …) on the rod's end face: the same run as the 25 points set
    up by hand, bit for bit; Σ F_z Δt over the samples (one per step) = Δp_z; the mean
    force over the contact interval ≈ ρ c A v; the tributary areas sum to the face's."""
    by_hand, (_, intervals, res) = landing(rod_data, True)[2], landing(rod_data, True, face=True)
    face = res.face
    assert len(face.points) == 25 and face.areas.sum() == pytest.approx(SIDE * SIDE, rel=1e-12)
    assert np.array_equal(res.q, by_hand.q) and np.array_equal(res.u, by_hand.u)
    force, moment = face.resultant(res)
    impulse = force[:, 2].sum() * DT
    assert impulse == pytest.approx(res["p_z"][-1] - res["p_z"][0], rel=1e-8)
    (on, off), = intervals
    assert impulse / (off - on + DT) == pytest.approx(RHO * np.sqrt(E / RHO) * SIDE * SIDE * V, rel=0.1)
    pressures = face.pressures(res)
    assert np.allclose((pressures * face.areas).sum(axis=1), force[:, 2], rtol=1e-12, atol=1e-9)

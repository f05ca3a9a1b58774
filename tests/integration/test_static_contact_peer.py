"""The full-FE static contact peer (validation.peers.static_contact) against closed forms:

* a block pressed on a rigid frictionless plane by a stroke δ of its top face is in
  uniaxial stress σ = E δ / H: the resultant E A δ / H and each contact force the
  consistent nodal force of that uniform pressure (preprocess.fe.face_load), tet4 and
  tet10, every gap closed;
* two blocks of other moduli on matching meshes, stacked on a roller and pressed: two
  springs in series, F = δ / (H₁/(E₁A) + H₂/(E₂A)); on non-matching meshes node to
  surface misses the series value (it fails the contact patch test) but keeps the
  equilibrium of the contact forces with both supports' reactions; the mortar pairing
  passes the patch test as its quadrature is refined, with either part as the slave:
  resultant and nodal forces converge to the uniform pressure's;
* a rigid flat punch pressed into the middle of a block's top face: the Signorini
  conditions hold (λ ≥ 0, g ≥ 0, λ·g = 0), the contact forces balance the support's
  reaction, the two halves carry alike and the pressure is highest at the punch's edges.
"""

from __future__ import annotations

import numpy as np
import pytest

from preprocess.fe import face_load
from preprocess.geometry import box
from validation.peers.static_contact import Pairing, Part, Plane, solve

E, NU = 2.0e9, 0.3           # [Pa], [-]
LX, LY, LZ = 0.04, 0.02, 0.03  # [m]
DELTA = 1e-5                 # [m]


def _roller(mesh, face, y=0.0):
    """The face's y fixed to ``y`` [m], and in-plane rigid motion removed by two pins at
    the corner nodes on the x axis of that face (x, z at the first, z at the other)."""
    nodes = mesh.group(face)
    p = mesh.points[nodes]
    first = nodes[np.argmin(np.linalg.norm(p - [0.0, p[0, 1], 0.0], axis=1))]
    other = nodes[np.argmin(np.linalg.norm(p - [p[:, 0].max(), p[0, 1], 0.0], axis=1))]
    return [(nodes, [1], y), ([first], [0, 2], 0.0), ([other], [2], 0.0)]


@pytest.mark.parametrize("order", [1, 2])
def test_a_block_pressed_on_a_rigid_plane_is_in_uniaxial_stress(order):
    mesh = box(LX, LY, LZ, None, order=order, divisions=(3, 2, 2))
    top = mesh.group("y1")
    p = mesh.points[top]
    first = top[np.argmin(np.linalg.norm(p - [0.0, LY, 0.0], axis=1))]
    other = top[np.argmin(np.linalg.norm(p - [LX, LY, 0.0], axis=1))]
    block = Part(mesh, E, NU, supports=[(top, [1], -DELTA), ([first], [0, 2], 0.0), ([other], [2], 0.0)])
    res = solve([block], [Pairing(0, mesh.group("y0"), Plane((0.0, 1.0, 0.0), 0.0))])
    force = E * LX * LZ * DELTA / LY
    assert res.unpaired == [0]
    assert res.resultant() == pytest.approx(force, rel=1e-10)
    expected = face_load(mesh, mesh.group("y0"), (0.0, force, 0.0))[res.nodes[0], 1]
    np.testing.assert_allclose(res.forces[0], expected, rtol=0.0, atol=1e-9 * force)
    np.testing.assert_allclose(res.gaps[0], 0.0, atol=1e-12 * DELTA)
    np.testing.assert_allclose(res.displacements[0][:, 1], -DELTA * mesh.points[:, 1] / LY, atol=1e-9 * DELTA)


def _stack(divisions_lower, divisions_upper, e_lower, e_upper, h_lower=LY, h_upper=LY, method="node-to-surface",
           subdivisions=8, slave="upper"):
    lower = box(LX, h_lower, LZ, None, order=1, divisions=divisions_lower)
    upper = box(LX, h_upper, LZ, None, order=1, divisions=divisions_upper)
    upper.points[:, 1] += h_lower
    top = upper.group("y1")
    p = upper.points[top]
    first = top[np.argmin(np.linalg.norm(p - [0.0, h_lower + h_upper, 0.0], axis=1))]
    other = top[np.argmin(np.linalg.norm(p - [LX, h_lower + h_upper, 0.0], axis=1))]
    parts = [Part(lower, e_lower, NU, supports=_roller(lower, "y0")),
             Part(upper, e_upper, NU, supports=[(top, [1], -DELTA), ([first], [0, 2], 0.0), ([other], [2], 0.0)])]
    pairing = Pairing(1, upper.group("y0"), (0, lower.group("y1")), method, subdivisions) if slave == "upper" else \
        Pairing(0, lower.group("y1"), (1, upper.group("y0")), method, subdivisions)
    return parts, solve(parts, [pairing])


def test_two_blocks_on_matching_meshes_are_two_springs_in_series():
    h_lower, h_upper, e_lower, e_upper = 0.015, 0.025, 3.0e9, 1.0e9
    parts, res = _stack((3, 2, 2), (3, 3, 2), e_lower, e_upper, h_lower, h_upper)
    area = LX * LZ
    series = DELTA / (h_lower / (e_lower * area) + h_upper / (e_upper * area))
    assert res.resultant() == pytest.approx(series, rel=1e-10)
    np.testing.assert_allclose(res.gaps[0], 0.0, atol=1e-12 * DELTA)


def test_node_to_surface_on_non_matching_meshes_keeps_equilibrium_not_the_patch_test():
    parts, res = _stack((3, 2, 2), (4, 2, 5), 2.0e9, 2.0e9)
    series = DELTA / (2 * LY / (2.0e9 * LX * LZ))
    lower_reaction = res.reactions[0][:, 1].sum()
    upper_reaction = res.reactions[1][:, 1].sum()
    assert res.resultant() == pytest.approx(lower_reaction, rel=1e-9)
    assert -upper_reaction == pytest.approx(res.resultant(), rel=1e-9)
    assert res.unpaired == [0] and (res.forces[0] >= 0.0).all()
    error = abs(res.resultant() / series - 1.0)
    assert 1e-6 < error < 0.05, error       # off the series value, but by little


@pytest.mark.parametrize("slave", ["upper", "lower"])
def test_the_mortar_pairing_passes_the_patch_test_as_its_quadrature_is_refined(slave):
    """Non-matching meshes (3 × 2 and 4 × 5 elements on the interface), one modulus: the
    uniform pressure F/A with F = δ E A / (2H). Node to surface misses F by 0.2 % (the
    finer mesh as slave) or 9 % (the coarser); the mortar resultant's error falls below
    1e-6 with 16 × 16 sub-triangles per triangle (from 2e-6 and 7e-5 with 4 × 4), its
    nodal forces' below 1e-3 of the largest (from 5e-3 and 3e-3)."""
    force = DELTA / (2 * LY / (E * LX * LZ))
    mesh = (lambda parts: parts[1 if slave == "upper" else 0].mesh)(_stack((3, 2, 2), (4, 2, 5), E, E)[0])
    group = mesh.group("y0" if slave == "upper" else "y1")
    errors = []
    for m in (4, 8, 16):
        _, res = _stack((3, 2, 2), (4, 2, 5), E, E, method="mortar", subdivisions=m, slave=slave)
        uniform = face_load(mesh, group, (0.0, force, 0.0))[res.nodes[0], 1]
        errors.append((abs(res.resultant() / force - 1.0), np.abs(res.forces[0] - uniform).max() / uniform.max()))
        assert (res.forces[0] >= 0.0).all() and np.abs(res.gaps[0]).max() < 1e-6 * DELTA
    (r4, f4), (r8, f8), (r16, f16) = errors
    assert r16 < 1e-6 and r16 < r8 < r4 and r16 < r4 / 50, errors
    assert f16 < 1e-3 and f16 < f4 / 4, errors
    _, nts = _stack((3, 2, 2), (4, 2, 5), E, E, slave=slave)
    assert abs(nts.resultant() / force - 1.0) > 1e-3


def test_a_rigid_flat_punch_meets_the_signorini_conditions():
    mesh = box(LX, LY, LZ, None, order=1, divisions=(8, 3, 6))
    block = Part(mesh, E, NU, supports=_roller(mesh, "y0"))
    top = mesh.group("y1")
    x = mesh.points[top]
    under = top[(np.abs(x[:, 0] - 0.5 * LX) <= 0.25 * LX + 1e-12) & (np.abs(x[:, 2] - 0.5 * LZ) <= LZ)]
    punch = Plane((0.0, -1.0, 0.0), -(LY - DELTA))          # the punch face y = LY − δ, below it the block
    res = solve([block], [Pairing(0, under, punch)])
    lam, g = res.forces[0], res.gaps[0]
    assert (lam >= 0.0).all() and (g >= -1e-12 * DELTA).all()
    assert np.abs(lam * g).max() <= 1e-9 * DELTA * lam.max()
    assert res.resultant() == pytest.approx(res.reactions[0][:, 1].sum(), rel=1e-9)
    xs = mesh.points[res.nodes[0]]
    left = xs[:, 0] < 0.5 * LX - 1e-12
    right = xs[:, 0] > 0.5 * LX + 1e-12
    assert lam[left].sum() == pytest.approx(lam[right].sum(), rel=0.02)    # the tets' diagonals are not mirrored
    interior = ~np.isclose(xs[:, 2], 0.0) & ~np.isclose(xs[:, 2], LZ)
    edge = np.isclose(np.abs(xs[:, 0] - 0.5 * LX), 0.25 * LX) & interior
    inner = np.isclose(xs[:, 0], 0.5 * LX) & interior
    assert lam[edge].mean() > 1.5 * lam[inner].mean()

"""Akantu's own assembly (optional peer, validation/peers/akantu_fe.py) against ours.

Skipped when akantu is not installed: it is an optional reference code.
"""

import numpy as np
import pytest

from preprocess import fe

RHO, E, NU = 8000.0, 200e9, 0.3


def test_akantu_stiffness_and_masses_match_ours(small_box_tet4, small_box_tet10):
    pytest.importorskip("akantu")
    from validation.peers import akantu_fe

    assert akantu_fe.available()
    for mesh in (small_box_tet4, small_box_tet10):
        K_aka, m_aka = akantu_fe.assemble(mesh.points, mesh.tets, RHO, E, NU)
        K_our, m_our = fe.stiffness_matrix(mesh, E, NU), fe.lumped_masses(mesh, RHO)
        assert K_aka.shape == K_our.shape == (3 * mesh.n_nodes,) * 2
        rel = abs(K_aka - K_our).max() / abs(K_our).max()
        assert rel < 1e-10, f"tet{mesh.tets.shape[1]}: K differs by {rel:.3e} (relative max)"

        volumes = mesh.element_volumes()  # straight-sided boxes: exact
        total = RHO * volumes.sum()
        np.testing.assert_allclose(m_aka.sum(), total, rtol=1e-12)
        np.testing.assert_allclose(m_our.sum(), total, rtol=1e-12)
        if mesh.order == 1:
            # row-sum lumping: ρV_e/4 to each corner, in both codes
            expected = np.zeros(mesh.n_nodes)
            np.add.at(expected, mesh.tets, np.repeat(RHO * volumes[:, None] / 4, 4, axis=1))
            np.testing.assert_allclose(m_aka, expected, rtol=1e-12, atol=0)
            np.testing.assert_allclose(m_our, expected, rtol=1e-12, atol=0)
        else:
            # the lumpings differ on purpose: corners get 1/8 of the mass in Akantu,
            # 1/9 in our HRZ scaling (mid-edge nodes 7/8 and 8/9)
            corner = np.unique(mesh.tets[:, :4])
            mid = np.setdiff1d(np.arange(mesh.n_nodes), corner)
            ratio_aka = m_aka[corner].sum() / m_aka[mid].sum()
            ratio_our = m_our[corner].sum() / m_our[mid].sum()
            np.testing.assert_allclose([ratio_aka, ratio_our], [1 / 7, 1 / 8], rtol=1e-12)

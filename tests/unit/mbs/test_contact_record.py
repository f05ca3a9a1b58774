"""The contact recorder (mbs.results.contact_record) samples an open contact at the sample's
state: for the pair kinds with a fused detection in the probe's own arrays
(mbs.run.fused_detection.Probe). Oracles: the default scene's gap before the impact, while
the beam is still at rest and undeformed, is the falling point's height over the top face,
g(t) = 2 mm − 0.2 m/s · t; and the Python path (contours updated, the search run, the run
state put back) records the same to rounding and leaves the same trajectory."""

import numpy as np
import pytest

from centre_scenes import PAIRS, centre_scene
from mbs.results import contact_record
from mbs.run.fused_detection import _FusedCentre

T_END, N_OUT = 0.012, 25            # [s]: the impact is at 10 ms; samples every 0.5 ms
GAP0, SPEED = 0.002, 0.2            # [m], [m/s]: setup A's point, 2 mm above the top face


def _run(side, contour):
    scene = centre_scene("impact", side, contour)
    system = scene.system
    q0, u0 = system.initial_state()
    q0[scene.mass.q_slice][1] += scene.contact.kinematics.radius      # a sphere: the same gap
    return scene, system.simulate(T_END, 1e-5, integrator="moreau", t_out=np.linspace(0.0, T_END, N_OUT),
                                  q0=q0, u0=u0, contacts=True)


@pytest.mark.parametrize("side, contour", PAIRS)
def test_the_open_gap_is_the_falling_height_sampled_by_the_probe(monkeypatch, side, contour):
    python_path = []
    locate = contact_record.ContactRecorder.locate
    monkeypatch.setattr(contact_record.ContactRecorder, "locate",
                        lambda self, *a: python_path.append(a[0]) or locate(self, *a))
    scene, res = _run(side, contour)
    rec = res.contacts[scene.contact.name]
    before = res.t < 0.0095
    np.testing.assert_allclose(rec["gap"][before], GAP0 - SPEED * res.t[before], rtol=0, atol=1e-12)
    np.testing.assert_allclose(rec["normal"][before], np.tile([0.0, 1.0, 0.0], (before.sum(), 1)), atol=1e-12)
    assert rec["active"][~before].any()                     # the impact happened
    assert len(python_path) <= 1                            # only the sample before the first step


@pytest.mark.parametrize("side, contour", [("point", "2s"), ("sphere", "band"), ("point", "1s")])
def test_the_probe_records_what_the_python_path_records(monkeypatch, side, contour):
    scene, res = _run(side, contour)
    monkeypatch.setattr(_FusedCentre, "probe", lambda self: None)
    _, ref = _run(side, contour)
    np.testing.assert_array_equal(res.q, ref.q)
    np.testing.assert_array_equal(res.u, ref.u)
    for field, values in ref.contacts[scene.contact.name].items():
        np.testing.assert_allclose(res.contacts[scene.contact.name][field], values, rtol=1e-12, atol=1e-15,
                                   err_msg=field)


@pytest.mark.parametrize("side, contour", [("point", "2s"), ("sphere", "edge")])
def test_a_contact_the_run_never_locates_is_sampled_by_the_seeded_probe(monkeypatch, side, contour):
    """The point (the sphere) 0.1 m above the top face, rising at 0.2 m/s: the planned run
    prunes the contact at every step, so the run has no contact point; the first sample
    takes the Python path, which seeds the probe, and the probe samples every other one:
    the gap is the height, 0.1 m + 0.2 m/s · t."""
    python_path = []
    locate = contact_record.ContactRecorder.locate
    monkeypatch.setattr(contact_record.ContactRecorder, "locate",
                        lambda self, *a: python_path.append(a[0]) or locate(self, *a))
    scene = centre_scene("impact", side, contour)
    system = scene.system
    q0, u0 = system.initial_state()
    q0[scene.mass.q_slice][1] += 0.1 - GAP0 + scene.contact.kinematics.radius
    u0[scene.mass.u_slice] = (0.0, SPEED, 0.0)
    res = system.simulate(T_END, 1e-5, integrator="moreau", t_out=np.linspace(0.0, T_END, N_OUT), q0=q0, u0=u0,
                          contacts=True)
    assert np.isnan(scene.contact.kinematics.start).all()          # the run never located it
    np.testing.assert_allclose(res.contacts[scene.contact.name]["gap"], 0.1 + SPEED * res.t, rtol=0, atol=1e-12)
    assert len(python_path) == 1

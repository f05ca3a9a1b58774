"""The registries of kinds (ffrmbs.registry): lookup errors, registration, the library's
registries checked against the classes they name, contact.connect choosing the
kinematics from the contour kinds, and a toy contact law added by one class and one
registry line, used from the Python API and from a scene file."""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np
import pytest

import contact
import mbs
from contact import LAWS, PAIR_KINEMATICS, BILATERAL_KINEMATICS, SOLVERS, Contact, ProxSolver, connect
from contact.search import Contact1sSearch, Contact2sSearch
from contours import (CONTOURS, Contour1sNeutralFactory, Contour2sNeutralFactory, Contour2sNeutralRigid, PlaneContour,
                      PointContour, SphereContour)
from ffrmbs.errors import InputFileError, ModelError
from ffrmbs.registry import Registry
from ffrmbs_app.scene_file import read_scene
from mbs import BODIES, INTEGRATORS, JOINTS, LOADS, ROTATIONS, PointMass, RigidBody, System, ground_frame
from qa.fixtures import fixture_text


# --- the Registry ------------------------------------------------------------------------------------

class A:
    pass


class B(A):
    pass


def test_lookup_error_names_the_kind_and_lists_the_known_names():
    r = Registry("widget")
    r.register("a", A)
    r.register(("x", "y"), B)
    assert r["a"] is A and r.lookup(("x", "y")) is B
    with pytest.raises(ModelError, match=r"^unknown widget 'b'; choose one of 'a', 'x'/'y'$"):
        r["b"]
    with pytest.raises(ModelError, match=r"^unknown widget 'y'/'x'; choose one of"):
        r[("y", "x")]
    with pytest.raises(ModelError, match=r"^unknown widget \['a'\]; choose one of"):
        r[["a"]]                                        # unhashable: a clear error, not a TypeError
    assert ["a"] not in r and "a" in r and ("x", "y") in r


def test_register_as_decorator_refuses_a_second_registration_and_unregisters():
    r = Registry("widget")

    @r.register("b")
    class C:
        pass

    assert r["b"] is C and r.names() == ("b",) and len(r) == 1 and list(r) == ["b"]
    with pytest.raises(ModelError, match="widget 'b' is already registered"):
        r.register("b", A)
    r.unregister("b")
    assert "b" not in r
    with pytest.raises(ModelError, match="unknown widget 'b'"):
        r.unregister("b")


def test_name_of_walks_the_class_hierarchy():
    r = Registry("widget")
    r.register("a", A)
    assert r.name_of(A()) == "a" and r.name_of(B) == "a"        # B is an A
    r.register("b", B)
    assert r.name_of(B()) == "b" and r.name_of(int) is None


# --- the library's registries -------------------------------------------------------------------------

def test_library_registries_name_the_classes_of_the_api():
    assert BODIES["flexible"] is mbs.FlexibleBodyFFR and BODIES["rigid"] is RigidBody
    assert BODIES["point_mass"] is PointMass
    assert [LOADS[k] for k in LOADS] == [mbs.Force, mbs.Torque, mbs.DistributedForce, mbs.NodalForces]
    assert set(INTEGRATORS.names()) == {"moreau", "moreau-adaptive", "generalized-alpha", "rk4"}
    assert set(ROTATIONS.names()) == {"quaternion", "cardan"}
    assert set(JOINTS.names()) == {"fixed", "spherical", "revolute", "prismatic"}
    assert [LAWS[k] for k in ("impact", "coulomb", "penalty", "bilateral")] == [
        contact.UnilateralNewtonImpact, contact.UnilateralCoulombContact,
        contact.LinearRegularizedUnilateralConstraint, contact.Bilateral]
    solver = SOLVERS["jacobi"](tol=1e-8)
    assert isinstance(solver, ProxSolver) and (solver.method, solver.tol) == ("jacobi", 1e-8)


def test_the_api_looks_kind_names_up_in_the_registries():
    with pytest.raises(ModelError, match="unknown joint kind 'hinge'; choose one of 'fixed', 'spherical'"):
        mbs.Joint(ground_frame((0.0, 0.0, 0.0)), PointMass(1.0).point, "hinge")
    with pytest.raises(ModelError, match="unknown integrator 'euler'; choose one of 'moreau'"):
        system = System()
        system.add(PointMass(1.0))
        system.simulate(0.1, 0.01, integrator="euler")
    with pytest.raises(ModelError, match="unknown rotation parametrization 'euler'"):
        RigidBody(1.0, np.eye(3), rotation="euler")
    with pytest.raises(ModelError, match="unknown contact law 'glue'; choose one of 'impact'"):
        connect(PointContour(PointMass(1.0).point), PlaneContour(ground_frame((0.0, 0.0, 0.0))), "glue")


@pytest.mark.parametrize("pair", PAIR_KINEMATICS.names(), ids="/".join)
def test_each_registered_pair_kinematics_takes_its_contour_kinds(pair):
    """The kinematics class of a pair accepts the registered contour classes: its point
    side (``side1``) is contour 1's class, and its search (for a searching kinematics)
    has the dimension of contour 2's class (a 2s or 1s contour), the class's own
    declarations — not the registry's."""
    kinematics = PAIR_KINEMATICS[pair]
    contour1, contour2 = CONTOURS[pair[0]], CONTOURS[pair[1]]
    assert kinematics.side1 is contour1
    search = getattr(kinematics, "search_class", None)
    if search is not None:
        dim = (2 if issubclass(contour2, Contour2sNeutralFactory) else 1 if issubclass(contour2, Contour1sNeutralFactory)
               else contour2.dim)                       # a neutral contour's dim is its space's
        assert dim == {Contact2sSearch: 2, Contact1sSearch: 1}[search]
    elif pair[1] == "plane":
        assert contour2 is PlaneContour
    else:
        assert contour2 is SphereContour


def test_bilateral_pairs_keep_a_point_on_a_curve():
    for pair in BILATERAL_KINEMATICS:
        assert pair[0] == "point" and issubclass(CONTOURS[pair[1]], Contour1sNeutralFactory)
        assert BILATERAL_KINEMATICS[pair] is contact.PointOnCurveConstraint


def test_connect_picks_the_kinematics_of_the_contour_kinds():
    ball = RigidBody(1.0, 0.01 * np.eye(3), name="ball").set_initial(R=(0.0, 0.0, 0.2))
    bob = PointMass(0.5, position=(0.0, 0.0, 0.5), name="bob")
    floor = PlaneContour(ground_frame((0.0, 0.0, 0.0)))
    c = connect(SphereContour(ball.origin, 0.1), floor, "impact", name="ball")
    assert type(c) is Contact and type(c.kinematics) is contact.ContactKinematicsSpherePlane
    assert c.law == contact.UnilateralNewtonImpact() and c.name == "ball"
    c = connect(PointContour(bob.point), SphereContour(ball.origin, 0.1), contact.UnilateralNewtonImpact(0.5))
    assert type(c.kinematics) is contact.ContactKinematicsPointSphere and c.law.e == 0.5
    grid = np.stack(np.meshgrid(np.linspace(-1, 1, 4), np.linspace(-1, 1, 4), indexing="ij"), axis=-1)
    surface = Contour2sNeutralRigid(ball, np.concatenate((grid, np.zeros((4, 4, 1))), axis=-1), outward=1)
    c = connect(PointContour(bob.point), surface, "impact")
    assert type(c.kinematics) is contact.ContactKinematicsPointContour2s
    with pytest.raises(ModelError, match="unknown contour pair 'plane'/'point'"):
        connect(floor, PointContour(bob.point), "impact")
    with pytest.raises(ModelError, match="unknown bilateral contour pair 'point'/'plane'"):
        connect(PointContour(bob.point), floor, "bilateral")
    with pytest.raises(ModelError, match=r"contact law 'coulomb' \(UnilateralCoulombContact\): .*'mu'"):
        connect(PointContour(bob.point), floor, "coulomb")


# --- a new law: one class and one registry line --------------------------------------------------------

@dataclass(frozen=True)
class HertzLaw:
    """A toy single-valued law: F_N = k (−g_N)^1.5 [N] while penetrating (g_N < 0)."""

    k: float
    kind: ClassVar[str] = "single-valued"
    dim: ClassVar[int] = 1
    units: ClassVar[dict] = {"k": "N/m^1.5"}

    def __post_init__(self):
        if not self.k > 0:
            raise ModelError(f"{self}: k must be > 0")

    def force(self, g_N, gd_N):
        g_N = np.asarray(g_N, dtype=float)
        return np.where(g_N < 0.0, self.k * np.abs(np.minimum(g_N, 0.0)) ** 1.5, 0.0)

    def derivatives(self, g_N, gd_N):
        g_N = np.asarray(g_N, dtype=float)
        return np.where(g_N < 0.0, -1.5 * self.k * np.abs(np.minimum(g_N, 0.0)) ** 0.5, 0.0), np.zeros_like(g_N)


@pytest.fixture
def hertz():
    LAWS.register("hertz", HertzLaw)              # the one registry line
    yield HertzLaw
    LAWS.unregister("hertz")


SCENE = fixture_text("scenes/bob_on_hertz_floor.toml")


def python_scene(law, friction=None):
    """The scene file bob_on_hertz_floor.toml written with the Python API and the law object ``law``."""
    system = System()
    bob = system.add(PointMass(0.1, position=(0.0, 0.0, 0.001), velocity=(0.2, 0.0, -1.0), name="bob"))
    system.add(Contact(contact.ContactKinematicsPointPlane(PointContour(bob.point),
                                                           PlaneContour(ground_frame((0.0, 0.0, 0.0)))),
                       law, friction=friction, name="floor"))
    return system


def test_a_registered_law_is_usable_from_a_scene_file(hertz, tmp_path):
    path = tmp_path / "hertz.toml"
    path.write_text(SCENE)
    scene = read_scene(path)
    (floor,) = scene.system.contacts
    assert floor.law == HertzLaw(1e6) and floor.friction is None and not floor.set_valued
    t_out = np.linspace(0.0, 0.02, 3)
    assert scene.integrator == "moreau"
    result = scene.system.simulate(0.02, 1e-4, integrator="moreau", t_out=t_out, plan=False)
    expected = python_scene(HertzLaw(1e6)).simulate(0.02, 1e-4, integrator="moreau", t_out=t_out, plan=False)
    np.testing.assert_array_equal(result.q, expected.q)
    np.testing.assert_array_equal(result.u, expected.u)
    assert result.q[-1][2] > 0.0 and result.u[-1][2] > 0.0        # it bounced off the floor

    # friction comes with any single-valued law
    path.write_text(SCENE + "mu = 0.3\nv_eps = 1e-3\n")
    floor, = read_scene(path).system.contacts
    assert floor.friction == contact.RegularizedCoulombFriction(0.3, 1e-3)


@pytest.mark.parametrize("old, new, fragments, on_line", [
    ("k = 1e6", "k = -1.0", ["contact 'floor': HertzLaw(k=-1.0): k must be > 0"], "k = -1.0"),
    ("k = 1e6", "k = true", ["'k' must be a number [N/m^1.5], got a boolean"], "k = true"),
    ("k = 1e6", "kk = 1.0", ["unknown key 'kk' for law 'hertz' (allowed: name, contour1, contour2, law, margin, k, "
                             "mu, v_eps)"], "kk"),
    ("k = 1e6", "", ["contact 'floor': missing required key 'k'"], "[[contact]]"),
    ('law = "hertz"', 'law = "hertzz"', ["'law' must be one of 'impact', 'coulomb', 'penalty', 'bilateral', 'hertz'"],
     "hertzz"),
])
def test_faults_of_a_registered_law_name_the_line_and_key(hertz, tmp_path, old, new, fragments, on_line):
    path = tmp_path / "hertz.toml"
    text = SCENE.replace(old, new)
    path.write_text(text)
    with pytest.raises(InputFileError) as info:
        read_scene(path)
    for fragment in fragments:
        assert fragment in info.value.fault
    assert on_line in text.splitlines()[info.value.line - 1]


def test_an_unregistered_law_is_not_known_to_scene_files(tmp_path):
    path = tmp_path / "hertz.toml"
    path.write_text(SCENE)
    with pytest.raises(InputFileError, match="'law' must be one of 'impact', 'coulomb', 'penalty', 'bilateral', got"):
        read_scene(path)


def test_system_takes_contacts_by_their_base_class_not_by_a_flag():
    """A System recognises a contact element by ContactElement (Contact and
    CurveConstraint derive from it); an object merely flagged ``is_contact`` is refused."""
    from contact import Contact, ContactElement, CurveConstraint
    from mbs import System

    assert issubclass(Contact, ContactElement) and issubclass(CurveConstraint, ContactElement)

    class Flagged:
        is_contact = True

        def bodies(self):
            return []

    with pytest.raises(ModelError, match="cannot add"):
        System().add(Flagged())

"""The point mass dropped on a clamped flexible beam (thesis Sec. 5.2, Fig. 5.3).

- Beam 250 x 50 x 50 mm, ρ = 920 kg/m³ (the thesis's 9.2e-10 t/mm³), E = 50 MPa,
  ν = 0.3, initially at rest. The thesis leaves the support implicit; **we clamp the
  face x = 0** (its frame-fixed FFR body of Sec. 5.1) and fix the body frame in space,
  so the reduced model is the FE model projected on its clamped modes.
- FE model: a structured tet4 mesh of 10 x 4 x 4 divisions (275 nodes, every face a
  node grid, a node at (250, 50, 25) mm: the thesis's "node 19"), all 750 clamped modes
  by a dense eigensolve, so the sweeps choose any number of modes and the reference
  can take them all. ``default_beam_data(divisions=..., order=2)`` builds finer and tet10
  meshes of the same beam (the meshes of the full-FE peer).
- Point mass 0.5 kg at (235, 52, 25) mm (setup A, on the beam's middle plane z = 25 mm)
  or (235, 52, 40) mm (setup B), velocity (0, −0.2, 0) m/s; no gravity (thesis
  Sec. 5.2.1).
- Contact: the point against a 2s neutral contour on the top face y = 50 mm
  (``contour="2s"``, the thesis's Contour2sNeutralLinearExternalFFR) or a
  ``FlexibleBand`` 50 mm wide on the top face's centre line (``contour="band"``, thesis
  Table 5.3), with a set-valued Newton impact law (``law="impact"``, e) or a linear
  penalty law (``law="penalty"``, k [N/m], d [N s/m]); the contact is named "impact"
  whatever its law.
- Outputs (:meth:`Scene.outputs`): ``y`` [m] and ``vy`` [m/s] of the point mass, and
  ``node19``, the **displacement** Φ q_f [m] of node 19 (not its position): the same
  names and meanings as ``examples/scenes/point_mass_beam.toml``.

The body data are preprocessed on first use and cached (:func:`default_beam_data`,
:mod:`ffrmbs_app.scenes.cache`).
"""

from __future__ import annotations

from dataclasses import dataclass

from contact import (Contact, ContactKinematicsPointContour2s, LinearRegularizedUnilateralConstraint,
                     UnilateralNewtonImpact)
from contours import Contour1sNeutralFFR, Contour2sNeutralFFR, FlexibleBand, PointContour
from ffrmbs.errors import ModelError
from mbs import FlexibleBodyFFR, PointMass, PrescribedFrameMotion, System

from .cache import cache_dir, cached_body

LENGTH, HEIGHT, WIDTH = 0.25, 0.05, 0.05          # [m] along x, y, z
DENSITY, YOUNG, POISSON = 920.0, 5e7, 0.3         # [kg/m³], [Pa], [-]
DIVISIONS = (10, 4, 4)                            # structured tet4, element edges per axis
MASS, VELOCITY = 0.5, (0.0, -0.2, 0.0)            # [kg], [m/s]
SETUPS = {"A": (0.235, 0.052, 0.025), "B": (0.235, 0.052, 0.040)}   # initial positions [m]
NODE_19 = (0.25, 0.05, 0.025)                     # the thesis's output node [m]
PENALTY_K = 1e7                                   # [N/m], the thesis's soft contact
OUTPUT_UNITS = {"y": "m", "vy": "m/s", "node19": "m"}
OUTPUT_LABELS = {"y": "point mass position y", "vy": "point mass velocity y",
                 "node19": "beam node 19 (thesis numbering) displacement"}
CONTACT = "impact"                                # the contact's name, whatever its law


def recipe(divisions=DIVISIONS, modes="all", order=1) -> dict:
    """The cache key of :func:`default_beam_data` (:func:`ffrmbs_app.scenes.cache.cached_body`);
    ``"order": 2`` is in it only for tet10, so the tet4 beams keep the keys they always had."""
    key = {"scene": "point_mass_beam", "size": [LENGTH, HEIGHT, WIDTH], "divisions": list(divisions),
           "material": [DENSITY, YOUNG, POISSON], "clamp": "x0", "modes": modes, "version": 1}
    if order == 2:
        key["order"] = 2
    return key


def default_beam_data(log=None, divisions=DIVISIONS, modes="all", order=1):
    """The beam's body data, preprocessed once and cached
    (:func:`ffrmbs_app.scenes.cache.cached_body`).

    Default: the 10 x 4 x 4 tet4 mesh with all its clamped modes (dense eigensolve).
    ``divisions`` (nx, ny, nz) meshes the same 250 x 50 x 50 mm beam more finely (nz
    even, so that node 19 at z = 25 mm is a node); ``order`` 2 meshes it with tet10
    (the mesh of the full-FE peer :mod:`validation.peers.full_fe_contact`, node for
    node); ``modes`` is "all" (dense, at most 6000 free DOFs) or the number of lowest
    clamped modes, found by the sparse shift-invert solver
    (:func:`preprocess.build_body`) — the way for large meshes.
    """
    if order not in (1, 2):
        raise ModelError(f"order must be 1 (tet4) or 2 (tet10), not {order!r}")
    params = recipe(tuple(divisions), modes, order)

    def build():
        from preprocess import Material, build_body
        from preprocess.geometry import box
        from preprocess.modes import all_modes

        mesh = box(LENGTH, HEIGHT, WIDTH, None, order=order, divisions=tuple(divisions))
        material = Material(DENSITY, YOUNG, POISSON)
        if modes != "all":
            return build_body(mesh, material, n_modes=int(modes), clamp="x0", params=params)
        data = build_body(mesh, material, n_modes=1, clamp="x0", params=params)
        data.eigenvalues, data.phi = all_modes(data.stiffness, data.mass, data.node_groups["x0"])
        data.params["n_modes"] = data.phi.shape[1]
        return data

    return cached_body(params, build, log)


@dataclass(frozen=True)
class Beam:
    """A mesh of the beam as a built-in body (``builtin:<name>`` of a scene file): its
    ``divisions``, element ``order`` and stored ``modes``, with the two functions a
    built-in body provides, :meth:`default_beam_data` and :meth:`recipe`."""

    divisions: tuple
    modes: object
    order: int

    @property
    def element_size(self) -> float:
        """The element edge along x [m]."""
        return LENGTH / self.divisions[0]

    def default_beam_data(self, log=None):
        return default_beam_data(log, self.divisions, self.modes, self.order)

    def recipe(self) -> dict:
        return recipe(self.divisions, self.modes, self.order)


#: the main job's beam: tet10 of 12.5 mm elements (3321 nodes), its 40 lowest clamped
#: modes; the full-FE study (``contact_full_fe``) puts its node-19 peak within 1.8 % of the
#: 6.25 mm mesh's, where the default tet4 mesh (all 750 modes) peaks 15–23 % lower
TET10 = Beam((20, 4, 4), 40, 2)
#: the same at 25 mm (525 nodes): the main job's mesh check
TET10_COARSE = Beam((10, 2, 2), 40, 2)


@dataclass
class Scene:
    """A built scene: the System and what its outputs read."""

    system: System
    beam: FlexibleBodyFFR
    mass: PointMass
    contact: Contact
    node: int                     # index of node 19

    def outputs(self):
        """Point-mass y position [m] and velocity [m/s], node 19's displacement Φ q_f [m]
        (body-frame components; the frame is fixed, so also world components). Their units:
        :data:`OUTPUT_UNITS`, what they are: :data:`OUTPUT_LABELS`."""
        mass, beam, j = self.mass, self.beam, self.node
        return {"y": lambda t, q, u: q[mass.q_slice][1],
                "vy": lambda t, q, u: u[mass.u_slice][1],
                "node19": lambda t, q, u: beam.phi_nodes[j] @ q[beam.q_slice]}


def build(setup="A", modes=20, law="impact", e=0.0, k=PENALTY_K, d=0.0, contour="2s", data=None,
          residual_flexibility=False) -> Scene:
    """Setup ``"A"`` or ``"B"`` with ``modes`` (int, or "all"), ``law`` "impact"
    (coefficient of restitution e) or "penalty" (k [N/m], d [N s/m]), ``contour`` "2s"
    or "band"; ``data`` the beam's body data (default: :func:`default_beam_data`);
    ``residual_flexibility``: the contour carries the dropped modes' static compliance
    (:mod:`contours.residual`; the System caches it in the scene cache)."""
    if setup not in SETUPS:
        raise ModelError(f"setup must be one of {sorted(SETUPS)}, not {setup!r}")
    data = default_beam_data() if data is None else data
    n = data.n_modes if modes == "all" else int(modes)
    system = System()
    system.cache_dir = cache_dir()
    beam = system.add(FlexibleBodyFFR(data, modes=n, frame=PrescribedFrameMotion.fixed(), name="beam"))
    mass = system.add(PointMass(MASS, position=SETUPS[setup], velocity=VELOCITY, name="point mass"))
    if contour == "2s":
        surface = Contour2sNeutralFFR(beam, "y1", residual_flexibility=residual_flexibility)
    elif contour == "band":
        axis = Contour1sNeutralFFR.along_line(beam, (0.0, HEIGHT, WIDTH / 2), (1, 0, 0), normal=(0, 1, 0), degree=4)
        surface = FlexibleBand(axis, width=WIDTH, offset=0.0, residual_flexibility=residual_flexibility)
    else:
        raise ModelError(f"contour must be '2s' or 'band', not {contour!r}")
    if law == "impact":
        force_law = UnilateralNewtonImpact(e)
    elif law == "penalty":
        force_law = LinearRegularizedUnilateralConstraint(k, d)
    else:
        raise ModelError(f"law must be 'impact' or 'penalty', not {law!r}")
    contact = system.add(Contact(ContactKinematicsPointContour2s(PointContour(mass.point), surface), force_law,
                                 name=CONTACT))
    return Scene(system, beam, mass, contact, data.node_at(NODE_19))

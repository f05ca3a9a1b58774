"""The ball sliding on a flexible beam (thesis Sec. 5.3, Fig. 5.14), and the moving-load
beam that checks it against an analytic oracle.

Thesis data (Sec. 5.3): beam 1.5 x 0.05 x 0.05 m (x the long axis), E = 5e7 Pa, ν = 0.3,
ρ = 920 kg/m³ (the thesis prints "9.2E2 t/mm³", a unit typo: 920 kg/m³ is the
polyethylene-like density of its Sec. 5.2), at rest, no gravity; a ball of radius
0.05 m, mass 1 kg, inertia 0.001 kg m², initial velocity (0.01, −0.002, 0) m/s, whose
centre is held bilaterally on the beam's neutral axis; 5 s; 20 (setup A) and 100
(setup B) modes.

Choices where the thesis is silent:

- **Support**: a cantilever, the face x = 0 clamped (clamped modes,
  ``build_body(..., clamp="x0")``) and the body frame fixed in space
  (``PrescribedFrameMotion.fixed()``), so q = q_f and the reduced beam is linear.
- **Ball start**: its centre at x = 0.75 m (mid-length) on the undeformed axis
  (y = z = 0.025 m), :data:`BALL_START`.
- **Ball model**: a :class:`mbs.PointMass` of 1 kg at the centre. The thesis's ball
  has its rotations "constrained by the beam", i.e. it turns with the cross-section's
  small slope w'(x, t); its rotational energy ½ J ẇ'² is J/m · k² ≈ 0.1 % of the
  translational ½ m ẇ² for the first mode (k ≈ 1.9/L) and the radius does not enter a
  centre-on-axis constraint, so a point mass carries the physics; the radius and inertia
  are kept as constants for the record only.
- **Mesh**: a structured tet10 mesh, ``box(1.5, 0.05, 0.05, order=2, divisions=(30, 1,
  1))`` (549 nodes). Its order-2 mid-edge/mid-face nodes put a line of 61 nodes on the
  centre axis y = z = 0.025 m (node spacing 25 mm), through which the 1s neutral contour
  (:class:`contours.Contour1sNeutralFFR`, degree 3, C²) is interpolated. The first
  y-bending frequencies against Euler–Bernoulli theory (β_nL = 1.8751, 4.6941, 7.8548,
  ...; ω_n = (β_nL)² (EI/(ρAL⁴))^½) are reported by the case (+0.4 %, −0.1 %, −0.9 %:
  tet10 is needed, tet4 with one element across is far too stiff in bending).
- **Constraint**: ``CurveConstraint(PointOnCurveConstraint(PointContour(ball.point),
  axis))``: the two normal-plane components of the ball centre's distance to the axis
  are kept at zero on velocity level (Moreau, γ⁺ = 0), so positions drift by O(Δt)
  (reported by :func:`axis_gap`). The initial ball velocity has a −0.002 m/s component
  normal to the beam at rest: the first step projects it (an inelastic impact of the ball
  on the beam, which then carries part of the momentum).

The body data, with the first :data:`STORED_MODES` clamped modes, are preprocessed once
and cached (:func:`default_beam_data`, like
:func:`ffrmbs_app.scenes.point_mass_beam.default_beam_data`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from contact import CurveConstraint, PointOnCurveConstraint
from contours import Contour1sNeutralFFR, PointContour
from ffrmbs.errors import ModelError
from mbs import FlexibleBodyFFR, Force, PointMass, PrescribedFrameMotion, System
from mbs.links.moving_force import MovingContourForce

from .cache import cache_dir, cached_body

LENGTH, HEIGHT, WIDTH = 1.5, 0.05, 0.05           # [m] along x, y, z
DENSITY, YOUNG, POISSON = 920.0, 5e7, 0.3         # [kg/m³], [Pa], [-]
AREA, INERTIA_Y = HEIGHT * WIDTH, WIDTH * HEIGHT**3 / 12   # [m²], [m⁴] (bending in y)
DIVISIONS, ORDER = (30, 1, 1), 2                  # structured tet10
STORED_MODES = 100
AXIS = (0.0, HEIGHT / 2, WIDTH / 2)               # a point of the centre axis [m]
BALL_MASS, BALL_RADIUS, BALL_INERTIA = 1.0, 0.05, 0.001     # [kg], [m], [kg m²]
BALL_VELOCITY = (0.01, -0.002, 0.0)               # [m/s]
BALL_START = (0.75, HEIGHT / 2, WIDTH / 2)        # [m], our choice
T_END = 5.0                                       # [s]
DEGREE = 3


def recipe() -> dict:
    """The cache key of :func:`default_beam_data` (:func:`ffrmbs_app.scenes.cache.cached_body`)."""
    return {"scene": "sliding_ball", "size": [LENGTH, HEIGHT, WIDTH], "divisions": list(DIVISIONS),
            "order": ORDER, "material": [DENSITY, YOUNG, POISSON], "clamp": "x0",
            "modes": STORED_MODES, "version": 1}


def default_beam_data(log=None):
    """The beam's body data with its first :data:`STORED_MODES` clamped modes,
    preprocessed once and cached (:func:`ffrmbs_app.scenes.cache.cached_body`)."""
    def build():
        from preprocess import Material, build_body
        from preprocess.geometry import box

        mesh = box(LENGTH, HEIGHT, WIDTH, None, order=ORDER, divisions=DIVISIONS)
        return build_body(mesh, Material(DENSITY, YOUNG, POISSON), n_modes=STORED_MODES, clamp="x0",
                          params=recipe())

    return cached_body(recipe(), build, log)


def axis_nodes(data) -> np.ndarray:
    """Indices of the nodes on the centre axis y = z = 0.025 m, by increasing x."""
    from contours.node_grid import node_line
    return node_line(data.u0, AXIS, (1.0, 0.0, 0.0))


def bending_modes(data, direction=1):
    """(indices, ω [rad/s]) of the stored modes dominated by displacement along
    ``direction`` (1: y-bending): more than half the modal mass φ_dᵀ M_s φ_d there
    (Σ m_j φ_jd² when lumped)."""
    phi_d = data.phi.reshape(data.n_nodes, 3, -1)[:, direction, :]
    share = np.einsum("jf,jf->f", phi_d, data.scalar_mass_matrix() @ phi_d)
    idx = np.flatnonzero(share > 0.5)
    return idx, np.sqrt(data.eigenvalues[idx])


def _beam(system, data, modes, degree, residual_flexibility=False):
    n = data.n_modes if modes == "all" else int(modes)
    beam = system.add(FlexibleBodyFFR(data, modes=n, frame=PrescribedFrameMotion.fixed(), name="beam"))
    return beam, _axis(beam, degree, residual_flexibility)


def _axis(beam, degree, residual_flexibility):
    """The degree-``degree`` neutral contour through the centre-axis nodes, with the
    dropped modes' static compliance when ``residual_flexibility``."""
    return Contour1sNeutralFFR.along_line(beam, AXIS, (1, 0, 0), normal=(0, 1, 0), degree=degree,
                                          name="neutral axis", residual_flexibility=residual_flexibility)


def eta_at(axis, x) -> float:
    """The contour coordinate η of the undeformed axis point at x [m]: the chord-length
    interpolant of collinear, equally spaced nodes is linear in η (a linear function lies
    in the spline space, and interpolation is unique), so η is affine in x; checked
    against the contour at both ends."""
    lo, hi = axis.domain
    x_lo, x_hi = axis.local_position_at(lo)[0], axis.local_position_at(hi)[0]
    return lo + (x - x_lo) * (hi - lo) / (x_hi - x_lo)


@dataclass
class Scene:
    """The sliding-ball System and what its outputs read."""

    system: System
    beam: FlexibleBodyFFR
    ball: PointMass
    axis: Contour1sNeutralFFR
    constraint: CurveConstraint

    def outputs(self):
        """Ball position x, y [m] and velocity vx, vy [m/s]; the beam's axis node
        displacements (n_axis, 3) [m] (for :func:`axis_gap`)."""
        ball, beam = self.ball, self.beam
        phi_axis = beam.phi_nodes[self.axis.nodes]
        return {"x": lambda t, q, u: q[ball.q_slice][0], "y": lambda t, q, u: q[ball.q_slice][1],
                "z": lambda t, q, u: q[ball.q_slice][2],
                "vx": lambda t, q, u: u[ball.u_slice][0], "vy": lambda t, q, u: u[ball.u_slice][1],
                "vz": lambda t, q, u: u[ball.u_slice][2],
                "axis": lambda t, q, u: phi_axis @ q[beam.q_slice]}

    def knots_x(self) -> np.ndarray:
        """x [m] of the undeformed axis nodes (the interpolation sites of the contour)."""
        return self.beam.data.u0[self.axis.nodes, 0]


def build(modes=20, start=BALL_START, velocity=BALL_VELOCITY, degree=DEGREE, data=None,
          residual_flexibility=False) -> Scene:
    """The sliding ball (module docstring) with ``modes`` (int or "all") clamped modes and
    a degree-``degree`` axis contour; ``data`` the body data (default: cached);
    ``residual_flexibility``: the axis carries the dropped modes' static compliance
    (:mod:`contours.residual`), so the constraint holding the ball acts through it — a
    massless spring in series in its rows [n, t2] (:mod:`mbs.run.residual_contact`; the
    System caches the compliance in the scene cache)."""
    data = default_beam_data() if data is None else data
    system = System()
    system.cache_dir = cache_dir()
    beam, axis = _beam(system, data, modes, degree, residual_flexibility)
    ball = system.add(PointMass(BALL_MASS, position=start, velocity=velocity, name="ball"))
    constraint = system.add(CurveConstraint(PointOnCurveConstraint(PointContour(ball.point), axis),
                                            name="ball on axis"))
    return Scene(system, beam, ball, axis, constraint)


def build_bent(tip_force, speed, x_start=0.1, modes=20, degree=DEGREE, data=None,
               residual_flexibility=False) -> Scene:
    """The knot-crossing variant: the beam held bent in static equilibrium by a constant
    tip force ``tip_force`` [N] along +y at the tip axis node (initial elastic coordinates
    q_f = K_ff⁻¹ Φ_tipᵀ F, at rest), the ball put on the bent axis at x_start [m] with the
    speed ``speed`` [m/s] along the axis tangent. On a C² axis the ball then feels only
    the smooth centripetal force m v² κ (κ(x) = F (L − x)/(EI) in Euler–Bernoulli theory)
    and the beam's smooth reaction to it; a kink of the contour at a node (degree 1)
    gives a velocity jump ≈ v · (change of slope) each time the ball crosses one.
    ``residual_flexibility`` as in :func:`build` (the tip force acts on a node, not
    through the axis, so only the ball's constraint sees the compliance)."""
    data = default_beam_data() if data is None else data
    system = System()
    system.cache_dir = cache_dir()
    n = data.n_modes if modes == "all" else int(modes)
    beam = FlexibleBodyFFR(data, modes=n, frame=PrescribedFrameMotion.fixed(), name="beam")
    tip = data.node_at((LENGTH, AXIS[1], AXIS[2]))
    q_f = np.linalg.solve(beam.K_ff, beam.phi_nodes[tip][1] * float(tip_force))
    beam.set_initial(q_f=q_f)
    system.add(beam)
    axis = _axis(beam, degree, residual_flexibility)
    system.add(Force(beam.node(tip), (0.0, float(tip_force), 0.0)))
    p = axis.evaluate(axis.new_point(), eta_at(axis, x_start))
    ball = system.add(PointMass(BALL_MASS, position=p.r.copy(), velocity=speed * p.t1, name="ball"))
    constraint = system.add(CurveConstraint(PointOnCurveConstraint(PointContour(ball.point), axis),
                                            name="ball on axis"))
    return Scene(system, beam, ball, axis, constraint)


def axis_gap(scene, result) -> np.ndarray:
    """|g| [m] per output time: the distance of the ball centre from the deformed axis in
    the axis's normal plane, g = (nᵀ d, t2ᵀ d) of :class:`contact.PointOnCurveConstraint`
    at the closest axis point — the position drift of the velocity-level constraint.
    Re-evaluates the contours after the run (their state is the last output's after)."""
    kin = scene.constraint.kinematics
    out = np.empty(len(result.t))
    for k in range(len(result.t)):
        q, u = result.q[k], result.u[k]
        for c in scene.constraint.contours():
            c.update(q[c.body.q_slice], u[c.body.u_slice], result.t[k])
        if not kin.update(velocity=False, jacobians=False):
            raise ModelError(f"the ball left the axis at t = {result.t[k]} s")
        out[k] = np.linalg.norm(kin.g)
    return out


@dataclass
class MovingLoadScene:
    """The beam alone under a force moving along its axis (the oracle check)."""

    system: System
    beam: FlexibleBodyFFR
    axis: Contour1sNeutralFFR
    load: MovingContourForce
    tip: int                      # node at (L, 0.025, 0.025)
    mid: int                      # node at (L/2, 0.025, 0.025)

    def outputs(self):
        """y-deflection [m] of the tip and midspan axis nodes."""
        beam, tip, mid = self.beam, self.tip, self.mid
        return {"tip": lambda t, q, u: beam.phi_nodes[tip][1] @ q[beam.q_slice],
                "mid": lambda t, q, u: beam.phi_nodes[mid][1] @ q[beam.q_slice]}


def build_moving_load(force, speed, x0=0.0, modes=20, degree=DEGREE, data=None) -> MovingLoadScene:
    """The cantilever with a force ``force`` [N] along +y (negative: downwards) at the
    axis point x0 + speed·t [m] (x0 [m], speed [m/s]), applied through the axis contour's
    J_T(η(t)) (:class:`mbs.links.moving_force.MovingContourForce`)."""
    data = default_beam_data() if data is None else data
    system = System()
    beam, axis = _beam(system, data, modes, degree)
    eta0, deta_dx = eta_at(axis, 0.0), (eta_at(axis, LENGTH) - eta_at(axis, 0.0)) / LENGTH
    load = system.add(MovingContourForce(axis, lambda t: eta0 + deta_dx * (x0 + speed * t),
                                         (0.0, float(force), 0.0)))
    return MovingLoadScene(system, beam, axis, load, data.node_at((LENGTH, AXIS[1], AXIS[2])),
                           data.node_at((LENGTH / 2, AXIS[1], AXIS[2])))

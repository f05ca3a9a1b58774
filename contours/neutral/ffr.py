"""The FFR family of neutral contours: concrete factories for :class:`mbs.FlexibleBodyFFR`
(thesis Sec. 3.2.2, 4.4.1; MBSim's ``Contour1sNeutralLinearExternalFFR``).

The products interpolate, on the undeformed node grid of the body file, the local
position ū = ū0 + Φ q_f and the mode shapes Φ once (thesis Table 4.1); position,
velocity and J_T = [1, −A ũ T, A Φ] (thesis Sec. 3.2.2) follow by control-point
combinations. Nodes come from a body-file node group (2s: structured-grid detection,
:func:`contours.node_grid.node_matrix`; 1s: a walk along the surface edges,
:func:`contours.node_grid.node_path`), an explicit node matrix O (eq. 3.24) or list,
or a straight line of nodes.
"""

from __future__ import annotations

import warnings

import numpy as np
from scipy.spatial import cKDTree

from ffrmbs.errors import ModelError
from contours.nurbs import Interpolation1D, SurfaceInterpolation
from contours.nurbs.knots import parameters

from ..fitting import SMOOTHING, CurveFit, Trim, fit_report, surface_fit
from ..node_grid import check_node_matrix, node_line, node_matrix, node_path
from .factory import Contour1sNeutralFactory, Contour2sNeutralFactory
from .products import NeutralNurbsLocalPosition, NeutralNurbsModeShapes, NeutralNurbsPosition, NeutralNurbsVelocity
from .space import CurveSpace, SurfaceSpace, as_pair


class _FFRProducts:
    """Product creation of the FFR family (shared by the 1s and 2s factories)."""

    def create_mode_shapes(self, nodal_phi):
        return NeutralNurbsModeShapes(self.space, nodal_phi) if nodal_phi.shape[-1] else None

    def create_local_position(self, nodal_u0, modes):
        return NeutralNurbsLocalPosition(self.space, nodal_u0, modes)

    def create_position(self):
        return NeutralNurbsPosition(self.space)

    def create_velocity(self):
        return NeutralNurbsVelocity(self.space)


class Contour1sNeutralFFR(_FFRProducts, Contour1sNeutralFactory):
    """A curve through a line of nodes of an FFR body (neutral axis, surface centre line).

    Parameters
    ----------
    body : FlexibleBodyFFR
    nodes : str or (k,) int
        A node-group name of the body file — a feature edge or any line of surface
        nodes of any tet4/tet10 mesh (e.g. a gmsh physical curve: a box edge, a pulley
        rim), ordered by walking the body's surface edges
        (:func:`contours.node_grid.node_path`, whose module docstring gives the start
        and direction) — or 0-based node indices in curve order (see
        :meth:`along_line`).
    normal : (3,)
        Reference normal in the body frame (e.g. (0, 1, 0) for a band on top of a beam
        along x); it rotates with the body and is made perpendicular to the tangent.
    degree : int
        NURBS degree (3: C²).
    closed : bool or None
        Periodic curve (the last node connects back to the first). None: a group's walk
        decides (a cycle of surface edges gives a closed curve, a path an open one),
        a list is open. Given with a group, it must agree with the walk (ModelError).
    method : "chord" or "centripetal"
        Parametrization of the undeformed nodes (thesis eq. 3.19–3.21).
    control_points : None or int
        None: the curve interpolates the ordered nodes (exact, thesis eq. 3.22). An int:
        a least-squares fit with that many distinct control points and uniform knots at
        the same parameters (:class:`contours.fitting.CurveFit`), e.g. to smooth a long
        edge of many nodes.
    smoothing : float
        Dimensionless weight of ∫ |C''|² in the fit (:mod:`contours.fitting.bspline_fit`).
    compiled : bool
        Span-local numba evaluation (default) or the reference route
        (:class:`~contours.neutral.factory.NeutralContour`).
    residual_flexibility : bool
        Contacts on this contour act through the static compliance of the modes the body
        leaves out (:mod:`contours.residual`, :mod:`contact.compliance`): accurate impacts
        with few modes, no extra coordinates.
    """

    def __init__(self, body, nodes, normal, degree=3, closed=None, method="chord", name="neutral 1s",
                 compiled=True, control_points=None, smoothing=SMOOTHING, residual_flexibility=False):
        self.residual_flexibility = bool(residual_flexibility)
        if isinstance(nodes, str):
            nodes, closed = self._walk(body, nodes, closed, name)
        else:
            nodes = check_node_matrix(np.asarray(nodes).reshape(1, -1), body.data.n_nodes)[0]
            closed = bool(closed)
        self.nodes = nodes
        points = body.data.u0[nodes]
        if control_points is None:
            interp = Interpolation1D.from_points(points, degree, closed, method)
        else:
            interp = CurveFit(parameters(points, method, closed), control_points, degree, closed, smoothing)
        phi = body.phi_nodes[nodes]
        super().__init__(body, CurveSpace(interp), body.data.u0[nodes], phi, normal, name, compiled)

    @staticmethod
    def _walk(body, group, closed, name):
        """(ordered nodes, closed) of the node group ``group`` walked along the surface
        edges; ``closed`` (None or a bool) checked against the walk."""
        data = body.data
        if data.surface_triangles is None:
            raise ModelError(f"{name}: the body file of {body.name!r} holds no surface triangles, so node group "
                             f"{group!r} cannot be walked; give the nodes as an ordered list")
        path, cycle = node_path(data.surface_triangles, body.node_group(group), data.u0, f"node group {group!r}")
        if closed is not None and bool(closed) != cycle:
            shape = "a closed loop" if cycle else "an open line with two ends"
            raise ModelError(f"{name}: closed={bool(closed)} but node group {group!r} is {shape} of surface "
                             f"edges; omit closed (it follows the walk) or give {cycle}")
        return path, cycle

    @classmethod
    def along_line(cls, body, start, direction, normal, nodes=None, **kw):
        """The contour through the nodes on the line through ``start`` [m] along
        ``direction`` (optionally among ``nodes`` or a node-group name). Too few nodes on
        the line for the curve's degree (an unstructured mesh has few nodes on an arbitrary
        line) is a ModelError that says so and what to do."""
        if isinstance(nodes, str):
            nodes = body.node_group(nodes)
        on_line = node_line(body.data.u0, start, direction, nodes)
        degree = kw.get("degree", 3)
        if kw.get("control_points") is None and on_line.size < degree + 1:
            point = lambda v: "(" + ", ".join(f"{float(x):g}" for x in np.ravel(v)) + ")"  # noqa: E731
            raise ModelError(f"{kw.get('name', 'neutral 1s')}: only {on_line.size} nodes of {body.name!r} lie on the "
                             f"line through {point(start)} m along {point(direction)}, a degree-{degree} curve "
                             f"needs {degree + 1}: mesh the part with nodes along that line (e.g. a structured "
                             "mesh) or give the curve's nodes in order")
        return cls(body, on_line, normal, **kw)


class Contour1sEdgeFFR(Contour1sNeutralFFR):
    """An edge of an FFR body: a curve through a line of surface nodes (parameters as
    :class:`Contour1sNeutralFFR`) that a sphere touches as a sharp edge — its contact
    measures the distance from the curve, the normal pointing from the curve to the
    sphere's centre (:class:`contact.kinematics.ContactKinematicsSphereEdge`), whatever
    the reference ``normal`` (which only completes the curve's own frame). The rims of a
    face (its outer edge, each hole's rim) are such edges: :meth:`Contour2sNeutralFFR.rims`."""


class Contour2sNeutralFFR(_FFRProducts, Contour2sNeutralFactory):
    """A surface on a patch of nodes of an FFR body (thesis Fig. 3.4).

    A structured patch (a node grid, thesis eq. 3.24) is interpolated exactly; any other
    face group of the body's surface — an unstructured tet4 or tet10 mesh — is fitted by
    least squares (:mod:`contours.fitting`): its nodes are mapped onto the unit square
    (periodic in η for a closed band), and the control points of ū0 and of every mode
    shape are F ū0 and F Φ with one fitting matrix F, so the per-step update is the same.
    A face with holes is fitted over its outer loop's square and trimmed to its material
    (:attr:`trim`, :mod:`contours.fitting.trim`): no contact point lies in a hole.

    Parameters
    ----------
    body : FlexibleBodyFFR
    nodes : str or (k_eta, k_xi) int
        A node-group name of the body file or the node matrix O (eq. 3.24) itself. A group
        that is a planar structured grid is ordered automatically
        (:func:`contours.node_grid.node_matrix`) and interpolated; any other group is fitted.
    extra_rows : int
        Grid route: rows of coplanar surface nodes added beyond each side of the patch
        where complete rows exist (thesis Sec. 3.2.2: better tangents near the boundary).
    degree : int or (int, int)
    closed : bool or (bool, bool)
        Grid route: periodic in η and/or ξ. A fitted patch is periodic in η exactly when
        it is a closed band (two boundary loops).
    method : "chord" or "centripetal"
        Grid route: the parametrization of the node grid.
    outward : None, +1 or -1
        Sign of t_η × t_ξ pointing out of the material; None decides it from the body's
        nodes behind the patch.
    control_points : None, int or (int, int)
        Distinct control points per direction of a fitted patch (None: knot spans of about
        two node spacings, :func:`contours.fitting.default_control_points`). Given with a
        group, the group is fitted even if it is a grid.
    smoothing : float
        Dimensionless thin-plate weight of the fit (:mod:`contours.fitting.bspline_fit`).
    compiled : bool
        Span-local numba evaluation (default) or the reference route
        (:class:`~contours.neutral.factory.NeutralContour`).
    residual_flexibility : bool
        Contacts on this contour act through the static compliance of the modes the body
        leaves out (:mod:`contours.residual`, :mod:`contact.compliance`): accurate impacts
        with few modes, no extra coordinates.

    Attributes
    ----------
    nodes : the node matrix O (grid route) or the patch's node indices (k,) (fitted).
    fit, patch, fit_report : the :class:`~contours.fitting.SurfaceFit`,
        :class:`~contours.fitting.SurfacePatch` and :class:`~contours.fitting.FitReport`
        of a fitted patch (a warning for each bound of the report it exceeds), else None.
    trim : the :class:`~contours.fitting.Trim` of a face with holes, else None.
    """

    def __init__(self, body, nodes, extra_rows=0, degree=3, closed=False, method="chord",
                 outward=None, name="neutral 2s", compiled=True, control_points=None, smoothing=SMOOTHING,
                 residual_flexibility=False):
        self.residual_flexibility = bool(residual_flexibility)
        data = body.data
        self.fit = self.patch = self.fit_report = None
        if isinstance(nodes, str):
            group = body.node_group(nodes)
            O = None if control_points is not None else _grid_or_none(data, group, extra_rows)
            if O is None:
                self.fit, self.patch = surface_fit(data.u0, data.surface_triangles, group, control_points,
                                                   degree, smoothing, f"{name}: node group {nodes!r}")
        else:
            O = check_node_matrix(nodes, data.n_nodes)
        if O is None:
            self.nodes = self.patch.nodes
            self.trim = Trim.of_fit(self.fit, self.patch)
            space = SurfaceSpace(self.fit)
            self.fit_report = fit_report(self.fit, self.patch, body.phi_nodes[self.nodes],
                                         f"{name}: node group {nodes!r} of body {body.name!r}")
            for line in self.fit_report.warnings:
                warnings.warn(f"{self.fit_report.name}: {line}", stacklevel=2)
        else:
            self.nodes = O
            space = SurfaceSpace(SurfaceInterpolation.from_grid(data.u0[O], as_pair(degree, "degree"),
                                                                as_pair(closed, "closed"), method))
        super().__init__(body, space, data.u0[self.nodes], body.phi_nodes[self.nodes],
                         1 if outward is None else outward, name, compiled)
        if outward is None:
            self.sign = self._outward_sign()

    def rims(self, **options) -> list:
        """The edges of a fitted face, each a closed :class:`Contour1sEdgeFFR` through its
        boundary loop's nodes: the outer edge first, then each hole's rim (a face with
        holes), or the one boundary of a face; a band's two rims. ``options``: those of
        :class:`Contour1sEdgeFFR` (degree, method, control_points, smoothing, ...); the
        reference normal is the face's mean outward normal (a band, whose normals cancel: z). ModelError on a structured grid (give the edge's node group)."""
        if self.patch is None:
            raise ModelError(f"{self.name}: the rims of a node-grid contour are not known; give each edge as a "
                             f"node group of a 1s edge contour")
        patch = self.patch
        loops = patch.loops
        if patch.topology() == "holes":
            outer, holes = patch.outer_and_holes()
            loops = [outer] + holes
        m = patch.mean_normal()
        normal = m if m is not None else np.array([0.0, 0.0, 1.0])
        return [Contour1sEdgeFFR(self.body, patch.nodes[loop], normal, closed=True,
                                 name=f"{self.name} {'outer edge' if i == 0 else f'rim {i}'}", **options)
                for i, loop in enumerate(loops)]

    def _outward_sign(self) -> float:
        """+1 if t_η × t_ξ at the patch centre points away from the nearest nodes not on
        the patch (the material behind it), else -1."""
        (a, b), (c, d) = self.domain
        self.space.locate(0.5 * (a + b), 0.5 * (c + d))
        rows = np.zeros((6, 3))
        self.space.contract(self.local_position.ctrl0, 3, rows)
        n0 = np.cross(rows[1], rows[2])
        u0 = self.body.data.u0
        others = np.setdiff1d(np.arange(len(u0)), self.nodes.ravel())
        if not others.size:
            raise ModelError(f"{self.name}: the patch holds every node; give outward=+1 or -1")
        _, near = cKDTree(u0[others]).query(rows[0], k=min(20, others.size))
        depth = (u0[others[np.atleast_1d(near)]] - rows[0]) @ n0
        if abs(depth.mean()) <= 1e-9 * np.abs(depth).max(initial=0.0) or not depth.any():
            raise ModelError(f"{self.name}: cannot tell the material side of the patch; give outward=+1 or -1")
        return 1.0 if depth.mean() < 0 else -1.0


def _grid_or_none(data, group, extra_rows):
    """The node matrix O of a planar structured ``group`` (eq. 3.24), or None when the
    group is not one (then it is fitted)."""
    candidates = data.surface_nodes if data.surface_triangles is not None else None
    try:
        return node_matrix(data.u0, group, extra_rows, candidates)
    except ModelError:
        return None

"""Face contact: a surface of a flexible body pressed on a surface of another body, or of
the ground, node to surface.

The face is a neutral contour of a flexible body (a 2s face, or a 1s curve: an edge on a
face) or of a rigid body (the grid or the points it runs through); the other side any
contour a point can touch (2s, 1s, band, cylinder, plane, sphere). :class:`FaceContact`
puts a point contact (:class:`contact.Contact`, the pair kind registered for a point and
that contour) at each node of the face, on the node's frame ``body.node(j)`` (a rigid
face: at each grid point, ``body.frame_at``), all with the same law — node to surface,
one pass, the face's nodes the points. With ``residual_flexibility`` on the face each point carries its
node's share of the static compliance of the modes the body leaves out, cross terms
between all the face's points included (:class:`contours.residual.NodeCompliance`), in
series with the other side's when that is corrected too: a face landing on a plate keeps
one contact interval and its energy, where rigid nodes lose a sixth of it
(``docs/guide/residual_flexibility.md``).

Node to surface passes the contact patch test only where the face's nodes meet the
other side's (matching meshes, a plane, a finer face on a coarser surface: 0.2 % off the
uniform pressure's resultant in the test of :mod:`validation.peers.static_contact`, 9 % with
the coarser face as the points); the mortar pairing of that peer passes it.

Each node's tributary area A_j [m²] — a third of each surface triangle at it, a tet10
triangle cut into its four corner triangles; on a rigid grid a quarter of each grid cell
at it — turns the point's normal force into a pressure p_j = F_N,j / A_j; :meth:`FaceContact.resultant` sums a run's recorded point
forces into the face's force and moment.
"""

from __future__ import annotations

import numpy as np

from contours.neutral.factory import NeutralContour
from contours.registry import CONTOURS
from contours.rigid import PointContour
from ffrmbs.errors import ModelError

from .contact import Contact
from .registry import PAIR_KINEMATICS

TET10_CORNERS = ((0, 3, 5), (3, 1, 4), (5, 4, 2), (3, 4, 5))    # a 6-node triangle's four linear triangles


class FaceContact:
    """The point contacts of a face against ``surface`` (module docstring).

    Parameters
    ----------
    face : NeutralContour
        A 1s or 2s neutral contour of a flexible body (its ``nodes`` are the points) or of a
        rigid body (its ``points``).
    surface : Contour
        The other side.
    law, friction, margin
        As for :class:`contact.Contact`, for every point.
    name : str
        The face's name; its points are named "<name> node <j>".

    Attributes
    ----------
    points : tuple of Contact
        One per node, in the order of ``nodes``.
    nodes : (k,) int array or None
        The face's nodes (each once); None on a rigid body.
    areas : (k,) array [m²] or None
        Tributary areas (a 2s face whose body file holds its surface triangles, or a rigid
        grid), else None.
    """

    def __init__(self, face, surface, law, friction=None, name="face", margin="auto"):
        flexible = hasattr(face.body, "K_ff")
        if not isinstance(face, NeutralContour) or not (flexible or hasattr(face, "points")):
            raise ModelError(f"face {name!r}: the face must be a neutral 1s or 2s contour of a flexible or a rigid "
                             f"body, not a {type(face).__name__}")
        kind = CONTOURS.name_of(surface)
        if ("point", kind) not in PAIR_KINEMATICS:
            raise ModelError(f"face {name!r}: its points cannot touch a contour of kind {kind!r}")
        body = face.body
        self.name, self.face, self.surface = name, face, surface
        if flexible:
            self.nodes = np.unique(np.asarray(face.nodes).ravel())
            frames = {f"{name} node {j}": body.node(int(j)) for j in self.nodes}
            self.areas = tributary_areas(body.data, self.nodes) if face.space.dim == 2 else None
        else:
            self.nodes = None
            points = face.points.reshape(-1, 3)
            frames = {f"{name} point {j}": body.frame_at(p) for j, p in enumerate(points)}
            self.areas = grid_areas(face.points) if face.space.dim == 2 else None
        residual = face.residual_flexibility
        self.points = tuple(
            Contact(PAIR_KINEMATICS[("point", kind)](PointContour(frame, point_name, residual_flexibility=residual),
                                                     surface),
                    law, friction=friction, name=point_name, margin=margin)
            for point_name, frame in frames.items())

    def contacts(self) -> tuple:
        """The point contacts a System adds for this face."""
        return self.points

    def bodies(self):
        return self.points[0].bodies()

    def resultant(self, result, about=(0.0, 0.0, 0.0)) -> tuple:
        """(force (n, 3) [N], moment (n, 3) [N m] about the point ``about`` [m]) on the
        face's body at each output of ``result`` (run with ``contacts=True``): the sums
        of the points' recorded forces F_j and of (p_j − about) × F_j, p_j the recorded
        contact points (on the other side)."""
        records = getattr(result, "contacts", None) or {}
        missing = [c.name for c in self.points if c.name not in records]
        if missing:
            raise ModelError(f"face {self.name!r}: the result holds no record of {missing[0]!r}: "
                             "run with contacts=True")
        force = sum(np.nan_to_num(records[c.name]["force"]) for c in self.points)
        arm = lambda rec: np.nan_to_num(rec["point"] - np.asarray(about, dtype=float))   # noqa: E731
        moment = sum(np.cross(arm(records[c.name]), np.nan_to_num(records[c.name]["force"])) for c in self.points)
        return force, moment

    def pressures(self, result) -> np.ndarray:
        """The points' pressures p_j = F_j · n_j / A_j (n, k) [Pa] at each output of
        ``result`` (run with ``contacts=True``), n_j the recorded normal; a 2s face only."""
        if self.areas is None:
            raise ModelError(f"face {self.name!r}: pressures need a 2s face whose body file holds surface triangles")
        records = result.contacts
        return np.stack([np.nan_to_num(np.einsum("ij,ij->i", records[c.name]["force"], records[c.name]["normal"]))
                         for c in self.points], axis=1) / self.areas


def grid_areas(grid) -> np.ndarray:
    """A quarter of the area of each cell of the point grid (k_η, k_ξ, 3) [m] at each of
    its corners (the cell's two triangles' areas), summed per point: (k_η k_ξ,) [m²] in the
    grid's row-major order."""
    grid = np.asarray(grid, dtype=float)
    a, b, c, d = grid[:-1, :-1], grid[1:, :-1], grid[1:, 1:], grid[:-1, 1:]
    cell = 0.5 * (np.linalg.norm(np.cross(b - a, c - a), axis=-1) + np.linalg.norm(np.cross(c - a, d - a), axis=-1))
    areas = np.zeros(grid.shape[:2])
    for di, dj in ((0, 0), (1, 0), (1, 1), (0, 1)):
        areas[di:di + cell.shape[0], dj:dj + cell.shape[1]] += 0.25 * cell
    return areas.ravel()


def tributary_areas(data, nodes) -> np.ndarray | None:
    """A third of the area of each surface triangle (a tet10 triangle's four corner
    triangles) whose nodes all lie in ``nodes``, summed on its nodes: (k,) [m²] in the
    order of ``nodes``; None when the body data holds no surface triangles."""
    triangles = getattr(data, "surface_triangles", None)
    if triangles is None:
        return None
    triangles = np.asarray(triangles)
    inside = np.isin(triangles, nodes).all(axis=1)
    if triangles.shape[1] == 6:
        triangles = np.concatenate([triangles[:, list(c)] for c in TET10_CORNERS])
        inside = np.tile(inside, len(TET10_CORNERS))
    triangles = triangles[inside]
    p = data.u0[triangles]
    area = 0.5 * np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1)
    per_node = np.zeros(data.n_nodes)
    np.add.at(per_node, triangles, np.repeat(area[:, None] / 3.0, 3, axis=1))
    return per_node[nodes]


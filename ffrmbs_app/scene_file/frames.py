"""Frames named in a scene file (``body`` plus at most one of ``node``, ``at``, ``point``;
see "Frames" in :mod:`ffrmbs_app.scene_file.schema`): checked while reading, resolved
to :class:`mbs.Frame` objects of the built System."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from mbs import PointMass, System, ground_frame
from mbs.bodies.body import Frame

from .schema import GROUND, REQUIRED
from .tables import Table, describe


@dataclass
class Env:
    """The System being built and its bodies by name."""

    system: System
    bodies: dict = field(default_factory=dict)


@dataclass(eq=False)
class FrameRef:
    """A checked frame reference: a body name (or "ground"), a node, or a point [m]."""

    body: str
    node: int | None = None
    point: np.ndarray | None = None

    def same(self, other) -> bool:
        """Whether both name the same point."""
        return (self.body, self.node) == (other.body, other.node) and (
            (self.point is None and other.point is None)
            or (self.point is not None and other.point is not None and np.array_equal(self.point, other.point)))

    def resolve(self, env: Env, orientation=None, name=None) -> Frame:
        """The :class:`mbs.Frame` in the built System ``env`` (axes ``orientation``, a
        rotation matrix relative to the body frame, if given)."""
        point = np.zeros(3) if self.point is None else self.point
        if self.body == GROUND:
            return ground_frame(point, orientation, name or GROUND)
        body = env.bodies[self.body]
        if self.node is not None:
            return body.node(self.node, orientation)
        if isinstance(body, PointMass):
            if self.point is None and orientation is None:
                return body.point
            return Frame(body, point, orientation=orientation, name=name or body.name)
        if self.point is None and orientation is None:
            return body.origin
        return body.frame_at(point, orientation, name)


def body_of(bodies: dict, t: Table, key="body", kinds=None, default=REQUIRED) -> str:
    """A body name of ``bodies`` (name -> checked body entry) or "ground", of one of
    ``kinds`` if given."""
    name = t.string(key, default)
    if name == GROUND and (kinds is None or GROUND in kinds):
        return name
    if name not in bodies:
        known = ", ".join([GROUND, *bodies]) if kinds is None or GROUND in kinds else ", ".join(bodies)
        t.fail(key, f"unknown body {name!r} (bodies: {known})")
    if kinds is not None and bodies[name].kind not in kinds:
        t.fail(key, f"body {name!r} is a {bodies[name].kind} body; this needs "
                    f"{' or '.join(k for k in kinds if k != GROUND)}")
    return name


def frame_of(bodies: dict, t: Table, default_body=REQUIRED) -> FrameRef:
    """The frame named by the keys body, node, at, point of ``t``."""
    name = body_of(bodies, t, default=default_body)
    given = [k for k in ("node", "at", "point") if t.has(k)]
    if len(given) > 1:
        t.fail(given[1], f"give one of 'node', 'at' or 'point', not {' and '.join(map(repr, given))}")
    kind = GROUND if name == GROUND else bodies[name].kind
    if given and given[0] in ("node", "at") and kind != "flexible":
        t.fail(given[0], f"{given[0]!r} needs a flexible body; {name!r} is "
                         f"{'the inertial frame' if kind == GROUND else 'a ' + kind + ' body'} "
                         "(use 'point')")
    if t.has("node"):
        data = bodies[name].data
        return FrameRef(name, node=t.integer("node", low=0, high=data.n_nodes - 1))
    if t.has("at"):
        at = t.get("at")
        return FrameRef(name, node=t.model("at", lambda: bodies[name].data.node_at(at.tolist())))
    return FrameRef(name, point=t.get("point"))


def nodes_of(bodies: dict, t: Table, key, name, required=True):
    """A node-group name of body ``name`` or an array of its node indices (None when
    absent and not ``required``)."""
    data = bodies[name].data
    value = t.data.get(key)
    if isinstance(value, str):
        if value not in data.node_groups:
            t.fail(key, f"body {name!r} has no node group {value!r} (groups: "
                        f"{', '.join(sorted(data.node_groups)) or 'none'})")
        return value
    if value is None and not required:
        return None
    if value is None:
        t.fail(None, f"missing required key {key!r}")
    if not isinstance(value, list):
        t.fail(key, f"{key!r} must be a node-group name or an array of 0-based node indices, "
                    f"got {describe(value)}")
    return t.indices(key, data.n_nodes)

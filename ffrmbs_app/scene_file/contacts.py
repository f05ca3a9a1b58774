"""The ``[[contact]]`` entries of a scene file: two contours (classes from
:data:`contours.CONTOURS`), a force law (:data:`contact.LAWS`, its parameters read from
the law class, :func:`~ffrmbs_app.scene_file.schema.law_keys`) and the kinematics the
registries give for the two contour kinds (:func:`contact.connect`)."""

from __future__ import annotations

import re

import numpy as np

from contact import (BILATERAL_KINEMATICS, LAWS, PAIR_KINEMATICS, Bilateral, RegularizedCoulombFriction, connect,
                     make_law)
from contours import CONTOURS
from contours.node_grid import node_path
from ffrmbs.errors import ModelError

from .frames import Env, body_of, frame_of, nodes_of
from .schema import (CONTACT, CONTOUR, CONTOUR1_KINDS, CONTOUR2_KINDS, FACE_KINDS, GROUND, Key, friction_keys,
                     law_keys)
from .tables import Table, describe, is_int, is_number, run


class ContactReader:
    """Reads the [[contact]] entries of one scene file (``doc``) with its checked bodies
    ({name: BodyEntry}); :meth:`read` returns one builder ``build(env)`` per entry."""

    def __init__(self, doc, bodies: dict):
        self.doc, self.bodies = doc, bodies

    def read(self, entries) -> list:
        """[(keypath, label, build(env))] of the (index, table) ``entries``."""
        names, steps = set(), []
        for i, data in entries:
            keypath = ("contact", i)
            given = data.get("name")
            label = f"contact {given!r}" if isinstance(given, str) else f"contact #{i + 1}"
            t = Table(self.doc, data, keypath, label, None)    # the keys are checked once the law is known
            name = t.get("name", f"contact {i + 1}", spec=CONTACT["name"])
            if name in names:
                t.fail("name", f"a second contact named {name!r} (contact names must be unique)")
            names.add(name)
            law = t.get("law", spec=CONTACT["law"])
            parameters, friction = law_keys(law), friction_keys(law)
            bilateral = issubclass(LAWS[law], Bilateral)
            common = tuple(k for k in CONTACT if not (bilateral and k == "margin"))
            t.allow(common + tuple(parameters) + tuple(k for k in friction if k not in parameters),
                    f" for law {law!r}")
            kind1, body1, make1 = self._contour(t, "contour1", CONTOUR1_KINDS)
            kind2, body2, make2 = self._contour(t, "contour2", CONTOUR2_KINDS)
            if body1 == GROUND and body2 == GROUND:
                t.fail("contour2", "both contours are on the ground: the contact would act on nothing")
            pairs = BILATERAL_KINEMATICS if bilateral else PAIR_KINEMATICS
            if kind1 in FACE_KINDS and bilateral:
                t.fail("law", f"a face (contour1 kind {kind1!r}) takes a unilateral law, not {law!r}")
            if ("point" if kind1 in FACE_KINDS else kind1, kind2) not in pairs:
                known = [f"{a}/{b}" for a, b in pairs if a in CONTOUR1_KINDS and b in CONTOUR2_KINDS]
                t.fail("law", f"law {law!r} has no kinematics for contour1 kind {kind1!r} and contour2 kind "
                              f"{kind2!r} (contour1/contour2 kinds it takes: {', '.join(known)})")
            force_law = self._law(t, law, parameters)
            friction_law = self._friction(t, friction)
            margin = self._margin(t) if not bilateral else None

            def build(env: Env, make1=make1, make2=make2, law=force_law, friction=friction_law, margin=margin,
                      name=name):
                env.system.add(connect(make1(env), make2(env), law, friction=friction, name=name, margin=margin))

            steps.append((t.keypath, t.label, build))
        return steps

    # --- the law ---------------------------------------------------------------------------------------
    def _law(self, t: Table, law, parameters: dict):
        """The law registered as ``law`` with its parameters read by ``parameters`` ({key:
        Key}); a ModelError of the law is reported at the key it names."""
        values = {key: t.get(key, spec=spec) for key, spec in parameters.items()}
        return self._model(t, values, lambda: make_law(law, **values))

    def _friction(self, t: Table, keys: dict):
        """The optional friction of a single-valued law: all its keys or none."""
        if not any(t.has(key) for key in keys):
            return None
        values = {key: t.get(key, spec=spec) for key, spec in keys.items()}
        return self._model(t, values, lambda: RegularizedCoulombFriction(**values))

    @staticmethod
    def _model(t: Table, values: dict, make):
        """``make()``, a ModelError reported at the parameter it names (else the first)."""
        try:
            return make()
        except ModelError as exc:
            named = [key for key in values if re.search(rf"(^|: ){re.escape(key)}\b", str(exc))]
            given = [key for key in values if t.has(key)] or [None]
            t.fail((named or given)[0], str(exc))

    def _margin(self, t: Table):
        """The broad phase's margin [m]: a length >= 0, "auto" or None ("off")."""
        if not t.has("margin"):
            return CONTACT["margin"].default
        value = t.data["margin"]
        if value in ("auto", "off"):
            return None if value == "off" else value
        if is_number(value):
            return t.number("margin", unit="m", low=0.0)
        t.fail("margin", f"'margin' must be a length [m] >= 0, \"auto\" or \"off\", got {describe(value)}")

    # --- the contours --------------------------------------------------------------------------------
    @staticmethod
    def _node_residual(c: Table, frame) -> bool:
        """A point's or sphere's ``residual_flexibility``: only at a node of a flexible body."""
        residual = c.get("residual_flexibility")
        if residual and frame.node is None:
            c.fail("residual_flexibility", "residual flexibility needs the point at a 'node' (or 'at') of a flexible "
                                           "body: the dropped modes' compliance is that of a node")
        return residual

    def _contour(self, t: Table, key, kinds):
        """(kind, body name or "ground", make(env) -> Contour) of the contour table ``key``.
        Either side may be on the ground: a point on the ground against a surface on a
        body is a part landing on a rigid support (the compliant surface on the part)."""
        head = t.table(key, f"{key!r}", None)         # the keys are checked once the kind is known
        kind = head.get("kind", spec=Key("choice", choices=kinds))
        label = f"{key} ({kind})"
        c = t.table(key, label, CONTOUR[kind])
        cls = CONTOURS[kind]
        if kind == "point":
            frame = frame_of(self.bodies, c)
            owner = frame.body
            residual = self._node_residual(c, frame)

            def make(env):
                return cls(frame.resolve(env), residual_flexibility=residual)

        elif kind == "sphere":
            frame = frame_of(self.bodies, c)
            owner = frame.body
            radius = c.get("radius")
            residual = self._node_residual(c, frame)

            def make(env):
                return cls(frame.resolve(env), radius, residual_flexibility=residual)

        elif kind == "plane":
            frame = frame_of(self.bodies, c, GROUND)
            owner = frame.body
            normal = c.get("normal")
            if not np.linalg.norm(normal) > 0:
                c.fail("normal", "'normal' must be a nonzero direction")
            size = c.get("size")
            axes = axes_with_normal(normal)

            def make(env):
                return cls(frame.resolve(env, orientation=axes, name="plane"), size)

        elif kind == "2s":
            name = owner = body_of(self.bodies, c, kinds=("flexible",))
            nodes = self._node_matrix(c, name)
            extra = c.get("extra_rows")
            degree = _pair(c, "degree", int)
            closed = _pair(c, "closed", bool)
            method = c.get("method")
            outward = None
            if c.has("outward"):
                outward = c.integer("outward")
                if outward not in (1, -1):
                    c.fail("outward", f"'outward' must be 1 or -1, got {outward}")

            fitting = dict(control_points=_pair(c, "control_points", int) if c.has("control_points") else None,
                           smoothing=c.get("smoothing"), residual_flexibility=c.get("residual_flexibility"))

            def make(env):
                return cls(env.bodies[name], nodes, extra, degree, closed, method, outward, **fitting)

        else:   # 1s, edge, band, cylinder: on a 1s neutral curve
            make = self._curve(c, kind)
            owner = c.data["body"]                  # a flexible body, checked by _curve
        keypath, label = t.keypath + (key,), f"{t.label}: {label}"        # a ModelError is reported there
        return kind, owner, lambda env: run(self.doc, keypath, label, lambda: make(env))

    def _curve(self, c: Table, kind):
        """make(env) of a 1s neutral curve or edge, or a band or a cylinder on a curve."""
        name = body_of(self.bodies, c, kinds=("flexible",))
        line = c.has("start") or c.has("direction")
        start = c.get("start") if line else None
        direction = c.get("direction") if line else None
        if line and not np.linalg.norm(direction) > 0:
            c.fail("direction", "'direction' must be a nonzero direction")
        nodes = nodes_of(self.bodies, c, "nodes", name, required=not line)
        closed = c.get("closed")
        if not line and isinstance(nodes, str):
            nodes, closed = self._walk(c, name, nodes, closed)
        normal = c.get("normal")
        if not np.linalg.norm(normal) > 0:
            c.fail("normal", "'normal' must be a nonzero direction")
        options = dict(degree=c.get("degree"), closed=closed, method=c.get("method"),
                       control_points=c.get("control_points"), smoothing=c.get("smoothing"))
        extra = tuple(c.get(key) for key in CONTOUR[kind] if key not in CONTOUR["1s"])    # width, offset / radius
        plain = kind in ("1s", "edge")                  # the curve itself, else a band or cylinder on it
        curve_class, cls = CONTOURS[kind if plain else "1s"], CONTOURS[kind]
        residual = dict(residual_flexibility=c.get("residual_flexibility"))

        def make(env):
            body = env.bodies[name]
            own = residual if plain else {}
            curve = (curve_class.along_line(body, start, direction, normal, nodes=nodes, **options, **own) if line
                     else curve_class(body, nodes, normal, **options, **own))
            return curve if plain else cls(curve, *extra, **residual)

        return make

    def _walk(self, c: Table, name, group, closed):
        """(ordered nodes, closed) of node group ``group`` of body ``name``, walked along the
        body's surface edges (:func:`contours.node_grid.node_path`); a given ``closed``
        must agree with the walk."""
        data = self.bodies[name].data
        if data.surface_triangles is None:
            c.fail("nodes", f"body {name!r} has no surface triangles in its body file, so node group {group!r} "
                            "cannot be ordered: give 'start' and 'direction' (the nodes on that line), or 'nodes' "
                            "as the ordered list of node indices")
        try:
            path, cycle = node_path(data.surface_triangles, data.node_groups[group], data.u0,
                                    f"node group {group!r}")
        except ModelError as exc:
            c.fail("nodes", f"{exc}; give 'start' and 'direction', or 'nodes' as the ordered list of node indices")
        if closed is not None and closed != cycle:
            shape = "a closed loop" if cycle else "an open line with two ends"
            c.fail("closed", f"'closed = {str(closed).lower()}' but node group {group!r} is {shape} of surface "
                             f"edges: omit 'closed' (it follows the group) or set it to {str(cycle).lower()}")
        return path, cycle

    def _node_matrix(self, c: Table, name):
        """A node-group name, or the node matrix O (rows of node indices, equal lengths >= 2)."""
        value = c.data.get("nodes")
        if isinstance(value, str) or value is None:
            return nodes_of(self.bodies, c, "nodes", name)
        n = self.bodies[name].data.n_nodes
        ok = (isinstance(value, list) and len(value) >= 2 and all(isinstance(row, list) for row in value)
              and len({len(row) for row in value}) == 1 and len(value[0]) >= 2
              and all(is_int(v) for row in value for v in row))
        if not ok:
            c.fail("nodes", "'nodes' must be a node-group name or the node matrix O: rows of equal length "
                            f"(>= 2 x 2) of 0-based node indices, got {describe(value)}")
        O = np.array(value, dtype=np.int64)
        if O.min() < 0 or O.max() >= n:
            c.fail("nodes", f"'nodes': node indices must lie in 0..{n - 1}")
        return O


def _pair(c: Table, key, kind):
    """One value or a pair [η, ξ] of integers (>= 1) or booleans."""
    value = c.data.get(key, c.schema[key].default)
    one = (lambda v: isinstance(v, bool)) if kind is bool else (lambda v: is_int(v) and v >= 1)
    if one(value):
        return value
    if isinstance(value, list) and len(value) == 2 and all(one(v) for v in value):
        return tuple(value)
    what = "true/false" if kind is bool else "an integer >= 1"
    c.fail(key, f"{key!r} must be {what} or a pair of them [eta, xi], got {describe(value)}")


def axes_with_normal(normal) -> np.ndarray:
    """A rotation matrix whose third column is the unit ``normal`` (the first column is
    perpendicular to it, built from the coordinate axis least aligned with it)."""
    z = normal / np.linalg.norm(normal)
    x = np.cross(np.eye(3)[int(np.argmin(np.abs(z)))], z)
    x /= np.linalg.norm(x)
    return np.column_stack((x, np.cross(z, x), z))

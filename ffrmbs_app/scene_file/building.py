"""Building a Scene from a parsed scene file: pass 1 checks every table against the
schema (:mod:`ffrmbs_app.scene_file.schema`) and collects one builder per entry; pass 2
(:meth:`SceneBuilder.build`) runs them on a new :class:`mbs.System`. The kinds come from
the library's registries (:data:`mbs.BODIES`, :data:`mbs.JOINTS`, :data:`mbs.LOADS`,
:data:`mbs.INTEGRATORS`, :data:`contours.CONTOURS`, :data:`contact.LAWS`,
:data:`contact.PAIR_KINEMATICS`)."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from ffrmbs.errors import InputFileError, ModelError
from ffrmbs_app.scene import Scene, name_fault
from ffrmbs_app.scenes.cache import cache_dir
from mbs import INTEGRATORS, LOADS, Joint, SpringDamper, System, Tabulated, read_force_file
from mbs.links.joints import AXIS_KINDS
from mbs.links.loads import WEIGHT_SUM_TOL
from preprocess.modes import clamped_dofs

from .bodies import BodyReader
from .contacts import ContactReader
from .frames import Env, FrameRef, body_of, frame_of, nodes_of
from .reading import Document
from .schema import (BODY_QUANTITIES, COMPONENTS, FLEXIBLE_QUANTITIES, FRAME, GROUND, JOINT, LOAD, OUTPUT,
                     QUANTITY_UNITS, SCENE, SPRING, TABULATED, TOP_LEVEL, option_keys)
from .tables import Table, describe, in_unit, run


class SceneBuilder:
    """Pass 1 (the constructor) checks the whole document and collects one builder per
    entry; pass 2 (:meth:`build`) runs the builders on a new System."""

    def __init__(self, doc: Document):
        self.doc = doc
        Table(doc, doc.data, (), "scene file", dict.fromkeys(TOP_LEVEL))     # rejects unknown top-level keys
        self.inputs: dict = {"scene file": str(doc.path)}
        self.steps: list = []               # (keypath, label, build(env)) after the bodies
        self.outputs: dict = {}             # name -> (keypath, label, make(env))
        self.units: dict = {}               # name -> unit of the output's quantity
        self.labels: dict = {}              # name -> what the output is ("beam node 19 displacement")
        self.settings = self._settings()
        self.bodies = BodyReader(doc, self.inputs).read(self._entries("body", "body"))
        self._links()
        self._loads()
        self.steps += ContactReader(doc, self.bodies).read(self._entries("contact", "contact"))
        self._outputs()

    def _entries(self, key, what):
        """The tables of the array of tables ``key`` as (index, data)."""
        value = self.doc.data.get(key, [])
        if not isinstance(value, list) or not all(isinstance(v, dict) for v in value):
            self.doc.fail((key,), f"'{key}' must be an array of tables: write each {what} as [[{key}]]")
        return list(enumerate(value))

    # --- [scene] ----------------------------------------------------------------------------------
    def _settings(self) -> dict:
        data = self.doc.data
        if "scene" not in data:
            self.doc.fail((), "missing required table 'scene' (write [scene] with t_end and dt)")
        if not isinstance(data["scene"], dict):
            self.doc.fail(("scene",), f"'scene' must be a table ([scene] with t_end and dt), "
                                      f"got {describe(data['scene'])}")
        s = Table(self.doc, data["scene"], ("scene",), "[scene]", SCENE)
        name = s.get("name", self.doc.path.stem)
        fault = name_fault(name)
        if fault:
            s.fail("name" if s.has("name") else None,
                   fault + ("" if s.has("name") else " (taken from the file name; set 'name')"))
        out = {key: s.get(key) for key in SCENE if key not in ("name", "options")}
        out["name"] = name
        out["options"] = self._options(s, out["integrator"])
        return out

    def _options(self, s: Table, integrator: str) -> dict:
        """The integrator's keyword options (schema: :func:`option_keys`), range-checked
        by constructing the integrator once."""
        keys = option_keys(integrator)
        o = s.table("options", f"options of integrator {integrator!r}", keys, {})
        if not isinstance(o, Table):
            return {}
        options = {key: o.get(key) for key in o.data}
        options = {key: tuple(v) if keys[key].type == "numbers" else v for key, v in options.items()}
        try:                            # the integrator checks its ranges
            INTEGRATORS[integrator](System(), **options)
        except ModelError as exc:
            named = [key for key in options if re.search(rf"\b{re.escape(key)}\b", str(exc))]
            o.fail(named[0] if named else None, str(exc))
        return options

    # --- links --------------------------------------------------------------------------------------
    def _frame_table(self, t: Table, key) -> FrameRef:
        return frame_of(self.bodies, t.table(key, f"{key!r}", FRAME))

    def _add(self, t: Table, build):
        self.steps.append((t.keypath, t.label, build))

    def _links(self):
        for i, data in self._entries("spring", "spring"):
            t = Table(self.doc, data, ("spring", i), f"spring #{i + 1}", SPRING)
            f1, f2 = self._frame_table(t, "frame1"), self._frame_table(t, "frame2")
            if f1.body == GROUND and f2.body == GROUND:
                t.fail("frame2", "both frames are on the ground: the spring would act on nothing")
            k, c, l0 = t.get("stiffness"), t.get("damping"), t.get("free_length")

            def build(env, f1=f1, f2=f2, k=k, c=c, l0=l0):
                env.system.add(SpringDamper(f1.resolve(env), f2.resolve(env), k, c, free_length=l0))

            self._add(t, build)
        for i, data in self._entries("joint", "joint"):
            t = Table(self.doc, data, ("joint", i), f"joint #{i + 1}", JOINT)
            kind = t.get("kind")
            f1, f2 = self._frame_table(t, "frame1"), self._frame_table(t, "frame2")
            if f1.same(f2):
                t.fail("frame2", "frame1 and frame2 are the same frame")
            if f1.body == GROUND and f2.body == GROUND:
                t.fail("frame2", "both frames are on the ground: the joint would constrain nothing")
            axis = None
            if kind in AXIS_KINDS:
                axis = t.get("axis")
                if not np.linalg.norm(axis) > 0:
                    t.fail("axis", "'axis' must be a nonzero direction")
            elif t.has("axis"):
                t.fail("axis", f"a {kind} joint takes no 'axis'")

            def build(env, kind=kind, f1=f1, f2=f2, axis=axis):
                env.system.add(Joint(f1.resolve(env), f2.resolve(env), kind, axis))       # kind: of mbs.JOINTS

            self._add(t, build)

    # --- loads ----------------------------------------------------------------------------------------
    def _time_function(self, t: Table, key):
        """A constant (3,) or a :class:`mbs.Tabulated` of 3-vectors."""
        unit = t.schema[key].unit
        if not isinstance(t.data.get(key), dict):
            return t.numbers(key, 3, unit=unit)
        table = t.table(key, f"{key!r} table", TABULATED)
        times = table.get("times")
        values = table.rows("values", None, f"an array of [x, y, z] rows{in_unit(unit)}")
        if len(values) != times.size:
            table.fail("values", f"{len(values)} rows of 'values' for {times.size} 'times'")
        kind, hold = table.get("kind"), table.get("hold_first")
        return table.model("times", lambda: Tabulated(times, values, kind, hold))

    def _loads(self):
        for i, data in self._entries("load", "load"):
            keypath = ("load", i)
            head = Table(self.doc, data, keypath, f"load #{i + 1}", None)
            kind = head.get("kind", spec=LOAD["force"]["kind"])
            t = Table(self.doc, data, keypath, f"load #{i + 1} ({kind})", LOAD[kind])
            cls = LOADS[kind]
            if kind in ("force", "torque"):
                frame = frame_of(self.bodies, t)
                if frame.body == GROUND:
                    t.fail("body", f"a {kind} on the ground does nothing: apply it to a body")
                value = self._time_function(t, kind)
                fixed = t.get("frame_fixed")

                def build(env, cls=cls, frame=frame, value=value, fixed=fixed):
                    env.system.add(cls(frame.resolve(env), value, fixed))

            elif kind == "distributed":
                name = body_of(self.bodies, t, kinds=("flexible",))
                nodes = nodes_of(self.bodies, t, "nodes", name)
                weights = t.get("weights")
                n = len(self.bodies[name].data.node_groups[nodes]) if isinstance(nodes, str) else nodes.size
                if weights is None:
                    weights = np.full(n, 1.0 / n)
                elif weights.size != n:
                    t.fail("weights", f"{weights.size} weights for {n} nodes")
                value = self._time_function(t, "force")
                fixed = t.get("frame_fixed")
                if not abs(weights.sum() - 1.0) <= WEIGHT_SUM_TOL:
                    t.fail("weights", f"the weights sum to {float(weights.sum())!r}, not 1")

                def build(env, cls=cls, name=name, nodes=nodes, weights=weights, value=value, fixed=fixed):
                    env.system.add(cls(env.bodies[name], nodes, weights, value, fixed))

            else:   # nodal
                build = self._nodal(t, cls)
            self._add(t, build)

    def _nodal(self, t: Table, cls):
        """build(env) of a "nodal" load: the force file is read now."""
        name = body_of(self.bodies, t, kinds=("flexible",))
        body_data = self.bodies[name].data
        file = t.get("file")
        scene_dir = self.doc.path.parent
        path = Path(file).expanduser()
        path = path if path.is_absolute() else scene_dir / path
        if not path.is_file():
            t.fail("file", f"force file {str(path)!r} not found (file {file!r}, relative to the scene "
                           f"file's directory {str(scene_dir)!r})")
        blocked = None
        if t.has("blocked"):
            nodes = nodes_of(self.bodies, t, "blocked", name)
            nodes = body_data.node_groups[nodes] if isinstance(nodes, str) else nodes
            blocked = clamped_dofs(3 * body_data.n_nodes, nodes)
        try:
            times, forces = read_force_file(path, body_data.n_nodes, blocked)
        except InputFileError as exc:
            raise InputFileError(exc.path, exc.line, f"{exc.fault} ({t.label} of scene file "
                                                     f"{self.doc.path})") from None
        self.inputs[f"{t.label} force file"] = str(path)
        fixed = t.get("frame_fixed")

        def build(env):
            env.system.add(cls(env.bodies[name], times, forces, fixed))

        return build

    # --- [outputs] ------------------------------------------------------------------------------------
    def _outputs(self):
        value = self.doc.data.get("outputs", {})
        if not isinstance(value, dict):
            self.doc.fail(("outputs",), f"'outputs' must be a table [outputs], got {describe(value)}")
        for name, spec in value.items():
            keypath, label = ("outputs", name), f"output {name!r}"
            if not isinstance(spec, dict):
                self.doc.fail(keypath, f"{label}: expected a table such as {{ body = \"...\", quantity = "
                                       f"\"position\" }}, got {describe(spec)}")
            t = Table(self.doc, spec, keypath, label, OUTPUT)
            quantity = t.get("quantity")
            body = body_of(self.bodies, t, kinds=("flexible", "rigid", "point_mass"))
            kind = self.bodies[body].kind
            if quantity in BODY_QUANTITIES:
                for key in ("node", "at", "point"):
                    if t.has(key):
                        t.fail(key, f"quantity {quantity!r} is the body's: it takes no {key!r}")
            if quantity in FLEXIBLE_QUANTITIES and kind != "flexible":
                t.fail("quantity", f"quantity {quantity!r} needs a flexible body; {body!r} is a {kind} body")
            if quantity == "displacement" and not (t.has("node") or t.has("at")):
                t.fail(None, "quantity 'displacement' needs the node: give 'node' or 'at'")
            frame = frame_of(self.bodies, t)
            component = None
            if t.has("component"):
                if quantity == "q_f":
                    t.fail("component", "quantity 'q_f' takes no 'component'")
                component = COMPONENTS.index(t.get("component"))
            self.outputs[name] = (keypath, label, _probe(frame, quantity, component))
            if quantity in QUANTITY_UNITS:
                self.units[name] = QUANTITY_UNITS[quantity]
            self.labels[name] = output_label(frame, quantity, t.get("component") if component is not None else None,
                                             at=t.get("at") if t.has("at") else None)

    # --- pass 2 ----------------------------------------------------------------------------------------
    def build(self) -> Scene:
        """The Scene: the bodies in file order, then springs, joints, loads and contacts."""
        settings, doc = self.settings, self.doc
        env = Env(System(gravity=settings["gravity"]))
        env.system.cache_dir = cache_dir()           # residual flexibility of contours, reused between runs
        for body in self.bodies.values():
            env.bodies[body.name] = run(doc, body.keypath, f"body {body.name!r}",
                                        lambda body=body: env.system.add(body.make()))
        for keypath, label, build in self.steps:
            run(doc, keypath, label, lambda: build(env))
        self._static_equilibrium(env)
        outputs = {name: run(doc, keypath, label, lambda make=make: make(env))
                   for name, (keypath, label, make) in self.outputs.items()}
        return run(doc, ("scene",), "[scene]", lambda: Scene(
            env.system, settings["t_end"], settings["dt"], settings["integrator"], settings["options"],
            settings["n_out"], outputs, settings["energies"], settings["plan"], settings["tolerance"],
            settings["name"], dict(self.inputs), settings["description"], units=dict(self.units),
            labels=dict(self.labels)))

    def _static_equilibrium(self, env: Env):
        """The bodies with initial = "static" put at rest in static equilibrium
        (:meth:`mbs.System.static_equilibrium`); a ModelError is reported at the
        'initial' key of the body it names (else of the first such body)."""
        static = [body for body in self.bodies.values() if body.static]
        if not static:
            return
        try:
            env.system.static_equilibrium(bodies=[body.name for body in static])
        except ModelError as exc:
            body = next((b for b in static if f"body {b.name!r}" in str(exc)), static[0])
            self.doc.fail(body.keypath + ("initial",), f"body {body.name!r}: initial = \"static\": {exc}")


def output_label(ref: FrameRef, quantity, component=None, at=None) -> str:
    """What an output is, in words: "beam node 19 displacement", "point mass velocity y",
    "bob point (0, 0, 0.1) m position", "beam modal coordinates q_f"; a node given by
    ``at`` [m] says so: "beam node 412 (nearest to (0.25, 0.05, 0.025) m) displacement"."""
    where = ref.body if ref.node is None else f"{ref.body} node {ref.node}"
    if at is not None:
        where += f" (nearest to ({', '.join(f'{x:g}' for x in at)}) m)"
    if ref.point is not None and quantity not in BODY_QUANTITIES:
        where += f" point ({', '.join(f'{x:g}' for x in ref.point)}) m"
    words = {"q_f": "modal coordinates q_f", "angular_velocity": "angular velocity"}.get(quantity, quantity)
    return " ".join([where, words] + ([component] if component else []))


def _probe(ref: FrameRef, quantity, component):
    """make(env) -> the output: a Frame (a position), or a callable (t, q, u) -> array."""
    def make(env):
        body = env.bodies[ref.body]
        frame = ref.resolve(env)
        if quantity == "position" and component is None:
            return frame
        pick = (lambda x: x) if component is None else (lambda x: x[component])
        if quantity == "position":
            return lambda t, q, u: pick(frame.position(q[body.q_slice], t))
        if quantity == "velocity":
            return lambda t, q, u: pick(frame.velocity(q[body.q_slice], u[body.u_slice], t))
        if quantity == "displacement":
            return lambda t, q, u: pick(frame.elastic_displacement(q[body.q_slice]))
        if quantity == "angular_velocity":
            return lambda t, q, u: pick(body.angular_velocity(q[body.q_slice], u[body.u_slice], t))
        return lambda t, q, u: body.elastic_coordinates(q[body.q_slice]).copy()
    return make

"""The ``[[body]]`` entries of a scene file: each checked against
:data:`~ffrmbs_app.scene_file.schema.BODY` and turned into a builder of its body, whose
class is the registered one (:data:`mbs.BODIES`). Body files are read once per file."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ffrmbs.errors import FfrmbsError, InputFileError
from ffrmbs_app.scenes import point_mass_beam, sliding_ball
from ffrmbs_app.scenes.cache import cached_body_path
from mbs import BODIES, PrescribedFrameMotion
from mbs.bodies.flexible_body import select_modes
from preprocess import read_body
from preprocess.bodyfiles import body_files

from .schema import BODY, BODY_HEAD, BUILTIN, FIXED_FRAME_REFUSES, GROUND, STATIC_REFUSES
from .tables import Table, describe, is_int

BUILTIN_BODIES = {"point_mass_beam": point_mass_beam, "point_mass_beam_tet10": point_mass_beam.TET10,
                  "sliding_ball": sliding_ball}


@dataclass
class BodyEntry:
    """A checked [[body]] entry. ``make()`` builds the body."""

    name: str
    kind: str
    keypath: tuple
    make: object
    data: object = None         # BodyData of a flexible body
    static: bool = False        # initial = "static": started in static equilibrium


class BodyReader:
    """Reads the [[body]] entries of one scene file (``doc``). ``inputs`` collects the
    body files read (label -> path)."""

    def __init__(self, doc, inputs: dict):
        self.doc, self.inputs = doc, inputs
        self._sources: dict = {}            # (resolved source, units) -> BodyData (read once)

    def read(self, entries) -> dict:
        """{name: BodyEntry} of the (index, table) ``entries``, in file order."""
        bodies: dict = {}
        if not entries:
            self.doc.fail(("body",), "no bodies: 'body' needs at least one [[body]] table")
        for i, data in entries:
            keypath = ("body", i)
            label = f"body {data['name']!r}" if isinstance(data.get("name"), str) else f"body #{i + 1}"
            head = Table(self.doc, data, keypath, label, None)     # the keys are checked once the kind is known
            name = head.get("name", spec=BODY_HEAD["name"])
            if name == GROUND:
                head.fail("name", f"the name {GROUND!r} is reserved for the inertial frame")
            if name in bodies:
                head.fail("name", f"a second body named {name!r} (body names must be unique)")
            kind = head.get("kind", spec=BODY_HEAD["kind"])
            t = Table(self.doc, data, keypath, label, BODY[kind])
            bodies[name] = getattr(self, "_" + kind)(t, keypath, name)
            bodies[name].static = self._static(t)
        return bodies

    @staticmethod
    def _static(t: Table) -> bool:
        """Whether the body starts in static equilibrium (``initial = "static"``), which
        computes its velocities and elastic coordinates: they must not be given."""
        if t.get("initial") != "static":
            return False
        for key in STATIC_REFUSES:
            if t.has(key):
                t.fail(key, f"{key!r} is computed by initial = \"static\" (the body starts at rest in static "
                            "equilibrium): remove it, or set initial = \"given\"")
        return True

    # --- flexible ---------------------------------------------------------------------------
    def _flexible(self, t: Table, keypath, name) -> BodyEntry:
        body_data = self._body_data(t, name)
        modes = t.data.get("modes")
        if modes is None:
            selection = None
        elif modes == "all":
            selection = body_data.n_modes
        elif is_int(modes):
            selection = modes
        elif isinstance(modes, list) and all(is_int(m) for m in modes):
            selection = list(modes)
        else:
            t.fail("modes", f"'modes' must be a number of modes, a list of 0-based mode indices or \"all\", "
                            f"got {describe(modes)}")
        n_modes = len(t.model("modes", lambda: select_modes(body_data.n_modes, selection)))
        frame = t.get("frame")
        rotation = t.get("rotation")
        if frame == "fixed":
            for key in FIXED_FRAME_REFUSES:
                if t.has(key):
                    t.fail(key, f"{key!r} applies to a free frame only (this body has frame = \"fixed\")")
        R = t.get("position")
        A = t.rotation("orientation")
        v, w = t.get("velocity"), t.get("angular_velocity")
        q_f = _modal(t, "q_f", n_modes)
        qd_f = _modal(t, "modal_velocities", n_modes)
        rayleigh = t.get("rayleigh")
        zeta = None
        if t.has("modal_damping"):
            zeta = (t.number("modal_damping", low=0.0) if not isinstance(t.data["modal_damping"], list)
                    else _modal(t, "modal_damping", n_modes, low=0.0))
        stiffening = t.get("geometric_stiffening")
        if stiffening and body_data.geometric_stiffness is None:
            t.fail("geometric_stiffening", "geometric_stiffening needs a body file with the geometric stiffness: "
                                           "preprocess it with --geometric-stiffness")

        def make():
            motion = "free"
            if frame == "fixed":
                motion = PrescribedFrameMotion.fixed(*(() if R is None and A is None else
                                                       ((0.0, 0.0, 0.0) if R is None else R, A)))
            body = BODIES["flexible"](body_data, modes=selection, frame=motion, rotation=rotation,
                                      rayleigh=None if rayleigh is None else tuple(rayleigh), modal_damping=zeta,
                                      name=name, geometric_stiffening=stiffening)
            if frame == "free":
                body.set_initial(R=R, A=A, v=v, omega=w)
            return body.set_initial(q_f=q_f, qdot_f=qd_f)

        return BodyEntry(name, "flexible", keypath, make, body_data)

    def _body_data(self, t: Table, name):
        """The BodyData of ``source`` (read once per file), its files added to inputs."""
        source = t.get("source")
        units = t.get("units")
        if source.startswith(BUILTIN):
            return self._builtin(t, name, source[len(BUILTIN):])
        if not source.strip():
            t.fail("source", "'source' is empty: give a body directory or .h5 file")
        path = Path(source).expanduser()
        scene_dir = self.doc.path.parent
        if not path.is_absolute():
            path = scene_dir / path
        if not path.exists():
            t.fail("source", f"body file {str(path)!r} not found (source {source!r}, relative to the "
                             f"scene file's directory {str(scene_dir)!r})")
        key = (str(path.resolve()), units)
        if key not in self._sources:
            try:
                self._sources[key] = read_body(path, units)
            except InputFileError as exc:
                raise InputFileError(exc.path, exc.line, f"{exc.fault} (body {name!r} of scene file "
                                                         f"{self.doc.path})") from None
            except FfrmbsError as exc:
                t.fail("source", f"cannot read body file {str(path)!r}: {exc}")
        files = body_files(path)
        for f in files:
            label = f"body {name!r}" if len(files) == 1 else f"body {name!r} {f.name}"
            self.inputs[label] = str(f)
        return self._sources[key]

    def _builtin(self, t: Table, name, which):
        """The BodyData of a built-in scene's beam (cached by :mod:`ffrmbs_app.scenes`)."""
        if which not in BUILTIN_BODIES:
            t.fail("source", f"unknown built-in body {BUILTIN + which!r} (built-in: "
                             f"{', '.join(BUILTIN + b for b in BUILTIN_BODIES)})")
        module = BUILTIN_BODIES[which]
        key = (BUILTIN + which, "si")
        if key not in self._sources:
            self._sources[key] = module.default_beam_data()
        h5 = cached_body_path(module.recipe())
        if h5.exists():
            self.inputs[f"body {name!r}"] = str(h5)
        return self._sources[key]

    # --- rigid, point mass ---------------------------------------------------------------------
    def _rigid(self, t: Table, keypath, name) -> BodyEntry:
        mass = t.get("mass")
        unit = t.schema["inertia"].unit
        if isinstance(t.data.get("inertia"), list) and t.data["inertia"] \
                and not isinstance(t.data["inertia"][0], list):
            inertia = np.diag(t.numbers("inertia", 3, unit=unit, low=0.0))
        else:
            inertia = t.matrix3("inertia", unit=unit)
        com = t.get("com")
        rotation = t.get("rotation")
        R = t.get("position")
        A = t.rotation("orientation")
        v, w = t.get("velocity"), t.get("angular_velocity")
        if not np.allclose(inertia, inertia.T):
            t.fail("inertia", "'inertia' must be symmetric")
        if np.linalg.eigvalsh(inertia).min() < 0:
            t.fail("inertia", "'inertia' must be positive semi-definite (principal values >= 0)")

        def make():
            return BODIES["rigid"](mass, inertia, com, rotation, name).set_initial(R=R, A=A, v=v, omega=w)

        return BodyEntry(name, "rigid", keypath, make)

    def _point_mass(self, t: Table, keypath, name) -> BodyEntry:
        mass, position, velocity = t.get("mass"), t.get("position"), t.get("velocity")

        def make():
            return BODIES["point_mass"](mass, position=position, velocity=velocity, name=name)

        return BodyEntry(name, "point_mass", keypath, make)


def _modal(t: Table, key, n_modes, low=None):
    """One value per selected mode, or None when absent."""
    array = t.numbers(key, None, None, unit=t.schema[key].unit, low=low)
    if array is not None and array.size != n_modes:
        t.fail(key, f"{key!r} needs one value per selected mode ({n_modes}), got {array.size}")
    return array

"""Scene files: one simulation job written in TOML, read into a
:class:`ffrmbs_app.scene.Scene`. The keys, kinds, units, defaults and bounds are
documented in :mod:`ffrmbs_app.scene_file.schema`.

* :mod:`.reading` — TOML text -> dict (tomllib) and the line of every key path.
* :mod:`.overrides` — ``--set KEY=VALUE``: values set in the parsed file before its checks.
* :mod:`.schema` — the schema: documentation and data (:class:`~.schema.Key` per key).
* :mod:`.tables` — checked access to a table against its schema; faults with file, line and key.
* :mod:`.frames`, :mod:`.bodies`, :mod:`.contacts`, :mod:`.building` — checked tables ->
  builders -> the System, its bodies, links, loads, contacts and outputs, through the
  library's registries.
"""

from __future__ import annotations

from ffrmbs_app.scene import Scene

from .building import SceneBuilder
from .overrides import apply_overrides
from .reading import read_toml


def read_scene(path, overrides=()) -> Scene:
    """The :class:`~ffrmbs_app.scene.Scene` of the TOML scene file ``path``
    (schema: :mod:`ffrmbs_app.scene_file.schema`), with the values of ``overrides``
    (``"KEY=VALUE"`` texts, :mod:`.overrides`) set in it before anything is checked.

    The whole file is checked first: its syntax, every key, its type and range, the
    body names, the node and mode indices, and the body and force files. Only then is
    the System built. Every fault raises :class:`~ffrmbs.errors.InputFileError` naming
    the file and the line, or the body or force file at fault. ``Scene.inputs`` lists
    the scene file and each body and force file read, as label -> path.
    """
    document = read_toml(path)
    document.overridden = apply_overrides(document.path, document.data, overrides)
    scene = SceneBuilder(document).build()
    scene.overrides = tuple(overrides)
    return scene


__all__ = ["read_scene"]

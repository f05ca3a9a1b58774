"""A scene from a file: a TOML scene file (:mod:`ffrmbs_app.scene_file`) or a Python
model script. :func:`load_scene` dispatches on the file's suffix.

A model script is a Python file defining ``scene() -> Scene``
(:class:`ffrmbs_app.scene.Scene`); ``ffrmbs run model.py`` calls it.
"""

from __future__ import annotations

import runpy
from pathlib import Path

from ffrmbs.errors import InputFileError, ModelError
from ffrmbs_app.scene import Scene
from ffrmbs_app.scene_file import read_scene
from preprocess.inputfiles import regular_file


def load_scene(path, overrides=()) -> Scene:
    """The scene of a TOML scene file (``.toml``) or a Python model script (``.py``
    defining ``scene()``); a path that is missing or not a regular file (a directory, a
    FIFO, ...) is an InputFileError saying so, and is never opened. ``overrides``:
    ``"KEY=VALUE"`` texts set in a scene file (:mod:`ffrmbs_app.scene_file.overrides`);
    a model script takes none."""
    path = regular_file(path)
    if path.suffix == ".toml":
        return read_scene(path, overrides)
    if path.suffix == ".py":
        if overrides:
            raise InputFileError(path, None, "--set sets values of a scene file (.toml); a model script "
                                             "takes its values from its own code")
        return _from_script(path)
    raise InputFileError(path, None, "a scene is a .toml scene file or a .py model script")


def _from_script(path: Path) -> Scene:
    namespace = runpy.run_path(str(path), run_name="ffrmbs_model")
    build = namespace.get("scene")
    if not callable(build):
        raise InputFileError(path, None, "a model script must define a function scene() returning an ffrmbs Scene")
    try:
        scene = build()
    except ModelError as exc:
        raise ModelError(f"{path}: scene(): {exc}") from None
    if not isinstance(scene, Scene):
        raise InputFileError(path, None, f"scene() returned {type(scene).__name__}, not an ffrmbs_app.scene.Scene")
    scene.inputs.setdefault("model script", str(path))
    return scene

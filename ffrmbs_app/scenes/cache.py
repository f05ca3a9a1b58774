"""Preprocessed body data of the built-in scenes, made once and cached on disk.

Entries live in ``$FFRMBS_CACHE`` or ``~/.cache/ffrmbs``, one directory per scene and
hash of its recipe (geometry, mesh, material, modes, version), so a changed recipe gets
a new entry and an old one is never read by mistake. Writing goes through
:func:`preprocess.write_body`, which leaves no half-written file; an entry is its
``body.h5`` alone (the thesis's text files are for bodies a user writes).
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

from ffrmbs.caches import cache_dir


def cached_body_path(recipe: dict) -> Path:
    """The ``body.h5`` file of the cache entry of ``recipe`` (a JSON-able dict with a
    ``"scene"`` name), whether it exists yet or not."""
    key = hashlib.sha256(json.dumps(recipe, sort_keys=True).encode()).hexdigest()[:12]
    return cache_dir() / f"{recipe['scene']}-{key}" / "body.h5"


def cached_body(recipe: dict, build, log=None):
    """The body data for ``recipe`` (a JSON-able dict with a ``"scene"`` name): read from
    the cache, or made by ``build()`` (returning BodyData), written and read back."""
    from preprocess import read_body, write_body

    h5 = cached_body_path(recipe)
    if not h5.exists():
        if log:
            log(f"preprocessing the {recipe['scene']} body (once; cached in {h5.parent})")
        write_body(h5.parent, build(), text_files=False)
    return read_body(h5)

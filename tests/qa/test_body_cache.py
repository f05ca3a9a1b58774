"""The tests' body cache (tests/support/body_cache.py): a body read from it is bit for bit
the body ``build_body`` makes, each recipe is built once, warnings come back on every
read, and a call that watches the building builds."""

import warnings

import numpy as np
import pytest
import scipy.sparse as sp

from body_cache import BodyCache
from preprocess import Material, box, pipeline

STEEL = Material(7850.0, 2.1e11, 0.3)


def same(a, b) -> bool:
    """Whether two values are equal bit for bit: arrays with their dtype, CSR matrices
    with their index order, containers item by item."""
    if sp.issparse(a) or sp.issparse(b):
        return (type(a) is type(b) and a.shape == b.shape
                and all(same(getattr(a, n), getattr(b, n)) for n in ("data", "indices", "indptr")))
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        return type(a) is type(b) and a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()
    if isinstance(a, dict):
        return type(a) is type(b) and list(a) == list(b) and all(same(a[k], b[k]) for k in a)
    return type(a) is type(b) and a == b


@pytest.fixture
def mesh():
    return box(0.2, 0.05, 0.05, None, order=2, divisions=(4, 1, 1))


@pytest.mark.parametrize("options", [dict(clamp="x0"), dict(geometric_stiffness=True, mass="consistent")])
def test_a_read_body_is_the_built_body_bit_for_bit(tmp_path, mesh, options):
    fresh = pipeline.build_body.build_body(mesh, STEEL, 6, **options)
    cache = BodyCache(tmp_path, pipeline.build_body.build_body)
    first, second = cache(mesh, STEEL, 6, **options), cache(mesh, STEEL, 6, **options)
    assert (cache.built, cache.read) == (1, 1)
    for field in fresh.__dataclass_fields__:
        assert same(getattr(first, field), getattr(fresh, field)), field
        assert same(getattr(second, field), getattr(fresh, field)), field


def test_each_recipe_has_its_entry(tmp_path, mesh):
    cache = BodyCache(tmp_path, pipeline.build_body.build_body)
    bodies = [cache(mesh, STEEL, 4), cache(mesh, STEEL, 5), cache(mesh, STEEL, 4, clamp="x0"),
              cache(mesh, Material(7850.0, 2.0e11, 0.3), 4), cache(mesh, STEEL, 4)]
    assert (cache.built, cache.read) == (4, 1)
    assert [b.n_modes for b in bodies] == [4, 5, 4, 4, 4]
    assert bodies[2].params["clamp"] == "x0" and bodies[3].material["young"] == 2.0e11
    assert sorted(p.suffix for p in tmp_path.iterdir()) == [".lock"] * 4 + [".pkl"] * 4   # no temporaries left


def test_warnings_of_the_build_come_back_on_every_read(tmp_path, mesh):
    def warning_build(*args, **kwargs):
        warnings.warn("mode 3 is poorly resolved", UserWarning)
        return pipeline.build_body.build_body(*args, **kwargs)

    cache = BodyCache(tmp_path, warning_build)
    for _ in range(2):
        with pytest.warns(UserWarning, match="mode 3 is poorly resolved"):
            cache(mesh, STEEL, 4)
    assert (cache.built, cache.read) == (1, 1)


def test_a_watched_build_builds_every_time(tmp_path, mesh):
    cache = BodyCache(tmp_path, pipeline.build_body.build_body)
    for _ in range(2):
        stages = []
        cache(mesh, STEEL, 4, progress=stages.append)
        assert stages[:2] == ["assembling K", "computing modes"]
    assert (cache.built, cache.read) == (0, 0) and not list(tmp_path.iterdir())

"""Body files: the thesis's text files (Listings 4.1-4.5) and the HDF5 body file."""

from __future__ import annotations

import math
from pathlib import Path

import h5py
import numpy as np
import pytest
import scipy.sparse as sp

from ffrmbs.errors import InputFileError, ModelError
from preprocess import bodyfiles
from preprocess.body import BodyData
from preprocess.bodyfiles import TEXT_FILES, read_body, write_body
from preprocess.hdf5file import read_hdf5, write_hdf5
from preprocess.textfiles import (parse_masses, parse_mode_shapes, parse_stiffness, parse_u0,
                                  read_text_body, write_text_body)
from preprocess.units import UNIT_SYSTEMS, unit_system

import paths

LISTINGS = paths.FIXTURES / "thesis_listings"


def random_body(n_nodes=5, n_modes=3, seed=0, mass_normalized=True) -> BodyData:
    """A small random body: SPD sparse K (3N x 3N), positive masses, random Φ."""
    rng = np.random.default_rng(seed)
    n = 3 * n_nodes
    a = sp.random(n, n, density=0.3, random_state=rng)
    k = (a + a.T + sp.identity(n) * n).tocsr() * 1e5
    masses = rng.uniform(0.1, 2.0, n_nodes)
    phi = rng.standard_normal((n, n_modes))
    if mass_normalized:
        m3 = np.repeat(masses, 3)
        q, _ = np.linalg.qr(np.sqrt(m3)[:, None] * phi)
        phi = q / np.sqrt(m3)[:, None]
    return BodyData(u0=rng.uniform(-1, 1, (n_nodes, 3)) * 0.1, phi=phi, masses=masses,
                    stiffness=k)


def full_body(**kw) -> BodyData:
    """A random body with everything HDF5 keeps beyond the text files."""
    body = random_body(**kw)
    body.eigenvalues = np.linspace(1e3, 5e4, body.n_modes)
    body.node_groups = {"clamp": np.array([0, 2], dtype=np.int64),
                        "load": np.array([4], dtype=np.int64), "none": np.zeros(0, np.int64)}
    body.surface_triangles = np.array([[0, 1, 2], [1, 3, 4]], dtype=np.int64)
    body.material = {"density": 7850.0, "young": 2.1e11, "poisson": 0.3}
    body.params = {"mesh_size": 0.01, "modes": 3, "nested": {"a": [1, 2]}}
    return body


def assert_same(a: BodyData, b: BodyData, extras=True):
    """Bitwise equality of the data (and of the HDF5-only extras if ``extras``)."""
    assert np.array_equal(a.u0, b.u0)
    assert np.array_equal(a.phi, b.phi)
    assert np.array_equal(a.masses, b.masses)
    assert np.array_equal(a.stiffness.toarray(), b.stiffness.toarray())
    if extras:
        assert (a.eigenvalues is None) == (b.eigenvalues is None)
        if a.eigenvalues is not None:
            assert np.array_equal(a.eigenvalues, b.eigenvalues)
        assert a.node_groups.keys() == b.node_groups.keys()
        for name in a.node_groups:
            assert np.array_equal(a.node_groups[name], b.node_groups[name])
        assert np.array_equal(a.surface_triangles, b.surface_triangles)
        assert a.material == b.material
        assert a.params == b.params


def write(path: Path, text: str) -> Path:
    path.write_text(text)
    return path


# --- the thesis's listings -----------------------------------------------------------

def test_listing_4_1_u0():
    u0 = parse_u0(LISTINGS / "u0.dat")
    assert u0.shape == (7, 3)
    assert np.array_equal(u0[0], [105, 10, 5.13000011])
    assert np.array_equal(u0[6], [95, 5, 14.8699999])


def test_listing_4_2_mode_shapes():
    phi = parse_mode_shapes(LISTINGS / "modeShapeMatrix.dat")
    assert phi.shape == (12, 3)
    assert np.array_equal(phi[0], [-3.1822e-02, 1.4396e-02, -7.9055e-02])
    assert not phi[3:9].any()
    assert np.array_equal(phi[10], [0.9994, 2.1436e-11, 1.1513e-10])
    assert np.array_equal(phi[11], [6.5417e-11, 0.5740, -0.3073])


def test_listing_4_3_masses():
    m = parse_masses(LISTINGS / "mij.dat")
    assert m.shape == (7,)
    assert m[0] == 2.393118773885549e-07 and m[6] == 7.173324325081246e-07


def test_listing_4_5_stiffness_lower_triangle_mirrored():
    k = parse_stiffness(LISTINGS / "stiffnessMatrix.dat")
    assert k.shape == (126, 126)  # 42 nodes inferred from the largest index
    assert k[0, 0] == 2.722094366664650e+05
    assert k[2, 0] == k[0, 2] == -1.242331718149038e+05
    assert k[114, 0] == k[0, 114] == 1.674319066952746e+05
    assert k[116, 0] == k[0, 116] == 2.484663436298076e+04
    assert k[123, 0] == 8.691092988626353e+04 and k[124, 0] == -1.229206703004807e+04
    assert k.nnz == 11
    assert parse_stiffness(LISTINGS / "stiffnessMatrix.dat", n_dof=180).shape == (180, 180)


# --- round trips -----------------------------------------------------------------------

def test_text_hdf5_text_round_trip_is_bitwise(tmp_path):
    body = random_body()
    write_text_body(tmp_path / "a", body)
    from_text = read_text_body(tmp_path / "a")
    assert_same(body, from_text, extras=False)
    write_hdf5(tmp_path / "b.h5", from_text)
    write_text_body(tmp_path / "c", read_hdf5(tmp_path / "b.h5"))
    for name in TEXT_FILES:
        assert (tmp_path / "a" / name).read_bytes() == (tmp_path / "c" / name).read_bytes()


def test_hdf5_text_hdf5_round_trip_is_bitwise(tmp_path):
    body = full_body()
    write_hdf5(tmp_path / "a.h5", body)
    from_h5 = read_hdf5(tmp_path / "a.h5")
    assert_same(body, from_h5)
    write_text_body(tmp_path / "t", from_h5)
    from_text = read_text_body(tmp_path / "t")
    assert_same(body, from_text, extras=False)
    write_hdf5(tmp_path / "b.h5", from_text)
    assert_same(from_text, read_hdf5(tmp_path / "b.h5"))


def test_text_file_layout(tmp_path):
    write_text_body(tmp_path, random_body(n_nodes=2, n_modes=2))
    u0 = (tmp_path / "u0.dat").read_text().splitlines()
    assert len(u0) == 2 and u0[1].endswith("\t% node: 2") and u0[0].count("\t") == 3
    modes = (tmp_path / "modeShapeMatrix.dat").read_text().splitlines()
    assert len(modes) == 6 and modes[4].endswith("\t% node: 2, DOF: 2")
    assert (tmp_path / "mij.dat").read_text().splitlines()[0].endswith("\t% node: 1")
    k_lines = (tmp_path / "stiffnessMatrix.dat").read_text().splitlines()
    entries = [line.split(", ") for line in k_lines]
    index = [(3 * int(a.split(",")[0]) + int(a.split(",")[1]) - 4,
              3 * int(c.split(",")[0]) + int(c.split(",")[1]) - 4) for a, c, _ in entries]
    assert all(r >= c for r, c in index)                      # lower triangle
    assert index == sorted(index, key=lambda rc: (rc[1], rc[0]))  # column by column


def test_write_rejects_non_symmetric_stiffness(tmp_path):
    body = random_body()
    body.stiffness = (body.stiffness + sp.csr_matrix(([1e3], ([0], [1])), shape=(15, 15))).tocsr()
    with pytest.raises(ModelError, match="not symmetric"):
        write_text_body(tmp_path, body)


def test_upper_and_full_storage(tmp_path):
    body = random_body()
    k = body.stiffness
    write_text_body(tmp_path, body)
    lines = (tmp_path / "stiffnessMatrix.dat").read_text().splitlines()
    swapped = [", ".join([c, a, v]) for a, c, v in (line.split(", ") for line in lines)]
    upper = write(tmp_path / "upper.dat", "\n".join(swapped))
    assert np.array_equal(parse_stiffness(upper, 15).toarray(), k.toarray())
    mirrored = [s for s, line in zip(swapped, lines) if s != line]
    full = write(tmp_path / "full.dat", "\n".join(lines + mirrored))
    assert np.array_equal(parse_stiffness(full, 15).toarray(), k.toarray())


# --- units ---------------------------------------------------------------------------

def test_unit_systems():
    mm = unit_system("si-mm")
    assert (mm.length, mm.mass, mm.stiffness, mm.density, mm.stress) == (1e-3, 1e3, 1e3, 1e12, 1e6)
    assert unit_system("si").length == 1.0
    with pytest.raises(ModelError, match="si, si-mm"):
        unit_system("imperial")
    assert set(UNIT_SYSTEMS) == {"si", "si-mm"}


def mm_body_files(directory: Path, normalized: bool) -> np.ndarray:
    """Two nodes in mm, t, N/mm; returns Φ as written."""
    directory.mkdir()
    write(directory / "u0.dat", "100 0 0\n0 200 5\n")
    write(directory / "mij.dat", "2e-3\n4e-3\n")
    write(directory / "stiffnessMatrix.dat",
          "".join(f"{i // 3 + 1},{i % 3 + 1}, {i // 3 + 1},{i % 3 + 1}, 1000\n" for i in range(6)))
    m3 = np.repeat([2e-3, 4e-3], 3)
    phi = np.zeros((6, 2))
    phi[0, 0], phi[4, 1] = 1.0, 1.0
    if normalized:
        phi /= np.sqrt(m3 @ phi**2)
    write(directory / "modeShapeMatrix.dat", "".join(f"{a!r} {b!r}\n" for a, b in phi.tolist()))
    return phi


def test_si_mm_reading_converts_and_rescales_mass_normalized_modes(tmp_path):
    phi_file = mm_body_files(tmp_path / "b", normalized=True)
    body = read_text_body(tmp_path / "b", units="si-mm")
    assert np.allclose(body.u0, [[0.1, 0, 0], [0, 0.2, 0.005]], rtol=1e-15)
    assert np.allclose(body.masses, [2.0, 4.0], rtol=1e-15)
    assert np.allclose(body.stiffness.diagonal(), 1e6, rtol=1e-15)
    assert np.allclose(body.phi, phi_file / math.sqrt(1000), rtol=1e-15)
    gram = body.phi.T @ (np.repeat(body.masses, 3)[:, None] * body.phi)
    assert np.allclose(gram, np.eye(2), atol=1e-12)
    assert np.allclose(read_body(tmp_path / "b", units="si-mm").phi, body.phi, rtol=0)


def test_si_mm_keeps_displacement_normalized_modes(tmp_path):
    phi_file = mm_body_files(tmp_path / "b", normalized=False)
    assert np.array_equal(read_text_body(tmp_path / "b", units="si-mm").phi, phi_file)


@pytest.mark.parametrize("normalized", [True, False])
def test_si_mm_writing_inverts_reading(tmp_path, normalized):
    body = random_body(mass_normalized=normalized)
    write_text_body(tmp_path, body, units="si-mm")
    assert np.allclose(parse_u0(tmp_path / "u0.dat"), body.u0 * 1e3, rtol=1e-15)
    assert np.allclose(parse_masses(tmp_path / "mij.dat"), body.masses * 1e-3, rtol=1e-15)
    back = read_text_body(tmp_path, units="si-mm")
    assert np.allclose(back.u0, body.u0, rtol=1e-14)
    assert np.allclose(back.masses, body.masses, rtol=1e-14)
    assert np.allclose(back.phi, body.phi, rtol=1e-14)
    assert np.allclose(back.stiffness.toarray(), body.stiffness.toarray(), rtol=1e-14)


# --- tolerant reading ---------------------------------------------------------------------

def test_tolerant_reading(tmp_path):
    u0 = write(tmp_path / "u0.dat", "# header\n\n% another\n1.0D+02,\t2.5d-1  3E0 # c\n"
                                    "  4, 5 ,6\t% node: 2\r\n\n")
    assert np.array_equal(parse_u0(u0), [[100.0, 0.25, 3.0], [4, 5, 6]])
    m = write(tmp_path / "mij.dat", "1.0d-3 % node: 1\n.5\n+2.\n1.5-100\n")
    assert np.array_equal(parse_masses(m), [1e-3, 0.5, 2.0, 1.5e-100])
    k = write(tmp_path / "k.dat", "1 1 1 1 2.0D+05\n% c\n2\t1,1,1\t-1d3\n2,1 2,1 3.0E+05 # x\n")
    assert np.array_equal(parse_stiffness(k).toarray()[:4, :4],
                          [[2e5, 0, 0, -1e3], [0, 0, 0, 0], [0, 0, 0, 0], [-1e3, 0, 0, 3e5]])


# --- faults ---------------------------------------------------------------------------------

GOOD = {
    "u0.dat": "0 0 0\n1 0 0\n",
    "mij.dat": "1.0\n2.0\n",
    "modeShapeMatrix.dat": "1 0\n0 1\n0 0\n0 0\n0 0\n0 0\n",
    "stiffnessMatrix.dat": "1,1, 1,1, 10\n2,1, 1,1, -5\n2,1, 2,1, 10\n",
}

BAD = [  # (file, content, line, keyword)
    ("u0.dat", "0 0 0\n1 0\n", 2, "columns"),
    ("u0.dat", "0 0 0\n1 0 x\n", 2, "parse"),
    ("u0.dat", "0 0 0\n\n1 0 nan\n", 3, "non-finite"),
    ("u0.dat", "% only a comment\n\n", None, "no data"),
    ("mij.dat", "1.0 2.0\n2.0\n", 1, "columns"),
    ("mij.dat", "1.0\n-2.0\n", 2, "non-positive"),
    ("mij.dat", "1.0\n0\n", 2, "non-positive"),
    ("mij.dat", "1.0\ninf\n", 2, "non-finite"),
    ("mij.dat", "1.0\n2.0\n3.0\n", None, "node count"),
    ("mij.dat", "", None, "no data"),
    ("modeShapeMatrix.dat", "1 0\n0 1\n0\n0 0\n0 0\n0 0\n", 3, "columns"),
    ("modeShapeMatrix.dat", "1 0\n0 1\n0 0\n0 0\n", None, "4 mode-shape rows"),
    ("modeShapeMatrix.dat", "1 0\n0 1\n0 1.0e999\n0 0\n0 0\n0 0\n", 3, "non-finite"),
    ("stiffnessMatrix.dat", "1,1, 1,1, 10\n2,1, 1,1\n", 2, "columns"),
    ("stiffnessMatrix.dat", "1,1, 1,1, 10\n3,1, 1,1, -5\n", 2, "node index 3"),
    ("stiffnessMatrix.dat", "1,1, 1,1, 10\n0,1, 1,1, -5\n", 2, "node index 0"),
    ("stiffnessMatrix.dat", "1,1, 1,1, 10\n2,4, 1,1, -5\n", 2, "DOF index 4"),
    ("stiffnessMatrix.dat", "1,1, 1,1, 10\n2,1, 1,0, -5\n", 2, "DOF index 0"),
    ("stiffnessMatrix.dat", "1,1, 1,1, 10\n2,x, 1,1, -5\n", 2, "parse"),
    ("stiffnessMatrix.dat", "1,1, 1,1, 10\n2,1.5, 1,1, -5\n", 2, "whole number"),
    ("stiffnessMatrix.dat", "1,1, 1,1, 10\n2,1, 1,1, -5\n% c\n2,1, 1,1, -5\n", 4, "duplicate"),
    ("stiffnessMatrix.dat", "1,1, 1,1, 10\n2,1, 1,1, -5\n1,1, 2,1, -6\n", 3, "non-symmetric"),
    ("stiffnessMatrix.dat", "1,1, 1,1, 10\n2,1, 1,1, 1e4000\n", 2, "non-finite"),
    ("stiffnessMatrix.dat", "\n\n", None, "no data"),
]


@pytest.mark.parametrize("name, content, line, keyword", BAD)
def test_bad_text_input(tmp_path, name, content, line, keyword):
    for file, text in {**GOOD, name: content}.items():
        write(tmp_path / file, text)
    with pytest.raises(InputFileError) as info:
        read_text_body(tmp_path)
    err = info.value
    assert err.line == line and Path(err.path).name == name
    assert name in str(err) and keyword in str(err)
    assert (f"line {line}" in str(err)) == (line is not None)


def test_good_text_input_and_missing_file(tmp_path):
    for file, text in GOOD.items():
        write(tmp_path / file, text)
    body = read_text_body(tmp_path)
    assert body.stiffness[0, 3] == body.stiffness[3, 0] == -5
    (tmp_path / "mij.dat").unlink()
    with pytest.raises(InputFileError, match="mij.dat: file not found") as info:
        read_text_body(tmp_path)
    assert info.value.line is None


def test_symmetric_within_tolerance_is_accepted(tmp_path):
    k = write(tmp_path / "k.dat", "1,1, 1,1, 1e6\n2,1, 1,1, -5\n1,1, 2,1, -5.0000001\n")
    assert parse_stiffness(k, 6)[0, 3] == parse_stiffness(k, 6)[3, 0] == -5


# --- HDF5 faults ----------------------------------------------------------------------------

def corrupt(path: Path, action):
    write_hdf5(path, full_body())
    with h5py.File(path, "a") as f:
        action(f)
    return path


def _replace(name, value):
    def action(f):
        del f[name]
        f[name] = value
    return action


HDF5_BAD = [
    (lambda f: f.__delitem__("u0"), "'u0'"),
    (lambda f: f.__delitem__("stiffness/indptr"), "'stiffness/indptr'"),
    (lambda f: f.__delitem__("stiffness"), "'stiffness'"),
    (_replace("u0", np.zeros((5, 2))), "'u0'"),
    (_replace("phi", np.zeros((14, 3))), "'phi'"),
    (_replace("masses", np.array([1, 1, np.nan, 1, 1])), "NaN"),
    (_replace("masses", -np.ones(5)), "non-positive"),
    (_replace("eigenvalues", np.ones(4)), "'eigenvalues'"),
    (_replace("node_groups/clamp", np.array([0, 7])), "'node_groups/clamp'"),
    (_replace("surface/triangles", np.zeros((2, 4), np.int64)), "3 or 6 columns"),
    (_replace("stiffness/indices", np.full(0, 0)), "CSR"),
    (lambda f: f.attrs.__setitem__("format", "other"), "format"),
    (lambda f: f.attrs.__setitem__("format_version", 2), "format_version"),
    (lambda f: f.attrs.__setitem__("units", "si-mm"), "units"),
    (lambda f: f.attrs.__setitem__("params", "{bad json"), "params"),
]


@pytest.mark.parametrize("action, keyword", HDF5_BAD)
def test_bad_hdf5(tmp_path, action, keyword):
    path = corrupt(tmp_path / "b.h5", action)
    with pytest.raises(InputFileError) as info:
        read_hdf5(path)
    assert info.value.line is None and "b.h5" in str(info.value) and keyword in str(info.value)


def test_non_hdf5_and_missing_files(tmp_path):
    with pytest.raises(InputFileError, match="not an HDF5 file"):
        read_hdf5(write(tmp_path / "x.h5", "hello"))
    with pytest.raises(InputFileError, match="file not found"):
        read_hdf5(tmp_path / "none.h5")


# --- read_body / write_body -----------------------------------------------------------------

def test_read_body_dispatch(tmp_path):
    body = full_body()
    write_hdf5(tmp_path / "x.hdf5", body)
    assert_same(body, read_body(tmp_path / "x.hdf5"))
    (tmp_path / "h").mkdir()
    write_hdf5(tmp_path / "h" / "body.h5", body)
    assert_same(body, read_body(tmp_path / "h"))
    write_body(tmp_path / "both", body)
    assert_same(body, read_body(tmp_path / "both"))     # body.h5 first: node groups, surface, ...
    (tmp_path / "both" / "body.h5").unlink()
    assert_same(body, read_body(tmp_path / "both"), extras=False)  # else the text files
    with pytest.raises(InputFileError, match="no body files"):
        read_body(tmp_path / "both" / "..")
    with pytest.raises(InputFileError, match="not a body directory"):
        read_body(tmp_path / "both" / "u0.dat")
    with pytest.raises(InputFileError, match="not found"):
        read_body(tmp_path / "nowhere")
    with pytest.raises(ModelError):
        read_body(tmp_path / "both", units="cgs")


def test_write_body_writes_all_files_and_no_temporaries(tmp_path):
    body = full_body()
    write_body(tmp_path / "new" / "dir", body, units="si-mm")
    directory = tmp_path / "new" / "dir"
    assert sorted(p.name for p in directory.iterdir()) == sorted([*TEXT_FILES, "body.h5"])
    assert_same(body, read_hdf5(directory / "body.h5"))
    assert np.allclose(read_text_body(directory, units="si-mm").u0, body.u0, rtol=1e-15)


def test_write_body_without_text_files_leaves_body_h5_alone(tmp_path):
    """text_files=False (the built-in scenes' cache): body.h5 only, the text files of an
    earlier body in the directory removed, and the body read back whole."""
    write_body(tmp_path, random_body(seed=1))
    body = full_body()
    write_body(tmp_path, body, text_files=False)
    assert [p.name for p in tmp_path.iterdir()] == ["body.h5"]
    assert_same(body, read_body(tmp_path))


def test_the_scene_cache_writes_no_text_files(tmp_path, monkeypatch):
    """A built-in scene's cache entry is its body.h5 alone: nothing reads the text files
    there, and formatting them cost 1.7 s of the default beam's first run."""
    from ffrmbs_app.scenes.cache import cached_body

    monkeypatch.setenv("FFRMBS_CACHE", str(tmp_path))
    body = full_body()
    assert_same(body, cached_body({"scene": "s", "n": 1}, lambda: body))
    assert [p.name for p in tmp_path.glob("s-*/*")] == ["body.h5"]


def test_write_body_failure_leaves_nothing_half_written(tmp_path, monkeypatch):
    old = random_body(seed=1)
    write_body(tmp_path, old)
    before = {p.name: p.read_bytes() for p in tmp_path.iterdir()}

    def broken(path, body):
        Path(path).write_bytes(b"partial")
        raise OSError("disk full")

    monkeypatch.setattr(bodyfiles, "write_hdf5", broken)
    with pytest.raises(OSError, match="disk full"):
        write_body(tmp_path, random_body(seed=2))
    assert {p.name: p.read_bytes() for p in tmp_path.iterdir()} == before
    with pytest.raises(OSError):
        write_body(tmp_path / "fresh", old)
    assert list((tmp_path / "fresh").iterdir()) == []


def test_node_at_finds_a_grid_node_and_names_the_miss(thesis_beam_data):
    from ffrmbs.errors import ModelError

    j = thesis_beam_data.node_at((0.25, 0.05, 0.025))       # the thesis's node 19 on the 10 x 4 x 4 grid
    assert np.allclose(thesis_beam_data.u0[j], (0.25, 0.05, 0.025), atol=1e-12)
    with pytest.raises(ModelError, match="nearest 0.001"):
        thesis_beam_data.node_at((0.25, 0.05, 0.026))

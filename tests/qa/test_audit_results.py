"""Results that a new user and a fault audit can trust (issue 18, findings 1, 3, 11, 14, 19):
ParaView export of tet4 and tet10 bodies, the README's plot command on the default scene,
a full disk, kill -9 at any moment, units on every dataset.

Oracles: deformed positions computed here from the body data and the quaternion formula;
file bytes before and after; the errno's own text; the file read back with h5py.
"""

from __future__ import annotations

import errno
import os
import random
import re
import signal
import subprocess
import sys
import time

import h5py
import meshio
import numpy as np
import pytest

from ffrmbs_app.export import export_paraview
from mbs import FlexibleBodyFFR, PointMass, System
from mbs.integrators.moreau import TRACE_KEYS
from mbs.results.result_file import ResultRecorder, load_result
from preprocess import Material, build_body
from preprocess.geometry import box

import paths
from cli_in_process import run_cli
from damage_places import damage_places, damaged as damaged_bytes

ENV = {**os.environ, "OPENBLAS_NUM_THREADS": "1"}


# --- finding 1: ParaView export of tet4 and tet10 bodies ------------------------------------------

def quaternion_matrix(p):
    """A of the unit quaternion p = (p0, p1, p2, p3), written out (Shabana's form)."""
    e0, e1, e2, e3 = p
    return np.array([[e0**2 + e1**2 - e2**2 - e3**2, 2 * (e1 * e2 - e0 * e3), 2 * (e1 * e3 + e0 * e2)],
                     [2 * (e1 * e2 + e0 * e3), e0**2 - e1**2 + e2**2 - e3**2, 2 * (e2 * e3 - e0 * e1)],
                     [2 * (e1 * e3 - e0 * e2), 2 * (e2 * e3 + e0 * e1), e0**2 - e1**2 - e2**2 + e3**2]])


@pytest.mark.parametrize("order, corners", [(1, 3), (2, 6)])
def test_export_writes_the_deformed_surface_of_tet4_and_tet10_bodies(tmp_path, order, corners):
    data = build_body(box(0.2, 0.04, 0.04, None, order=order, divisions=(4, 1, 1)),
                      Material(7800.0, 2e11, 0.3), n_modes=3)
    assert data.surface_triangles.shape[1] == corners
    system = System()
    body = system.add(FlexibleBodyFFR(data, name="box"))
    body.set_initial(v=(0.1, 0.0, 0.0), omega=(0.0, 0.0, 3.0), qdot_f=(40.0, -30.0, 20.0))
    path = tmp_path / "box.h5"
    system.simulate(0.02, 1e-3, integrator="generalized-alpha", t_out=np.linspace(0.0, 0.02, 5), plan=False,
                    recorder=ResultRecorder(path, {"scene": "box"}))
    pvd = export_paraview(path)

    res, _ = load_result(path)
    q = res.q                                     # the free frame's q: R (3), quaternion (4), q_f (3)
    phi = data.phi.reshape(data.n_nodes, 3, data.n_modes)
    for k in range(len(res.t)):
        mesh = meshio.read(pvd.parent / "box" / f"box_{k:06d}.vtu")
        kinds = {c.type: len(c.data) for c in mesh.cells}
        assert kinds == {("triangle" if order == 1 else "triangle6"): len(data.surface_triangles)}
        nodes = mesh.point_data["node"]
        R, A, q_f = q[k, :3], quaternion_matrix(q[k, 3:7]), q[k, 7:]
        expected = R + (data.u0[nodes] + phi[nodes] @ q_f) @ A.T
        assert np.allclose(mesh.points, expected, rtol=0, atol=1e-12)
        cells = mesh.cells[0].data                 # the body's own faces, node order kept
        assert set(map(tuple, nodes[cells])) == set(map(tuple, data.surface_triangles))
    assert np.abs(q[-1, 7:]).max() > 1e-6          # the body did deform


# --- the default scene, run once for findings 3 and 19 --------------------------------------------

README_PLOT = ["y", "vy", "energy", "contact:impact"]      # README: ffrmbs plot OUT/point_mass_beam.h5 y vy ...
EXAMPLE = paths.EXAMPLES / "scenes" / "point_mass_beam.toml"
PNG = b"\x89PNG\r\n\x1a\n"



@pytest.fixture(scope="module")
def default_run(tmp_path_factory):
    """`ffrmbs run` with no scene (15 ms: free flight and the impact), with the Δt/2 check;
    (output directory, stdout)."""
    out = tmp_path_factory.mktemp("default")
    code, stdout, stderr = run_cli("run", "--no-export", "--t-end", "0.015", "--out", str(out))
    assert code == 0, stderr
    return out, stdout


@pytest.fixture(scope="module")
def example_run(tmp_path_factory):
    """`ffrmbs run examples/scenes/point_mass_beam.toml` for 15 ms as the default run (free
    flight and the impact; the file's 1001 samples), no check."""
    out = tmp_path_factory.mktemp("example")
    code, _, stderr = run_cli("run", str(EXAMPLE), "--no-check", "--no-export", "--set", "scene.t_end=0.015",
                              "--out", str(out))
    assert code == 0, stderr
    return out


# --- finding 3: the README's plot command, one naming for both scenes, no overwritten PNG -----------

@pytest.mark.parametrize("which", ["default", "example"])
def test_the_readme_plot_command_works_and_keeps_the_runs_png(request, which):
    out = request.getfixturevalue("default_run")[0] if which == "default" else request.getfixturevalue("example_run")
    result, own = out / "point_mass_beam.h5", out / "point_mass_beam.png"
    before = (own.read_bytes(), own.stat().st_mtime_ns)
    code, stdout, stderr = run_cli("plot", str(result), *README_PLOT)
    first = out / "point_mass_beam-plot.png"
    assert code == 0, stderr
    assert stdout.strip() == f"wrote {first}" and first.read_bytes()[:8] == PNG
    assert (own.read_bytes(), own.stat().st_mtime_ns) == before          # the run's own plot untouched
    kept = first.read_bytes()
    assert run_cli("plot", str(result), "y")[0] == 0                      # again: a new name
    assert (out / "point_mass_beam-plot-2.png").read_bytes()[:8] == PNG and first.read_bytes() == kept
    assert run_cli("plot", str(result), "y", "--overwrite")[0] == 0       # asked: replaced
    assert first.read_bytes() != kept and not (out / "point_mass_beam-plot-3.png").exists()
    named = out / "chosen.png"
    named.write_bytes(b"old")
    assert run_cli("plot", str(result), "vy", "--out", str(named))[0] == 0  # --out names the file
    assert named.read_bytes()[:8] == PNG
    assert (own.read_bytes(), own.stat().st_mtime_ns) == before


def test_the_readme_export_command_works_on_the_default_scene(default_run):
    out = default_run[0]
    code, stdout, stderr = run_cli("export", str(out / "point_mass_beam.h5"), "--every", "10")
    assert code == 0, stderr
    pvd = out / "point_mass_beam-paraview" / "point_mass_beam.pvd"
    assert f"wrote {pvd}" in stdout
    n = len(load_result(out / "point_mass_beam.h5")[0].t)
    assert len(list((pvd.parent / "beam").glob("beam_*.vtu"))) == len(range(0, n, 10))


def test_default_and_example_scene_name_and_mean_their_outputs_alike(default_run, example_run):
    """The same names in both files, and node19 the same quantity in both: node 19's
    displacement Φ_19 q_f, from the beam's body data and the file's modal coordinates (its
    position would add (0.25, 0.05, 0.025) m)."""
    from ffrmbs_app.scenes import point_mass_beam as pmb

    data = pmb.TET10.default_beam_data()                                  # the main job's beam
    j = data.node_at(pmb.NODE_19)
    phi_19 = data.phi[3 * j:3 * j + 3, :20]                               # the 20 modes both scenes keep
    for path in (default_run[0] / "point_mass_beam.h5", example_run / "point_mass_beam.h5"):
        res, _ = load_result(path)
        assert sorted(res.outputs) == ["node19", "vy", "y"] and sorted(res.contacts) == ["impact"]
        assert sorted(res.energy) == ["kinetic", "potential"]
        with h5py.File(path, "r") as f:
            q_f = f["bodies/beam/q_f"][()]
        np.testing.assert_allclose(res["node19"], q_f @ phi_19.T, rtol=0, atol=1e-15)
        assert np.abs(res["node19"][-1]).max() > 1e-5                     # the beam did deflect


# --- finding 19: units on every dataset, on plot axes and in the accuracy line ---------------------

def datasets_with_units(path) -> dict:
    found = {}
    with h5py.File(path, "r") as f:
        f.visititems(lambda name, obj: found.__setitem__(name, obj.attrs.get("units"))
                     if isinstance(obj, h5py.Dataset) else None)
    return found


@pytest.mark.parametrize("which", ["default", "example"])
def test_every_dataset_has_units(request, which):
    out = request.getfixturevalue("default_run")[0] if which == "default" else request.getfixturevalue("example_run")
    units = datasets_with_units(out / "point_mass_beam.h5")
    assert len(units) > 30 and all(isinstance(u, str) and u for u in units.values()), units
    assert units["t"] == "s" and units["energy/kinetic"] == "J" and units["trace/dt"] == "s"
    assert (units["outputs/y"], units["outputs/vy"], units["outputs/node19"]) == ("m", "m/s", "m")
    assert units["contacts/impact/force"] == "N" and units["contacts/impact/gap"] == "m"
    assert units["bodies/point mass/q"] == "m" and units["bodies/point mass/u"] == "m/s"
    # the beam's modes are mass-normalized (Φᵀ M Φ = I): Φ [kg^-1/2], q_f [kg^1/2 m]
    assert units["bodies/beam/surface/phi"] == "kg^(-1/2)" and units["bodies/beam/q_f"] == "kg^(1/2) m"


def test_plot_axes_carry_the_units(default_run):
    from ffrmbs_app.plot import result_figure

    fig = result_figure(default_run[0] / "point_mass_beam.h5", ["y", "vy", "node19", "energy"])
    assert [ax.get_ylabel() for ax in fig.axes[:4]] == ["y [m]", "vy [m/s]", "node19 [m]", "energy [J]"]


def test_the_accuracy_line_gives_unit_and_range_ratio(default_run):
    out, stdout = default_run
    line = next(ln for ln in stdout.splitlines() if ln.startswith("accuracy"))
    res, _ = load_result(out / "point_mass_beam.h5")
    for name, unit in (("y", "m"), ("vy", "m/s"), ("node19", "m")):
        values = res[name].reshape(len(res.t), -1)
        spread = (values.max(axis=0) - values.min(axis=0)).max()          # the range, read from the file
        found = re.search(rf"\b{name} ([0-9.e+-]+) {re.escape(unit)} \(([0-9.e+-]+) of its range "
                          rf"([0-9.e+-]+) {re.escape(unit)}\)", line)
        assert found, line
        err, ratio, shown = (float(x) for x in found.groups())
        assert shown == float(f"{spread:.3g}") and ratio == pytest.approx(err / spread, rel=0.01)
        assert 0 < err < spread


# --- finding 11: a full disk -----------------------------------------------------------------------

def enospc(*args, **kwargs):
    raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))


def test_a_full_disk_at_a_checkpoint_is_one_clear_line_and_status_failed(tmp_path, monkeypatch):
    import mbs.results.result_file

    monkeypatch.setattr(mbs.results.result_file, "write_checkpoint", enospc)
    code, _, stderr = run_cli("run", "--no-check", "--no-export", "--t-end", "0.015", "--checkpoint-every", "0.001",
                              "--out", str(tmp_path))
    ckpt = tmp_path / "point_mass_beam.h5.ckpt"
    assert code == 2
    assert stderr.strip() == f"ffrmbs: error: {ckpt}: cannot write the checkpoint: {os.strerror(errno.ENOSPC)}"
    with h5py.File(tmp_path / "point_mass_beam.h5", "r") as f:
        assert f.attrs["status"] == f"failed: cannot write the checkpoint: {os.strerror(errno.ENOSPC)}"
    assert not ckpt.exists()


HDF5_ENOSPC = RuntimeError("Unable to synchronously flush file (file write failed: time = Wed Nov 25 12:08:13 2026\n, "
                           "filename = 'x.h5', file descriptor = 3, errno = 28, error message = 'No space left on "
                           "device', buf = 0x1, total write size = 96, bytes this sub-write = 96, offset = 1757976)")


@pytest.mark.parametrize("error", [OSError(errno.ENOSPC, os.strerror(errno.ENOSPC)), HDF5_ENOSPC],
                         ids=["OSError", "HDF5 RuntimeError"])
def test_a_full_disk_at_a_flush_is_one_clear_line_and_status_failed(tmp_path, monkeypatch, error):
    real, calls = h5py.File.flush, []

    def flush(self):                     # the layout's flush goes through, the next one finds the disk full
        calls.append(1)
        if len(calls) > 1:
            raise error
        real(self)

    monkeypatch.setattr(h5py.File, "flush", flush)
    code, _, stderr = run_cli("run", "--no-check", "--no-export", "--t-end", "0.015", "--out", str(tmp_path))
    path = tmp_path / "point_mass_beam.h5"
    assert code == 2
    assert stderr.strip() == f"ffrmbs: error: {path}: cannot write the result file: {os.strerror(errno.ENOSPC)}"
    monkeypatch.undo()
    res, attrs = load_result(path)
    assert attrs["status"] == f"failed: cannot write the result file: {os.strerror(errno.ENOSPC)}"


def test_a_disk_about_to_fill_stops_before_hdf5_writes(tmp_path, monkeypatch):
    """HDF5 cannot close a file after a failed write (the process then crashes as it
    exits, seen on a full 1 MB tmpfs), so the recorder checks the free space before each
    flush and stops with room left to close the file."""
    import mbs.results.result_file

    free = iter([50e6] + [1.2e6] * 100)                     # [bytes]: room for the layout, not for 256 samples
    monkeypatch.setattr(mbs.results.result_file, "free_bytes", lambda directory: int(next(free)))
    code, _, stderr = run_cli("run", "--no-check", "--no-export", "--t-end", "0.015", "--out", str(tmp_path))
    path = tmp_path / "point_mass_beam.h5"
    assert code == 2
    assert stderr.startswith(f"ffrmbs: error: {path}: cannot write the result file: {os.strerror(errno.ENOSPC)} "
                             "(1.20 MB free, ") and stderr.count("\n") == 1
    res, attrs = load_result(path)
    assert attrs["status"].startswith(f"failed: cannot write the result file: {os.strerror(errno.ENOSPC)}")
    assert len(res.t) == 0 and len(res.trace["t"]) == 0


def test_a_full_disk_while_plotting_or_exporting_is_one_clear_line(default_run, tmp_path, monkeypatch):
    from matplotlib.figure import Figure

    result, png, pv = default_run[0] / "point_mass_beam.h5", tmp_path / "p.png", tmp_path / "pv"
    monkeypatch.setattr(Figure, "savefig", enospc)
    code, _, stderr = run_cli("plot", str(result), "y", "--out", str(png))
    assert code == 2
    assert stderr.strip() == f"ffrmbs: error: {png}: cannot write the plot: {os.strerror(errno.ENOSPC)}"
    monkeypatch.setattr(meshio, "write", enospc)
    code, _, stderr = run_cli("export", str(result), "--out", str(pv), "--every", "100")
    assert code == 2
    assert stderr.strip() == f"ffrmbs: error: {pv}: cannot write the ParaView export: {os.strerror(errno.ENOSPC)}"
    assert list(tmp_path.iterdir()) == []                                 # nothing half-written


# --- finding 14: kill -9 at any moment leaves a readable file ------------------------------------

KILL_T_END, KILL_N_OUT = 0.05, 4001      # the example scene shortened, with dense samples: many flushes


def check_killed_file(path, t_end, n_out) -> int:
    """A killed run's file: readable by load_result, status running, every per-sample
    dataset of one length n (the samples are the first n output times, finite), the trace
    keys of one length, reaching the last sample. Returns n."""
    res, attrs = load_result(path)
    assert attrs["status"] == "running"
    n = len(res.t)
    with h5py.File(path, "r") as f:
        lengths, trace = {}, {}
        f.visititems(lambda name, obj: (trace if name.startswith("trace/") else lengths).__setitem__(
            name, obj.shape[0]) if isinstance(obj, h5py.Dataset) and "/surface/" not in name else None)
        trace_t = f["trace/t"][()]
    assert set(lengths.values()) == {n}, lengths
    assert len(set(trace.values())) == 1 and len(trace) == len(TRACE_KEYS), trace
    assert np.array_equal(res.t, np.linspace(0.0, t_end, n_out)[:n])
    assert np.isfinite(res.q).all() and np.isfinite(res["y"]).all()
    assert res.q.shape[0] == res["node19"].shape[0] == res.energy["kinetic"].shape[0] == n
    if len(trace_t):
        assert np.all(np.diff(trace_t) > 0) and abs(trace_t[-1] - res.t[-1]) < 1e-9
    return n


def wait_for(condition, proc, timeout=120.0):
    deadline = time.monotonic() + timeout
    while not condition():
        if proc.poll() is not None:
            pytest.fail(f"the run ended before it was killed: {proc.communicate()}")
        if time.monotonic() > deadline:
            proc.kill()
            pytest.fail("timed out")
        time.sleep(0.001)


def test_the_result_file_writes_its_metadata_only_when_it_flushes(tmp_path):
    """HDF5 may evict metadata to disk between flushes; a kill then can leave a chunk index
    pointing past the file's end-of-allocation ("addr overflow", found by the kill test
    below). The recorder's open file keeps its metadata until a flush,
    from the first flush on and after a resume's reopening alike."""
    seen = []

    class Watching(ResultRecorder):
        def _flush(self, integ):
            seen.append(self.file.id.get_mdc_config().evictions_enabled)
            super()._flush(integ)

    system = System()
    system.add(PointMass(1.0, velocity=(1.0, 0.0, 0.0)))
    system.simulate(0.01, 1e-3, integrator="moreau", recorder=Watching(tmp_path / "m.h5"))
    assert seen and not any(seen)
    assert load_result(tmp_path / "m.h5")[0].t[-1] == pytest.approx(0.01)


@pytest.mark.slow
def test_kill_9_at_random_moments_leaves_a_readable_file(tmp_path):
    """SIGKILL a run of the example scene at random moments (seed fixed): before the file
    exists, the moment it appears, while the kernels compile (before any sample is
    flushed), and while samples are streamed; every time the file opens and is
    consistent."""
    text = EXAMPLE.read_text()
    short = text.replace("t_end = 0.1 ", f"t_end = {KILL_T_END} ").replace("n_out = 1001", f"n_out = {KILL_N_OUT}")
    assert short.count(str(KILL_N_OUT)) == 1 and f"t_end = {KILL_T_END}" in short
    scene = tmp_path / "scene.toml"
    scene.write_text(short)
    rng = random.Random(18)
    moments = [("start", 0.3), ("file", 0.0), ("file", 0.0), ("file", rng.uniform(0.0, 0.5))] \
        + [("samples", rng.uniform(0.0, 0.5)) for _ in range(5)]
    seen = []
    for i, (after, delay) in enumerate(moments):
        out = tmp_path / f"kill{i}"
        path = out / "point_mass_beam.h5"
        proc = subprocess.Popen([sys.executable, "-m", "ffrmbs_app.cli", "run", str(scene), "--no-check", "--no-export",
                                 "--out", str(out)], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, env=ENV)
        if after == "file":
            wait_for(path.exists, proc)
        elif after == "samples":                    # the file grows: its first samples are flushed
            wait_for(path.exists, proc)
            size = path.stat().st_size
            wait_for(lambda: path.stat().st_size > size, proc)
        time.sleep(delay)
        os.kill(proc.pid, signal.SIGKILL)
        proc.communicate()
        if after == "start":
            assert not path.exists()                # killed while starting: no file at all, not a broken one
            continue
        seen.append(check_killed_file(path, KILL_T_END, KILL_N_OUT))
    print("samples in the killed files:", seen)
    assert seen[0] == 0 and max(seen) > 0           # killed before any sample was flushed, and after some


def test_a_damaged_result_file_is_a_clear_error(default_run, tmp_path):
    """64 bytes of 0xff every 4 KiB of a result file, one place at a time (damaged HDF5
    metadata made h5py raise RuntimeError, OSError or KeyError, and bad JSON a
    JSONDecodeError; within one dataset's raw data, where the damage is NaN or -1 values,
    one place per dataset): load_result reads the file or raises InputFileError, nothing
    else."""
    from ffrmbs.errors import InputFileError

    path = default_run[0] / "point_mass_beam.h5"
    data = path.read_bytes()
    damaged, faults = tmp_path / "damaged.h5", 0
    for offset in damage_places(path):
        damaged.write_bytes(damaged_bytes(data, offset))
        try:
            load_result(damaged)
        except InputFileError as exc:
            faults += 1
            assert str(exc).startswith(f"{damaged}: ") and "\n" not in str(exc) and len(str(exc)) < 300
    assert faults >= 3



def test_an_unexpected_error_while_finishing_closes_the_file_as_failed(tmp_path, monkeypatch):
    """A bug-like error (not a disk fault) in the last flush: it propagates as itself, and
    the result file is closed all the same, readable, with status 'failed: …' (it stayed
    open with status 'running')."""
    real = ResultRecorder._flush

    def flush(self, integ):
        if integ.state.recorded == len(integ.state.times):       # the final flush only
            raise ZeroDivisionError("a bug in a flush")
        real(self, integ)

    monkeypatch.setattr(ResultRecorder, "_flush", flush)
    with pytest.raises(ZeroDivisionError):
        run_cli("run", "--no-check", "--no-export", "--t-end", "0.002", "--out", str(tmp_path))
    monkeypatch.undo()
    _, attrs = load_result(tmp_path / "point_mass_beam.h5")
    assert attrs["status"].startswith("failed: the file could not be finished")


def test_a_non_reading_error_in_a_result_block_is_not_blamed_on_the_file(tmp_path):
    """damaged_result_file turns what h5py or json raise into 'damaged result file', but
    lets an error of other code in the block (here numpy) pass as itself."""
    from ffrmbs.errors import InputFileError
    from mbs.results.result_file import damaged_result_file

    path = tmp_path / "r.h5"
    h5py.File(path, "w").close()
    with pytest.raises(InputFileError, match="damaged result file"):
        with h5py.File(path, "r") as f, damaged_result_file(path):
            f["missing"]
    with pytest.raises(ValueError, match="cannot reshape"):
        with damaged_result_file(path):
            np.zeros(2).reshape(3)

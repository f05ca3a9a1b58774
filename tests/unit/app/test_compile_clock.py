"""Compilation is announced and measured apart, never counted as run time (issue 18, finding 18)."""

import time

import numpy as np
from numba import njit
from numba.core import event

from ffrmbs_app.compile_clock import CompileClock
from ffrmbs_app.job import run_scene
from ffrmbs_app.scene import Scene
from mbs import PointMass, System

SLEEP_S = 0.3


def _fresh_kernel():
    """A kernel numba has never seen (a new function object each call, no disk cache)."""
    @njit(cache=False)
    def kernel(x):
        return 2.0 * x
    return kernel


def test_clock_counts_a_compilation_once_and_announces_it():
    lines = []
    kernel = _fresh_kernel()
    with CompileClock(lines.append) as clock:
        kernel(1.0)
        kernel(2.0)                     # compiled already: no second compilation
    assert clock.compiled == 1 and clock.seconds > 0.0
    assert len(lines) == 1 and "compiling numba kernels" in lines[0]
    with CompileClock(lines.append) as again:
        kernel(3.0)
    assert again.compiled == 0 and again.seconds == 0.0 and len(lines) == 1
    assert again.describe() == "kernels: already loaded in this process"


class _SlowCompile(event.Listener):
    """Makes each compilation measurably long (SLEEP_S while numba holds its lock)."""

    def on_start(self, ev):
        time.sleep(SLEEP_S)

    def on_end(self, ev):
        pass


def _scene_compiling_during_the_run():
    """A free-falling point mass whose output probe (evaluated at each sample) calls a
    fresh kernel from t = 5 ms on: it compiles in the middle of the timed run (the job's
    checks before the run evaluate the probe at t = 0)."""
    kernel = _fresh_kernel()
    system = System(gravity=(0.0, -9.81, 0.0))
    system.add(PointMass(1.0, position=(0.0, 0.0, 0.0)))

    def probe(t, q, u):
        return np.array([kernel(q[1]) if t >= 0.005 else 2.0 * q[1]])

    return Scene(system, 0.01, 1e-3, "rk4", n_out=11, outputs={"y2": probe}, energies=False,
                 plan=False, name="falling")


def test_compilation_inside_the_run_is_not_in_the_per_step_cost(tmp_path):
    scene = _scene_compiling_during_the_run()
    lines = []
    with event.install_listener("numba:compile", _SlowCompile()):
        summary = run_scene(lambda: scene, tmp_path, check=False, export=False, plot=False, log=lines.append)
    assert summary["kernels_compiled"] == 1
    assert summary["compile_s"] >= SLEEP_S
    # the whole run takes far less than the compilation's SLEEP_S: the cost excludes it
    assert summary["wall_s"] < SLEEP_S / 3, summary["wall_s"]
    # the compilation's CPU seconds are subtracted from the CPU time, not its wall seconds
    # (the sleep costs no CPU: subtracting SLEEP_S left 0 s of CPU for a run that used some)
    assert 0.0 < summary["cpu_s"] < SLEEP_S / 3, summary["cpu_s"]
    assert any("compiling numba kernels" in line for line in lines)
    assert any(line.startswith("kernels: 1 compiled") for line in lines)


def test_validation_timing_excludes_compilation():
    """validation.harness.timed: the CPU seconds of a call that compiles a kernel (made
    slow by SLEEP_S of busy CPU inside numba's lock) do not contain the compilation."""
    from validation import timed

    class BusyCompile(event.Listener):
        def on_start(self, ev):
            end = time.process_time() + SLEEP_S
            while time.process_time() < end:
                pass

        def on_end(self, ev):
            pass

    kernel = _fresh_kernel()
    with event.install_listener("numba:compile", BusyCompile()):
        value, cpu = timed(kernel, 1.5)
    assert value == 3.0
    assert cpu < SLEEP_S / 3, cpu

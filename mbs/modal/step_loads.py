"""Step-function nodal loads for the modal solvers (report eq. 9, Appendix A).

A load is a sum of step functions: the nodal forces jump to ``forces[j]`` at
``times[j]`` and hold until ``times[j+1]`` (the last row holds for ever); before
``times[0]`` they are zero (report eq. 9 with f^(−1) = 0). Load times need not be
uniform: rapid changes get many steps, slow ones few (report Sec. 2.2).

Only the loaded nodes are stored (``nodes`` (k,), ``forces`` (n_t, k, 3)), so every
projection costs O(k n) rather than O(N n). Components are in the body frame B
(``frame="body"``, the report's convention: the loads turn with the body) or in the
inertial frame G (``frame="inertial"``, report Sec. 7.2 "Forces in the G frame").
"""

from __future__ import annotations

import numpy as np

from ffrmbs.errors import ModelError

from mbs.links.force_file import read_force_file
from mbs.links.step_times import check_times

FRAMES = ("body", "inertial")


class StepLoads:
    """Nodal step loads (report eq. 9).

    Parameters
    ----------
    times : (n_t,) [s], strictly increasing.
    nodes : (k,) int, distinct 0-based node indices carrying load.
    forces : (n_t, k, 3) [N], force on each loaded node from times[j] on.
    frame : "body" or "inertial", the axes of the force components.
    """

    def __init__(self, times, nodes, forces, frame="body"):
        times = check_times(np.array(times, dtype=float).ravel(), "StepLoads")
        nodes = np.array(nodes, dtype=np.int64).ravel()
        forces = np.array(forces, dtype=float)
        if frame not in FRAMES:
            raise ModelError(f"StepLoads: frame must be one of {FRAMES}, got {frame!r}")
        if forces.shape != (times.size, nodes.size, 3):
            raise ModelError(f"StepLoads: forces must have shape (n_t, k, 3) = "
                             f"({times.size}, {nodes.size}, 3), got {forces.shape}")
        if not np.all(np.isfinite(forces)):
            raise ModelError("StepLoads: forces must be finite")
        if nodes.size and (nodes.min() < 0 or np.unique(nodes).size != nodes.size):
            raise ModelError("StepLoads: node indices must be distinct and non-negative")
        self.times, self.nodes, self.forces, self.frame = times, nodes, forces, frame

    # --- constructors -------------------------------------------------------------------

    @classmethod
    def from_nodal(cls, times, forces, frame="body"):
        """From full nodal forces (n_t, N, 3) [N]; keeps only the nodes ever loaded."""
        forces = np.asarray(forces, dtype=float)
        if forces.ndim != 3 or forces.shape[2] != 3:
            raise ModelError(f"StepLoads.from_nodal: forces must be (n_t, N, 3), got {forces.shape}")
        nodes = np.flatnonzero(np.any(forces != 0.0, axis=(0, 2)))
        return cls(times, nodes, forces[:, nodes], frame)

    @classmethod
    def from_file(cls, path, n_nodes, blocked_dofs=None, frame="body"):
        """From a force file of report Appendix A (see :func:`mbs.read_force_file`;
        errors name the file and line)."""
        times, forces = read_force_file(path, n_nodes, blocked_dofs)
        return cls.from_nodal(times, forces, frame)

    @classmethod
    def sampled(cls, function, times, nodes, weights, frame="body", rule="midpoint"):
        """Step discretisation (eq. 9) of a time-varying resultant spread over nodes.

        ``function(t)`` returns the resultant force (3,) [N] at time t [s];
        ``weights`` (k,) spread it over ``nodes`` (k,) (e.g. area weights of a face,
        summing to 1). Step j holds the value at the midpoint of [times[j],
        times[j+1]] (``rule="midpoint"``, second-order accurate; the last step uses
        its left end) or at its left end (``rule="left"``).
        """
        times = np.asarray(times, dtype=float).ravel()
        if rule not in ("midpoint", "left"):
            raise ModelError(f"StepLoads.sampled: rule must be 'midpoint' or 'left', got {rule!r}")
        at = times.copy()
        if rule == "midpoint" and times.size > 1:
            at[:-1] = 0.5 * (times[:-1] + times[1:])
        resultants = np.array([np.broadcast_to(np.asarray(function(t), dtype=float), (3,)) for t in at])
        weights = np.asarray(weights, dtype=float).ravel()
        return cls(times, nodes, resultants[:, None, :] * weights[None, :, None], frame)

    # --- derived quantities -----------------------------------------------------------

    @property
    def n_steps(self) -> int:
        return self.times.size

    def step_index(self, t) -> np.ndarray:
        """Row j in force at time(s) t (times[j] <= t < times[j+1]); −1 before times[0]."""
        return np.searchsorted(self.times, t, side="right") - 1

    def resultants(self) -> np.ndarray:
        """Σ_i f_i per step, (n_t, 3) [N]."""
        return self.forces.sum(axis=1)

    def moments(self, b) -> np.ndarray:
        """Σ_i b_i × f_i per step (report eq. 19) with lever arms ``b`` (N, 3) [m], (n_t, 3) [N m]."""
        return np.cross(b[self.nodes][None], self.forces).sum(axis=1)

    def first_moments(self, b) -> np.ndarray:
        """Σ_i b_i f_iᵀ per step, (n_t, 3, 3) [N m]: the moment of inertial-frame forces
        about B's origin in any orientation R follows from it in O(1) (see
        :func:`mbs.modal.rigid_motion.inertial_torque`)."""
        return np.einsum("ia,tib->tab", b[self.nodes], self.forces)

    def check_nodes(self, n_nodes, allowed=None, what="the body"):
        """ModelError unless the loaded nodes exist (and lie in ``allowed``, e.g. the surface)."""
        if self.nodes.size and self.nodes.max() >= n_nodes:
            raise ModelError(f"StepLoads: node {int(self.nodes.max())} does not exist; "
                             f"{what} has {n_nodes} nodes")
        if allowed is not None:
            outside = np.setdiff1d(self.nodes, allowed)
            if outside.size:
                raise ModelError(f"StepLoads: {outside.size} loaded node(s) (e.g. node {int(outside[0])}) "
                                 "are not surface nodes; the boundary approach (report Sec. 4.2) "
                                 "needs loads on the surface")

"""Applied loads: forces and torques on frames, distributed and nodal loads.

Every load here is a :class:`~mbs.links.link.ForceElement` that adds its generalized forces
through the frame Jacobians (thesis eq. 2.76):

    Q = J_Tᵀ F   (force F [N] at a point),      Q = J_Rᵀ τ   (torque τ [N m]).

Components are inertial, or — ``frame_fixed=True`` — in the axes of the frame, which
turn with it: the inertial force is then A F with A = ``frame.orientation``. Loads are
not conservative (they may depend on time): their potential energy is zero, and they
add no tangents (the stiffness of follower loads is neglected by implicit integrators).

Time dependence: a constant, a callable f(t), or a :class:`Tabulated` table — "step"
tables are the report's loads as sums of step functions (report eq. 9).

Fast many-node loads rest on one fact: a point's J_T is affine in its body-frame data
(ū0, Φ) (thesis eq. 2.70 with ū = ū0 + Φ q_f, eq. 2.23):

    J_T(ū0, Φ) = [1, −A (ū0 + Φ q_f)~ T, A Φ]   (free frame),   A Φ   (prescribed frame),

so Σ_j c_j J_T(ū0_j, Φ_j) = J_T(Σ c_j ū0_j, Σ c_j Φ_j) + (Σ c_j − 1) J_T(0, 0). A load
spread over N nodes then costs one O(N n_f) sum once and O(n_f) per evaluation.

Force files (report Appendix A) are read and written by :mod:`mbs.links.force_file`.
"""

from __future__ import annotations

import numpy as np

from ffrmbs.errors import ModelError

from mbs.bodies.body import Frame
from mbs.bodies.flexible_body import FlexibleBodyFFR
from mbs.links.force_file import read_force_file
from mbs.links.link import ForceElement, add_point_force, add_torque, body_q
from mbs.modal import StepLoads
from mbs.links.step_times import check_times, step_index

WEIGHT_SUM_TOL = 1e-9   # |Σ w_j − 1| allowed for DistributedForce weights


# --- time functions -------------------------------------------------------------------

class Tabulated:
    """A function of time given by a table.

    Parameters
    ----------
    times : (n_t,) [s]
        Strictly increasing.
    values : (n_t,) or (n_t, k)
        Value(s) at each time, in the unit of the quantity (N for forces).
    kind : "step" or "linear"
        "step": value j holds for times[j] <= t < times[j+1] — Σ_j h(t − t_j) Δf_j with
        Δf_j = f_j − f_{j−1}, the report's step-function loads (report eq. 9).
        "linear": linear interpolation between the rows.
    hold_first : bool
        Before times[0] the function is zero (default: no load before the first step,
        f_{−1} = 0 in report eq. 9); with ``hold_first=True`` it is values[0] there.
        After times[-1] the last value holds, for both kinds.

    Notes
    -----
    Calling the table at a time t [s] returns a float (1-D values) or a (k,) array.
    """

    KINDS = ("step", "linear")

    def __init__(self, times, values, kind="step", hold_first=False):
        if kind not in self.KINDS:
            raise ModelError(f"Tabulated: kind must be one of {self.KINDS}, got {kind!r}")
        self.times = check_times(times, "Tabulated")
        self.values = np.array(values, dtype=float)
        if self.values.ndim not in (1, 2) or self.values.shape[0] != self.times.size:
            raise ModelError(f"Tabulated: values must have shape ({self.times.size},) or "
                             f"({self.times.size}, k) to match the times, got {self.values.shape}")
        self.kind = kind
        self.hold_first = bool(hold_first)

    @property
    def value_shape(self) -> tuple:
        """Shape of one value: () or (k,)."""
        return self.values.shape[1:]

    def __call__(self, t):
        j = step_index(self.times, t)
        if j < 0 and not self.hold_first:
            return np.zeros(self.value_shape) if self.value_shape else 0.0
        if j < 0 or self.kind == "step" or j == self.times.size - 1:
            v = self.values[max(j, 0)]
            return v.copy() if self.value_shape else float(v)
        s = (t - self.times[j]) / (self.times[j + 1] - self.times[j])
        return (1.0 - s) * self.values[j] + s * self.values[j + 1]


def _jumps(function):
    """The jump times of a step Tabulated, () for anything else."""
    if isinstance(function, Tabulated) and function.kind == "step":
        return tuple(function.times)
    return ()


def _step_table(value):
    """(times (n_t,), values (n_t, 3)) of a constant force or a step :class:`Tabulated`
    (report eq. 9: each row holds from its time on), None for anything else."""
    if isinstance(value, Tabulated):
        if value.kind != "step" or value.value_shape != (3,):
            return None
        times, values = value.times, value.values
        if value.hold_first and times[0] > 0.0:
            times, values = np.concatenate(([0.0], times)), np.concatenate((values[:1], values))
        return times, values
    if callable(value):
        return None
    return np.zeros(1), np.array(value, dtype=float).reshape(1, 3)


def _point_table(value):
    """(times (n_t,), values (n_t, 3)) with the force values[r] for times[r] <= t <
    times[r+1] and none before times[0], equal to ``value`` at every t: a constant holds
    from −inf, a step :class:`Tabulated` as it is (its first row from −inf when
    ``hold_first``); None for a callable or a linear table."""
    if isinstance(value, Tabulated):
        if value.kind != "step" or value.value_shape != (3,):
            return None
        times = value.times.copy()
        if value.hold_first:
            times[0] = -np.inf
        return times, value.values
    if callable(value):
        return None
    return np.array([-np.inf]), np.array(value, dtype=float).reshape(1, 3)


def _vector_function(value, what):
    """A callable t -> (3,) array from a constant (3,), a callable or a :class:`Tabulated`."""
    if isinstance(value, Tabulated):
        if value.value_shape != (3,):
            raise ModelError(f"{what}: the table must have 3 values per time, "
                             f"got shape {value.values.shape}")
        return value
    if callable(value):
        def checked(t):
            v = np.asarray(value(t), dtype=float)
            if v.shape != (3,):
                raise ModelError(f"{what}: the function returned shape {v.shape} at t = {t} s, "
                                 "expected (3,)")
            return v
        return checked
    v = np.array(value, dtype=float)
    if v.shape != (3,) or not np.isfinite(v).all():
        raise ModelError(f"{what}: expected 3 finite components, a callable f(t) or a "
                         f"Tabulated, got {value!r}")
    return lambda t: v


# --- forces and torques on one frame --------------------------------------------------

class Force(ForceElement):
    """A force at ``frame``'s point: Q = J_Tᵀ F (thesis eq. 2.76, J_T of eq. 2.70).

    Parameters
    ----------
    frame : Frame
        The point of application (not a ground frame).
    force : (3,) [N], callable f(t) -> (3,), or Tabulated with (n_t, 3) values
    frame_fixed : bool
        False: inertial components. True: components in the frame's axes, so the
        inertial force is A F with A = ``frame.orientation(q_body, t)`` (a follower load).
    """

    def __init__(self, frame: Frame, force, frame_fixed=False):
        if frame.body is None:
            raise ModelError(f"{type(self).__name__}: {frame!r} is fixed in the inertial "
                             "frame; a load there does nothing — apply it to a body's frame")
        self.frame = frame
        self.force = _vector_function(force, type(self).__name__)
        self._table = _step_table(force)
        self._point_table = _point_table(force)
        self.frame_fixed = bool(frame_fixed)
        self._nodes = None if getattr(frame, "node_index", None) is None else (np.array([frame.node_index]),
                                                                              np.ones(1))

    def bodies(self):
        return [self.frame.body]

    def inertial_force(self, t, q) -> np.ndarray:
        """F in inertial components (3,) [N] at time t [s] and global positions q."""
        F = self.force(t)
        if self.frame_fixed:
            F = self.frame.orientation(body_q(self.frame, q), t) @ F
        return F

    def add_forces(self, t, q, u, h):
        add_point_force(self.frame, q, t, self.inertial_force(t, q), h)

    def breakpoints(self):
        return _jumps(self.force)

    def point_load(self):
        """(frame, times, values, frame_fixed) of a constant force or a step
        :class:`Tabulated` (see :meth:`mbs.links.link.ForceElement.point_load`), else None."""
        return None if self._point_table is None else (self.frame, *self._point_table, self.frame_fixed)

    def step_loads(self):
        """The load as nodal step loads (:class:`mbs.modal.StepLoads`, report eq. 9) for the
        planner's modal solvers, or None when it is not one: a callable force, a linear
        table, or a point that is not a node."""
        if self._table is None or self._nodes is None:
            return None
        (times, values), (nodes, weights) = self._table, self._nodes
        return StepLoads(times, nodes, values[:, None, :] * weights[None, :, None],
                         "body" if self.frame_fixed else "inertial")


class Torque(ForceElement):
    """A torque on ``frame``'s body: Q = J_Rᵀ τ (thesis eq. 2.76, J_R of eq. 2.72).

    ``torque`` (3,) [N m], callable τ(t) or Tabulated; ``frame_fixed`` as for
    :class:`Force` (True: components in the frame's axes, inertial torque A τ).
    """

    def __init__(self, frame: Frame, torque, frame_fixed=False):
        if frame.body is None:
            raise ModelError(f"Torque: {frame!r} is fixed in the inertial frame; "
                             "apply the torque to a body's frame")
        self.frame = frame
        self.torque = _vector_function(torque, "Torque")
        self.frame_fixed = bool(frame_fixed)

    def bodies(self):
        return [self.frame.body]

    def add_forces(self, t, q, u, h):
        tau = self.torque(t)
        if self.frame_fixed:
            tau = self.frame.orientation(body_q(self.frame, q), t) @ tau
        add_torque(self.frame, q, t, tau, h)

    def breakpoints(self):
        return _jumps(self.torque)


# --- loads spread over the nodes of a flexible body -----------------------------------

class DistributedForce(Force):
    """A resultant force spread over nodes of a flexible body with weights w_j, Σ w_j = 1:

        Q = Σ_j w_j J_T,jᵀ F = J_T(ū0 = Σ w_j ū0_j, Φ = Σ w_j Φ_j)ᵀ F,

    exact because J_T is affine in (ū0, Φ) (module docstring, thesis eq. 2.70, 2.76). The
    weighted-mean frame is built once (O(N n_f)); each evaluation costs O(n_f),
    whatever the node count. A face load: ``w = face_load(mesh, nodes, [1, 0, 0])[nodes, 0]``.

    Parameters
    ----------
    body : FlexibleBodyFFR
    nodes : (n,) int or str
        0-based node indices, or the name of a node group of the body.
    weights : (n,)
        One weight per entry of ``nodes``, summing to 1 (within 1e-9).
    force : (3,) [N], callable or Tabulated — the resultant, see :class:`Force`.
    frame_fixed : bool
        True (default): components in the body frame's axes; False: inertial.
    """

    def __init__(self, body: FlexibleBodyFFR, nodes, weights, force, frame_fixed=True):
        if not isinstance(body, FlexibleBodyFFR):
            raise ModelError(f"DistributedForce acts on a FlexibleBodyFFR, got {body!r}")
        nodes = body.node_group(nodes) if isinstance(nodes, str) else np.asarray(nodes, dtype=int).ravel()
        weights = np.asarray(weights, dtype=float).ravel()
        if weights.shape != nodes.shape:
            raise ModelError(f"DistributedForce: {weights.size} weights for {nodes.size} nodes; "
                             "give one weight per node (e.g. weights[nodes] of a nodal array)")
        if nodes.size and (nodes.min() < 0 or nodes.max() >= body.data.n_nodes):
            raise ModelError(f"DistributedForce: node indices must lie in 0..{body.data.n_nodes - 1}")
        if not abs(weights.sum() - 1.0) <= WEIGHT_SUM_TOL:
            raise ModelError(f"DistributedForce: the weights sum to {float(weights.sum())!r}, not 1; "
                             "divide them by their sum (the force argument is the resultant)")
        phi_nodes = body.phi.reshape(body.data.n_nodes, 3, body.n_modes)
        frame = Frame(body, weights @ body.data.u0[nodes],
                      np.einsum("j,jcf->cf", weights, phi_nodes[nodes]), name="load centre")
        super().__init__(frame, force, frame_fixed)
        self._nodes = nodes, weights


class NodalForces(ForceElement):
    """Step-function nodal forces on a flexible body (report eq. 9, force files of report
    Appendix A): row r of ``forces`` holds for times[r] <= t < times[r+1], the last from
    times[-1] on, none before times[0].

        Q(t) = Σ_j J_T,jᵀ D F_j(t),    D = A (``frame_fixed``) or 1 (inertial components).

    Writing F_j = Σ_k F_jk e_k and using that J_T is affine in (ū0, Φ) (module docstring),
    Σ_j F_jk J_T,j = J_T(V_k) + (W_k − 1) J_T(origin) with the "virtual frame" V_k of
    ū0 = Σ_j F_jk ū0_j [N m], Φ = Σ_j F_jk Φ_j and W_k = Σ_j F_jk [N]. These are summed
    once per time row (O(n_t N n_f)); an evaluation then costs four J_T, O(n_f), through
    the body's own Jacobians, so it holds for free and prescribed frames alike. For a
    free frame and body-frame components it equals (thesis eq. 2.70, 2.76)

        Q = [A Σ F_j ;  Tᵀ Σ_j (ū0_j + Φ_j q_f) × F_j ;  Σ_j Φ_jᵀ F_j].

    Parameters
    ----------
    body : FlexibleBodyFFR
    times : (n_t,) [s], strictly increasing
    forces : (n_t, N, 3) [N], N = the body's node count
    frame_fixed : bool
        True (default): components in the body frame's axes; False: inertial.
    """

    def __init__(self, body: FlexibleBodyFFR, times, forces, frame_fixed=True):
        if not isinstance(body, FlexibleBodyFFR):
            raise ModelError(f"NodalForces acts on a FlexibleBodyFFR, got {body!r}")
        self.body = body
        self.times = check_times(times, "NodalForces")
        n, n_f = body.data.n_nodes, body.n_modes
        forces = np.asarray(forces, dtype=float)
        if forces.shape != (self.times.size, n, 3):
            raise ModelError(f"NodalForces: forces must have shape ({self.times.size}, {n}, 3) "
                             f"for {self.times.size} times and {n} nodes, got {forces.shape}")
        self.frame_fixed = bool(frame_fixed)
        self.forces = forces
        u0 = forces.transpose(0, 2, 1) @ body.data.u0                          # (n_t, 3, 3)
        phi = np.tensordot(forces, body.phi.reshape(n, 3, n_f), axes=([1], [0]))  # (n_t, 3, 3, n_f)
        self._excess = forces.sum(axis=1) - 1.0          # W_k − 1 per row (n_t, 3)
        self._frames = [[Frame(body, u0[r, k], phi[r, k], name=f"row {r} e{k}") for k in range(3)]
                        for r in range(self.times.size)]
        self._origin = body.origin

    @classmethod
    def from_file(cls, body: FlexibleBodyFFR, path, blocked_dofs=None, frame_fixed=True):
        """The nodal forces of a force file (:func:`mbs.links.force_file.read_force_file`) on ``body``."""
        times, forces = read_force_file(path, body.data.n_nodes, blocked_dofs)
        return cls(body, times, forces, frame_fixed)

    def bodies(self):
        return [self.body]

    def breakpoints(self):
        return tuple(self.times)

    def step_loads(self):
        """The forces as :class:`mbs.modal.StepLoads` (the planner's modal solvers)."""
        return StepLoads.from_nodal(self.times, self.forces, "body" if self.frame_fixed else "inertial")

    def add_forces(self, t, q, u, h):
        r = step_index(self.times, t)
        if r < 0:
            return
        qb = q[self.body.q_slice]
        D = self._origin.orientation(qb, t) if self.frame_fixed else np.eye(3)
        Q = self._origin.J_T(qb, t).T @ (D @ self._excess[r])
        for k, frame in enumerate(self._frames[r]):
            Q += frame.J_T(qb, t).T @ D[:, k]
        h[self.body.u_slice] += Q

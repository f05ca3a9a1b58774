"""FlexibleBodyFFR: a flexible body in the floating frame of reference (thesis Sec. 2.4, 4.3).

Built from the body files of :mod:`preprocess` (ū0, Φ, lumped masses or the consistent
mass matrix M_s when the body has one, K) and a mode selection. The shape integrals
(thesis eq. 2.53, 2.54, 2.65; eq. C1 of :mod:`mbs.bodies.shape_integrals` with M_s) are summed
once; after that the mass matrix (eq. 2.44–2.69) and the quadratic velocity vector
(eq. 2.77–2.79) cost O(n_f²) per evaluation, whatever the node count. Elastic forces
K q (eq. 2.36) use the modal stiffness K_ff = Φᵀ K Φ, plus, with ``geometric_stiffening``,
the stiffening by the frame's inertia loads K_geo(Ω, Ω̇, a) (:mod:`mbs.bodies.geometric_stiffening`);
damping is Rayleigh, D = α M_ff + β K_ff, or modal, D = 2 ζ_i ω_i per mode (report Sec. 7.1).

State layout (free frame, quaternion default): q = (R (3), p (4), q_f (n_f)),
u = (Ṙ (3), ω̄ (3), q̇_f (n_f)); with ``rotation="cardan"`` q = (R, θ, q_f), u = q̇;
with a :class:`PrescribedFrameMotion` (e.g. frame-fixed, thesis Sec. 5.1) q = q_f, u = q̇_f.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg

from ffrmbs.errors import ModelError
from preprocess import BodyData, read_body

from mbs.bodies.body import Frame
from mbs.bodies._kernels import (elastic_h_into, ffr_free_energies, ffr_free_mass_and_h, ffr_mass_and_qv,
                                 ffr_prescribed_mass_and_h)
from mbs.bodies.floating_frame import FloatingFrameBody
from mbs.bodies.geometric_stiffening import N_CASES, add_geometric_tangents, load_parameters_into, sub_geometric_force
from mbs.bodies.shape_integrals import ShapeIntegrals


def select_modes(n_available: int, modes) -> np.ndarray:
    """Mode indices from ``modes``: None (all), an int n (the first n) or a list of 0-based indices."""
    if modes is None:
        return np.arange(n_available)
    if isinstance(modes, (int, np.integer)):
        if not 0 <= modes <= n_available:
            raise ModelError(f"asked for {modes} modes, the body has {n_available}")
        return np.arange(int(modes))
    idx = np.asarray(modes, dtype=int).ravel()
    if idx.size and (idx.min() < 0 or idx.max() >= n_available or len(set(idx.tolist())) != idx.size):
        raise ModelError(f"mode list {idx.tolist()} must hold distinct indices in 0..{n_available - 1}")
    return idx


class FlexibleBodyFFR(FloatingFrameBody):
    """A flexible body: rigid frame motion plus a linear combination of mode shapes.

    Parameters
    ----------
    data : BodyData
        The preprocessed body (SI units).
    modes : None, int or sequence of int
        All modes, the first n, or an explicit 0-based list. With None the scene planner
        (:mod:`mbs.run.plan`) may solve the body on the modes that hold most of the loads'
        effective mass (report eq. 36); a number or a list fixes them.
    frame : "free" or PrescribedFrameMotion
    rotation : "quaternion" (default) or "cardan"
    rayleigh : (α [1/s], β [s]) or None
        Rayleigh damping D = α M_ff + β K_ff.
    modal_damping : float or (n_f,) or None
        Damping ratios ζ_i: D = M_ff Ψ diag(2 ζ_i ω_i) Ψᵀ M_ff with the modal eigenvectors Ψ.
    geometric_stiffening : bool
        Add the stiffening by the frame's inertia loads, K_geo(p) q_f (eq. S1 of
        :mod:`mbs.bodies.geometric_stiffening`), from the body file's geometric stiffness
        (``ffrmbs preprocess --geometric-stiffness``). Needed once the spin approaches the
        lowest bending frequency (:class:`mbs.bodies.validity.SpinMonitor`).
    name : str
    """

    def __init__(self, data: BodyData, modes=None, frame="free", rotation="quaternion",
                 rayleigh=None, modal_damping=None, name="flexible", geometric_stiffening=False):
        self.data = data
        self.modes_fixed = modes is not None      # None: all modes, which the planner may reduce
        self.rayleigh, self.modal_damping = rayleigh, modal_damping
        self.mode_indices = select_modes(data.n_modes, modes)
        super().__init__(name, len(self.mode_indices), frame, rotation)
        self.phi = np.ascontiguousarray(data.phi[:, self.mode_indices])
        self.integrals = (ShapeIntegrals.from_nodes(data.u0, self.phi, data.masses) if data.mass_matrix is None
                          else ShapeIntegrals.from_mass_matrix(data.u0, self.phi, data.mass_matrix))
        self.K_ff = self.phi.T @ (data.stiffness @ self.phi)
        self.K_ff = 0.5 * (self.K_ff + self.K_ff.T)
        self.D_ff = self._damping(rayleigh, modal_damping)
        self.damped = bool(self.D_ff.any())       # zero damping: D q̇_f is not evaluated
        self.geometric_stiffening = bool(geometric_stiffening)
        self.K_cases = self._geometric_cases() if self.geometric_stiffening else None
        self._p = np.zeros(N_CASES)               # the load parameters p of eq. S1 (workspace)
        self._eye = np.eye(3)                     # an unread orientation for a free frame's p
        self._p_time = None                       # the time p of a prescribed frame was taken at
        self.phi_nodes = self.phi.reshape(data.n_nodes, 3, self.n_modes)  # (N, 3, n_f) view of phi
        lo, hi = data.u0.min(axis=0), data.u0.max(axis=0)
        self._box_centre = 0.5 * (lo + hi)
        self._box_radius = float(np.linalg.norm(data.u0 - self._box_centre, axis=1).max())
        self._rest_centre = None
        self._phi_reach = np.linalg.norm(self.phi_nodes, axis=1).max(axis=0) if self.n_modes else np.zeros(0)

    @classmethod
    def from_file(cls, path, modes=None, units="si", **kw) -> "FlexibleBodyFFR":
        """Read the body files at ``path`` (directory or .h5, see :func:`preprocess.read_body`)."""
        return cls(read_body(path, units), modes, **kw)

    def _geometric_cases(self):
        """The body file's Φᵀ K_σ,c Φ on the selected modes (12, n_f, n_f), symmetrized."""
        G = self.data.geometric_stiffness
        if G is None:
            raise ModelError(f"{self.name}: geometric_stiffening needs the geometric stiffness in the body file; "
                             "preprocess the body with --geometric-stiffness (ffrmbs preprocess) or "
                             "build_body(..., geometric_stiffness=True)")
        idx = self.mode_indices
        G = G[:, idx][:, :, idx]
        return np.ascontiguousarray(0.5 * (G + G.transpose(0, 2, 1)))

    @property
    def varying_tangents(self) -> bool:
        """True when the stiffness tangent changes with the frame motion (stiffening on a
        moving frame): the integrators then take it from :meth:`add_tangents`."""
        return self.geometric_stiffening and not self.frame_at_rest

    def _frame_loads(self, q, u, t):
        """Write the load parameters p of eq. S1 at the body's own (q, u, t) into ``self._p``
        — a prescribed frame's ω̄, ω̄̇, Aᵀ R̈; a free frame's ω̄ (u[3:6] of a quaternion
        frame, T u_r of a Cardan one) — and return (the array holding ω̄, its offset),
        which a free frame's tangents read."""
        if self.motion is not None:
            if t != self._p_time:                 # p of a prescribed frame depends on t alone
                A, w, wd = (np.asarray(x, dtype=float) for x in self.motion.rotation(t))
                load_parameters_into(w, 0, wd, A, np.asarray(self.motion.translation(t)[2], dtype=float), True,
                                     self._p)
                self._p_time = t
            return self._p, 0
        w, wi = (u, 3) if self.free_quaternion else (self._frame(q, u, t)[3], 0)
        load_parameters_into(w, wi, self._p, self._eye, self._p, False, self._p)
        self._p_time = None
        return w, wi

    def add_tangents(self, t, q, u, K, D):
        """K_geo(p) into the body's tangent block ``K`` (nu, nu) at its own (q, u, t); on a
        free quaternion frame also the −∂h_f/∂ω̄ coupling into ``D`` (nu, nu)
        (:mod:`mbs.bodies.geometric_stiffening`)."""
        if not self.varying_tangents:
            return
        w, wi = self._frame_loads(q, u, t)
        add_geometric_tangents(self.K_cases, self._p, q, self._f.start, self.free_quaternion, w, wi, K, D,
                               self._fu.start, 3)

    def _damping(self, rayleigh, modal_damping):
        n = self.n_modes
        D = np.zeros((n, n))
        M = self.integrals.M_ff
        if rayleigh is not None:
            alpha, beta = rayleigh
            D += alpha * M + beta * self.K_ff
        if modal_damping is not None and n:
            zeta = np.broadcast_to(np.asarray(modal_damping, dtype=float), (n,))
            w2, psi = scipy.linalg.eigh(self.K_ff, M)
            Mpsi = M @ psi
            D += Mpsi @ np.diag(2.0 * zeta * np.sqrt(np.clip(w2, 0.0, None))) @ Mpsi.T
        return D

    # --- frames on the body -------------------------------------------------------------
    def node(self, j: int, orientation=None, name=None) -> Frame:
        """The frame at node ``j`` (0-based): it follows the elastic deformation. Its
        orientation is the body frame's times the constant ``orientation``: lumped nodes
        carry no rotation, so a joint at a node constrains the body frame's rotation, not
        the local material rotation."""
        if not 0 <= j < self.data.n_nodes:
            raise ModelError(f"{self.name}: node {j} outside 0..{self.data.n_nodes - 1}")
        frame = Frame(self, self.data.u0[j], self.phi_nodes[j], orientation, name or f"node {j}")
        frame.node_index = j
        return frame

    def node_group(self, name: str) -> np.ndarray:
        """0-based node indices of the named group of the body file."""
        try:
            return self.data.node_groups[name]
        except KeyError:
            raise ModelError(f"{self.name}: no node group {name!r}; "
                             f"the body has {sorted(self.data.node_groups)}") from None

    def com_frame(self) -> Frame:
        """Centre of mass: ū = (I1 + S̄ q_f)/m = S̄_t/m (thesis eq. 2.55)."""
        si = self.integrals
        return Frame(self, si.I1 / si.mass, si.S_bar / si.mass, None, "centre of mass")

    @property
    def mass(self) -> float:
        return self.integrals.mass

    # --- dynamics from shape integrals --------------------------------------------------
    def _dynamics(self, A, q_f, w, qdot_f):
        """M̄ of thesis eq. 2.44 in (Ṙ, ω̄, q̇_f) (blocks eq. 2.47, 2.50, 2.57, 2.58, 2.66,
        2.69 with ω̄ in place of Ḡ θ̇) and Q̄_v of eq. 2.77–2.79, by the numba kernel
        :func:`mbs.bodies._kernels.ffr_mass_and_qv` (numpy reference: :class:`ShapeIntegrals`)."""
        si = self.integrals
        n = 6 + self.n_modes
        M, Q = np.empty((n, n)), np.empty(n)
        ffr_mass_and_qv(np.ascontiguousarray(A), np.asarray(w, dtype=float), np.asarray(q_f, dtype=float),
                        np.asarray(qdot_f, dtype=float), si.mass, si.I1, si.S_bar, si.I_kl, si.I_bar,
                        si.S_kl, si.M_ff, si.S_skew, M, Q)
        return M, Q

    def mass_and_h_into(self, q, u, t, M, h, work=None):
        """M and h (module docstring of :mod:`mbs.bodies.floating_frame`) by the kernels of
        :mod:`mbs.bodies._kernels`, allocation-free: a frame at rest copies the constant m_ff and
        takes h = −K q_f − D q̇_f; a free quaternion frame and a moving prescribed frame
        contract the shape integrals (a Cardan frame takes the generic path)."""
        if self.frame_at_rest:
            if self._M_rest is None:
                self.mass_matrix(q, t)
            M[...] = self._M_rest
            elastic_h_into(self.K_ff, self.D_ff, self.damped, q, u, h)
            return
        if work is None:
            work = self.workspace()
        si = self.integrals
        if self.free_quaternion:
            ffr_free_mass_and_h(q, u, si.mass, si.I1, si.S_bar, si.I_kl, si.I_bar, si.S_kl, si.M_ff, si.S_skew,
                                self.K_ff, self.D_ff, self.damped, work[0], work[1], M, h)
            if self.geometric_stiffening:
                load_parameters_into(u, 3, self._p, self._eye, self._p, False, self._p)
                self._p_time = None
                sub_geometric_force(self.K_cases, self._p, q, 7, h, 6)
        elif self.motion is not None:
            a_R = np.asarray(self.motion.translation(t)[2], dtype=float)
            A, w, wd = (np.asarray(x, dtype=float) for x in self.motion.rotation(t))
            ffr_prescribed_mass_and_h(A, w, a_R, wd, q, u, si.mass,
                                      si.I1, si.S_bar, si.I_kl, si.I_bar, si.S_kl, si.M_ff, si.S_skew, self.K_ff,
                                      self.D_ff, self.damped, work[1], work[2], work[3], M, h)
            if self.geometric_stiffening:
                load_parameters_into(w, 0, wd, A, a_R, True, self._p)
                self._p_time = t
                sub_geometric_force(self.K_cases, self._p, q, 0, h, 0)
        else:
            super().mass_and_h_into(q, u, t, M, h, work)

    def mass_and_h(self, q, u, t=0.0):
        """(M, h) of :meth:`FloatingFrameBody.mass_and_h` with h_f −= K_geo(p) q_f when the
        stiffening is on and the frame moves (the generic, allocating path)."""
        M, h = super().mass_and_h(q, u, t)
        if self.varying_tangents:
            self._frame_loads(q, u, t)
            sub_geometric_force(self.K_cases, self._p, q, self._f.start, h, self._fu.start)
        return M, h

    def h_into(self, q, u, t, h, work=None):
        if self.frame_at_rest:      # Q_v = 0 with the frame at rest (eq. 4.2)
            elastic_h_into(self.K_ff, self.D_ff, self.damped, q, u, h)
        else:
            super().h_into(q, u, t, h, work)

    def free_energies(self, q, u, gravity, work=None):
        """(kinetic, potential) energy [J] of a body on a free quaternion frame at its own
        (q, u) under ``gravity`` (3,) [m/s²] in one kernel
        (:func:`mbs.bodies._kernels.ffr_free_energies`): T = ½ uᵀ M̄ u and V = ½ q_fᵀ K_ff q_f
        − m g·r_com, as :meth:`kinetic_energy`, :meth:`elastic_energy` and gravity at the
        :meth:`com_frame` give them; None on another frame."""
        if not self.free_quaternion:
            return None
        if work is None:
            work = self.workspace()
        si = self.integrals
        return ffr_free_energies(q, u, si.mass, si.I1, si.S_bar, si.I_kl, si.I_bar, si.S_kl, si.M_ff, si.S_skew,
                                 self.K_ff, gravity, work[0], work[1], work[2], work[3])

    def linear_forces(self):
        """On a frame at rest h = −K_ff q_f − D_ff q̇_f (thesis eq. 2.36; Q_v = 0, eq. 4.2)
        with q = q_f: (K_ff, D_ff, or None when undamped); else None."""
        if not self.frame_at_rest:
            return None
        return self.K_ff, (self.D_ff if self.damped else None)

    def _elastic(self, q_f, qdot_f):
        return self.K_ff @ q_f + self.D_ff @ qdot_f if self.damped else self.K_ff @ q_f

    def elastic_energy(self, q) -> float:
        """½ q_fᵀ K_ff q_f [J]."""
        q_f = q[self._f]
        return 0.5 * q_f @ self.K_ff @ q_f

    def stiffness_tangent(self):
        T = np.zeros((self.nu, self.nu))
        T[self._fu, self._fu] = self.K_ff
        return T

    def damping_tangent(self):
        D = np.zeros((self.nu, self.nu))
        D[self._fu, self._fu] = self.D_ff
        return D

    @property
    def box_centre(self) -> np.ndarray:
        """c (3,) [m]: the centre of the undeformed nodes' box in the body frame, the
        body-frame centre of :meth:`bounding_sphere` (R + A c)."""
        return self._box_centre

    @property
    def rest_radius(self) -> float:
        """max_j |ū0_j − c| [m]: the radius about the centre c of the nodes' box (body
        frame) that holds every undeformed node; the constant part of
        :meth:`bounding_sphere`'s radius."""
        return self._box_radius

    @property
    def mode_reach(self) -> np.ndarray:
        """max_j |Φ_jk| (n_f,) [m per unit q_f,k]: how far mode k moves the node it moves
        most; :meth:`bounding_sphere`'s radius grows by Σ_k mode_reach[k] |q_f,k|."""
        return self._phi_reach

    def bounding_sphere(self, q, t=0.0):
        """Centre R + A c and radius :attr:`rest_radius` + Σ_k mode_reach[k] |q_f,k| (c the
        centre of the nodes' box, :attr:`mode_reach`): holds every node whatever the
        deformation, O(n_f).
        On a frame at rest the centre is computed once and the same array returned."""
        radius = self._box_radius + self._phi_reach @ np.abs(q[self._f])
        if self.frame_at_rest:
            if self._rest_centre is None:
                self._rest_centre = self.point_position(q, Frame(self, self._box_centre), t)
            return self._rest_centre, radius
        R, A, *_ = self._frame(q, None, t)
        return R + A @ self._box_centre, radius

    def node_positions(self, q, nodes=None, t=0.0) -> np.ndarray:
        """Inertial positions (k, 3) [m] of ``nodes`` (all if None), eq. 2.24."""
        idx = slice(None) if nodes is None else np.asarray(nodes)
        ub = self.data.u0[idx] + self.phi_nodes[idx] @ q[self._f]
        R, A, *_ = self._frame(q, None, t)
        return R + ub @ A.T

"""What every contour offers contact kinematics: fields at surface coordinates.

A contour is a curve (1s, one surface coordinate η) or a surface (2s, coordinates η, ξ)
attached to a body (thesis Sec. 3.1, 4.4). Once per step ``update(q, u, t)`` reads the
body state (body-local slices of the System's q and u); then ``evaluate`` fills a
:class:`ContourPoint` workspace at any (η, ξ) with what the contact kinematics of thesis
eq. 3.2–3.8 need:

* position r and its derivatives r_η, r_ξ (tangents t_η, t_ξ, eq. 3.25–3.26) and
  r_ηη, r_ηξ, r_ξξ, all inertial [m];
* the orthonormal right-handed frame (t1, t2, n): n the outward unit normal (eq. 3.27),
  t1 = t_η/|t_η| (eq. 3.28), t2 = n × t1 (eq. 3.29);
* velocity ṙ [m/s];
* Jacobians J_T = ∂ṙ/∂u and J_R = ∂ω/∂u (3, nu) of the body (thesis eq. 2.70, 2.72).

Contours allocate nothing per evaluation: each caller owns its ContourPoint
(:meth:`Contour.new_point`). The convenience methods (``position``, ``frame``, …)
allocate and are meant for scripts and tests.

On a 1s contour, η runs along the curve; ``n`` is the curve normal (a reference
direction given in the body frame, made perpendicular to the tangent) and t2 = n × t1
completes the frame; the ξ entries are zero.
"""

from __future__ import annotations

from abc import ABC, abstractmethod

import numpy as np

from ffrmbs.errors import ModelError

# rows of ContourPoint.derivs and of the contraction kernels
VALUE, D_ETA, D_XI, D_ETA_ETA, D_ETA_XI, D_XI_XI = range(6)
# layout of ContourPoint.buffer: η, ξ, derivs (6, 3), frame (3, 3), v (3,), J_T (3, nu), J_R (3, nu)
ETA_AT, XI_AT, DERIVS_AT, FRAME_AT, V_AT, J_AT = 0, 1, 2, 20, 29, 32


class BufferSlot:
    """An attribute kept as one entry of its object's float vector ``array`` (default
    ``buffer``, the vector a compiled kernel writes) at ``index``, read as ``kind``
    (float, or bool: non-zero), so that it lives in the run's state arrays with the rest
    (:mod:`mbs.run.contact_state`)."""

    def __init__(self, index: int, kind=float, array="buffer"):
        self.index, self.kind, self.array = index, kind, array

    def __get__(self, obj, owner=None):
        return self if obj is None else self.kind(getattr(obj, self.array)[self.index])

    def __set__(self, obj, value):
        getattr(obj, self.array)[self.index] = float(value)


class ContourPoint:
    """Workspace of one evaluated contour point (all inertial unless said otherwise).

    Attributes
    ----------
    eta, xi : float
        Surface coordinates where it was evaluated (xi = 0 on 1s contours).
    derivs : (6, 3) [m]
        r, r_η, r_ξ, r_ηη, r_ηξ, r_ξξ; also exposed as ``r``, ``t_eta``, ``t_xi``.
    frame : (3, 3)
        Columns t1, t2, n (orthonormal, right-handed).
    v : (3,) [m/s]
        Velocity ṙ (filled when asked for).
    J_T, J_R : (3, nu)
        Jacobians of translation and rotation (filled when asked for).
    buffer : (32 + 6 nu,)
        η, ξ and the arrays above are this one vector (layout ``ETA_AT``, ``XI_AT``,
        ``DERIVS_AT``, ``FRAME_AT``, ``V_AT``, ``J_AT``: derivs row-major, frame row-major,
        v, J_T row-major, J_R row-major), so that a compiled kernel takes a point as one
        array.
    """

    state_slots = ("buffer",)   # the run state (mbs.run.contact_state)
    eta, xi = BufferSlot(ETA_AT), BufferSlot(XI_AT)

    def __init__(self, nu: int):
        self.buffer = np.zeros(J_AT + 6 * nu)
        self.bind_views()

    def bind_views(self) -> None:
        """The named views of :attr:`buffer` (again after it moved into a run's state)."""
        b, nu = self.buffer, (self.buffer.size - J_AT) // 6
        self.derivs = b[DERIVS_AT:FRAME_AT].reshape(6, 3)
        self.frame = b[FRAME_AT:V_AT].reshape(3, 3)
        self.v = b[V_AT:J_AT]
        self.J_T = b[J_AT:J_AT + 3 * nu].reshape(3, nu)
        self.J_R = b[J_AT + 3 * nu:].reshape(3, nu)

    @property
    def r(self) -> np.ndarray:
        return self.derivs[VALUE]

    @property
    def t_eta(self) -> np.ndarray:
        return self.derivs[D_ETA]

    @property
    def t_xi(self) -> np.ndarray:
        return self.derivs[D_XI]

    @property
    def t1(self) -> np.ndarray:
        return self.frame[:, 0]

    @property
    def t2(self) -> np.ndarray:
        return self.frame[:, 1]

    @property
    def n(self) -> np.ndarray:
        return self.frame[:, 2]


class Contour(ABC):
    """A contour on ``body`` (see module docstring).

    Subclasses set ``dim`` (1 or 2), ``domain`` ((η_min, η_max) or two such pairs),
    ``closed`` (one flag per surface coordinate) and implement :meth:`update`,
    :meth:`evaluate` and :meth:`bounding_box`.
    """

    dim: int
    name: str
    #: the contacts on this contour see the static compliance of the modes its body leaves
    #: out (:mod:`contours.residual`); set on neutral contours and those derived from them
    residual_flexibility = False
    #: a surface trimmed to its material (:class:`contours.fitting.Trim`, a face with
    #: holes): a point whose (η, ξ) lies in a hole is no point of the contour; else None
    trim = None

    def __init__(self, body, name):
        self.body = body
        self.name = name
        self.nu = body.nu if body is not None else 0

    @abstractmethod
    def update(self, q, u=None, t=0.0) -> None:
        """Read the body state (its own q, u slices) once per step."""

    @abstractmethod
    def evaluate(self, point: ContourPoint, eta: float, xi: float = 0.0,
                 velocity: bool = False, jacobians: bool = False) -> ContourPoint:
        """Fill ``point`` at (η, ξ): positions, derivatives and frame always; the
        velocity and the Jacobians when asked for. Returns ``point``."""

    @abstractmethod
    def bounding_box(self, out=None) -> np.ndarray:
        """(2, 3) [m] (rows min, max) into ``out`` (a new array if None): an axis-aligned
        box containing the whole contour at the last update (conservative; for the broad
        phase, which passes preallocated boxes)."""

    def new_point(self) -> ContourPoint:
        """A workspace for :meth:`evaluate`."""
        return ContourPoint(self.nu)

    # --- convenience (allocating) -------------------------------------------------------
    def _at(self, eta, xi, **kw):
        return self.evaluate(self.new_point(), eta, xi, **kw)

    def position(self, eta, xi=0.0) -> np.ndarray:
        """r(η, ξ) (3,) [m]."""
        return self._at(eta, xi).r.copy()

    def frame(self, eta, xi=0.0) -> np.ndarray:
        """(t1, t2, n) as columns of a (3, 3) rotation matrix."""
        return self._at(eta, xi).frame.copy()

    def normal(self, eta, xi=0.0) -> np.ndarray:
        """Outward unit normal n (3,)."""
        return self._at(eta, xi).n.copy()

    def velocity(self, eta, xi=0.0) -> np.ndarray:
        """ṙ(η, ξ) (3,) [m/s]."""
        return self._at(eta, xi, velocity=True).v.copy()

    def J_T(self, eta, xi=0.0) -> np.ndarray:
        """∂ṙ/∂u (3, nu) at (η, ξ)."""
        return self._at(eta, xi, jacobians=True).J_T.copy()

    def J_R(self, eta, xi=0.0) -> np.ndarray:
        """∂ω/∂u (3, nu) at (η, ξ)."""
        return self._at(eta, xi, jacobians=True).J_R.copy()

    def sample(self, n_eta=20, n_xi=10) -> np.ndarray:
        """Positions on a regular grid of surface coordinates: (n_eta, 3) on 1s contours,
        (n_eta, n_xi, 3) on 2s contours [m]."""
        point = self.new_point()
        etas = _grid(self._eta_domain(), n_eta, self._closed(0))
        if self.dim == 1:
            return np.array([self.evaluate(point, e).r.copy() for e in etas])
        xis = _grid(self.domain[1], n_xi, self._closed(1))
        return np.array([[self.evaluate(point, e, x).r.copy() for x in xis] for e in etas])

    def to_trimesh(self, n_eta=40, n_xi=10, radius=None):
        """The contour sampled to a :class:`trimesh.Trimesh` (visualization, bounding boxes):
        a 2s contour as its surface grid; a 1s contour as a tube of ``radius`` [m]
        around the curve (default: 1 % of the curve's bounding-box diagonal)."""
        from .sampling import surface_mesh, tube_mesh

        if self.dim == 2:
            return surface_mesh(self.sample(n_eta, n_xi), self._closed(0), self._closed(1))
        return tube_mesh(self, n_eta, n_xi, radius)

    def _eta_domain(self):
        return self.domain if self.dim == 1 else self.domain[0]

    def _closed(self, axis) -> bool:
        return bool(self.closed[axis])

    def __repr__(self):
        owner = "ground" if self.body is None else self.body.name
        return f"{type(self).__name__}({self.name!r} on {owner})"


def _grid(domain, n, closed):
    if n < 2:
        raise ModelError(f"need at least 2 samples per surface coordinate, got {n}")
    return np.linspace(domain[0], domain[1], n, endpoint=not closed)

"""Hierarchical contact search: the closest point of a contour to a given point.

After thesis Sec. 3.3 and Algorithms 4–6 (MBSim's ``Contact2sSearch``). For a point P
(position r_P [m]) and a contour r(η, ξ), the candidate contact points solve the
necessary conditions eq. 3.6, the tangent projections of g = r_P − r (eq. 3.30)

    g_η = t_ηᵀ g = 0,   g_ξ = t_ξᵀ g = 0          (eq. 3.31–3.32; 1s: g_η only)

with t_η = r_η, t_ξ = r_ξ. :meth:`Contact2sSearch.solve` works on two levels:

1. **warm start** — Newton from the last successful (η, ξ), if given (Algorithm 6);
2. **coarse level** — when there is no start or Newton fails: g_η, g_ξ at the nodes of a
   grid on the domain; cells in which both change sign (or vanish) at their corners hold
   candidate roots (Algorithm 4); Newton from each cell centre (finer level, Algorithm 5);
   among the converged roots, the one nearest to P (smallest |g|).

Newton uses the exact Jacobian of (g_η, g_ξ) with respect to (η, ξ),

    H = [[r_ηηᵀ g − t_ηᵀ t_η, r_ηξᵀ g − t_ηᵀ t_ξ],
         [r_ηξᵀ g − t_ηᵀ t_ξ, r_ξξᵀ g − t_ξᵀ t_ξ]]   (= −the Hessian of |g|²/2)

from the contour's second derivatives (rows of :attr:`ContourPoint.derivs`) where H is
negative definite (near a distance minimum), else the Gauss–Newton matrix
−[[t_ηᵀ t_η, t_ηᵀ t_ξ], [·, t_ξᵀ t_ξ]] (always a descent direction of |g|; singular only
where the parametrization degenerates, e.g. a sphere's pole: the start fails). A step is
capped at one grid cell per coordinate. Newton has converged when the tangential
components of g, |g_η|/|t_η| and |g_ξ|/|t_ξ| [m], are below ``tol`` × the contour's length
scale; the root counts only if it is a local minimum of |g| (a maximum or saddle of eq. 3.6
— e.g. the far side of a cylinder — is no contact point). Closed directions wrap the
parameter; on an open direction an iterate is clipped to the domain. A point whose closest
point of the domain is on its boundary projects onto the boundary: an iterate on a bound
has converged in that coordinate when the point lies beyond the bound by at most
``edge_tol`` × the length scale (the projection clamped to [η0, η1] × [ξ0, ξ1], so that a
point exactly on the boundary — a node of the face's edge — is on the contour whatever
the rounding; :func:`._detection_kernels.stationary`). A second clip in a row rejects the
start (the root lies outside the contour: no contact point there). The coarse level
counts a cell as a candidate when g_η, g_ξ change sign or are within the same tolerance
of zero at its corners.
On a trimmed surface (``contour.trim``, a face with holes: :mod:`contours.fitting.trim`)
a root inside a hole is rejected likewise; it is kept (``hole``) as the next warm start,
and a warm start that converges into a hole again ends the solve without the coarse level
(the nearest point of the surface is in a hole: no contact point).

On a compiled neutral contour (:class:`~contours.neutral.factory.NeutralContour`, the
default) Newton runs as one numba kernel per start (:func:`._detection_kernels.newton_2s`,
:func:`._detection_kernels.newton_1s`) that evaluates the contour span-locally from its
state, and so on a compiled band or cylinder (:mod:`contours.derived`,
:func:`._detection_kernels.newton_offset`, over its neutral curve's state);
``compiled=False`` (or any other contour) runs the Python reference
(``_newton_reference``) over ``contour.evaluate``. Both give the same iterates up to
rounding.
"""

from __future__ import annotations

import numpy as np

from ffrmbs.errors import ModelError

from contours.base import D_ETA, D_ETA_ETA, D_ETA_XI, D_XI, D_XI_XI, VALUE
from contours.derived import OffsetContour
from contours.neutral import NeutralContour

from . import _detection_kernels as K
from ._detection_kernels import SINGULAR as _SINGULAR


EDGE_TOL = 3e-7     # default edge_tol: a point 3e-7 length scales beyond the boundary projects onto it
NEWTON_SOLVES, NEWTON_ITERATIONS, LAST_ITERATIONS, COARSE_SEARCHES = range(4)   # entries of _Search.counts


def _set(search, which, n):
    search.counts[which] = n


class _Axis:
    """One surface coordinate of the search grid: domain [a, b], closedness, grid nodes and
    the cells between neighbouring nodes (on a closed direction the last cell wraps)."""

    def __init__(self, domain, closed):
        self.a, self.b = (float(x) for x in domain)
        self.closed = bool(closed)
        self.period = self.b - self.a

    def set_cells(self, n):
        """n equal cells on the domain."""
        if int(n) < 1:
            raise ModelError(f"the search grid needs at least one cell per surface coordinate, got {n}")
        nodes = np.linspace(self.a, self.b, int(n) + 1)
        self.set_nodes(nodes[:-1] if self.closed else nodes)

    def set_nodes(self, nodes):
        """Given grid nodes: strictly increasing, inside [a, b] ([a, b) when closed)."""
        nodes = np.asarray(nodes, dtype=float).ravel()
        upper_ok = nodes.size and (nodes[-1] < self.b if self.closed else nodes[-1] <= self.b)
        if nodes.size < 2 or not (np.diff(nodes) > 0).all() or nodes[0] < self.a or not upper_ok:
            raise ModelError(f"search grid nodes must be >= 2 strictly increasing values in the domain "
                             f"[{self.a}, {self.b}{')' if self.closed else ']'}, got {nodes}")
        self.nodes = nodes
        k = nodes.size
        self.lo = np.arange(k) if self.closed else np.arange(k - 1)  # cell start node
        self.hi = (self.lo + 1) % k                                    # cell end node
        ends = np.append(nodes[1:], nodes[0] + self.period) if self.closed else nodes[1:]
        self.centres = 0.5 * (nodes[self.lo] + ends)
        self.max_step = float((ends - nodes[self.lo]).max())

    def step(self, t, dt):
        """t + dt with |dt| capped at the largest cell width (Newton stays near its start
        cell), wrapped or clipped by :meth:`wrap`."""
        return self.wrap(t + min(max(dt, -self.max_step), self.max_step))

    def side(self, t):
        """+1 on the upper bound of an open direction, −1 on the lower, else 0
        (:func:`._detection_kernels.side`)."""
        return K.side(t, self.a, self.b, self.closed)

    def wrap(self, t):
        """(t in the domain, True if an open direction had to clip t)."""
        if self.closed:
            return self.a + (t - self.a) % self.period, False
        if t < self.a:
            return self.a, True
        if t > self.b:
            return self.b, True
        return t, False


def _sign_change(corners, zero):
    """Cells whose corner values (k, ...) include both signs or a zero (|value| ≤ zero)."""
    return (corners.min(axis=0) <= zero) & (corners.max(axis=0) >= -zero)


def _unit_projection(t, g):
    """tᵀ g / |t| [m] (0 where t vanishes): the tangent projection of eq. 3.31–3.32 as a
    length, so that roundoff zeros compare with the length tolerance."""
    a = np.sqrt(t @ t)
    return (t @ g) / a if a > 0.0 else 0.0


class _Search:
    """Shared settings and diagnostics of the 1s and 2s searches.

    Attributes
    ----------
    tol : float
        Newton tolerance relative to ``length_scale``.
    edge_tol : float
        How far beyond the domain's boundary a point may lie and still project onto it,
        relative to ``length_scale`` (module docstring).
    max_iter : int
        Newton iterations per start.
    length_scale : float [m]
        Extent of the contour (default: the diagonal of the box around the grid nodes'
        positions at the first solve).
    newton_iterations, newton_solves, coarse_searches : int
        Counters since construction or :meth:`reset_counters`.
    last_iterations : int
        Newton iterations of the last converged start.
    counts : (4,) int64
        The four counters, at ``NEWTON_SOLVES``, ``NEWTON_ITERATIONS``,
        ``LAST_ITERATIONS``, ``COARSE_SEARCHES`` (a compiled detection counts there).
    compiled : bool
        Newton runs in the numba kernel: asked for (``compiled=True``) and the contour is
        a compiled neutral contour or a compiled band or cylinder (decided at construction).
    hole : (dim,)
        After a solve that found no contact point: the surface coordinates of a distance
        minimum that lay in a hole of a trimmed contour, else NaN (a warm start for the
        next solve, which then skips the coarse level while the point stays over the hole).
    """

    dim: int
    #: what a solve changes and the next one reads (the run state, :mod:`mbs.run.contact_state`):
    #: the length scale (NaN until the first search fixes it), the counters, the hole
    state_slots = ("_scale", "counts", "hole")

    def __init__(self, contour, tol, max_iter, length_scale, compiled, edge_tol=EDGE_TOL):
        if contour.dim != self.dim:
            raise ModelError(f"{type(self).__name__} needs a {self.dim}s contour, got {contour!r}")
        self.contour = contour
        self._point = contour.new_point()
        self._g = np.zeros(3)
        self.tol = float(tol)
        self.edge_tol = float(edge_tol)
        self.max_iter = int(max_iter)
        self._scale = np.array([np.nan if length_scale is None else float(length_scale)])
        self.compiled = (bool(compiled) and isinstance(contour, (NeutralContour, OffsetContour))
                         and contour.compiled)
        self._work = contour.kernel_workspace() + (self._g,) if self.compiled else None
        self.counts = np.zeros(4, dtype=np.int64)
        self.hole = np.full(self.dim, np.nan)

    def reset_counters(self):
        self.counts[:] = 0

    newton_solves = property(lambda self: int(self.counts[NEWTON_SOLVES]), lambda self, n: _set(self, NEWTON_SOLVES, n))
    newton_iterations = property(lambda self: int(self.counts[NEWTON_ITERATIONS]),
                                 lambda self, n: _set(self, NEWTON_ITERATIONS, n))
    last_iterations = property(lambda self: int(self.counts[LAST_ITERATIONS]),
                               lambda self, n: _set(self, LAST_ITERATIONS, n))
    coarse_searches = property(lambda self: int(self.counts[COARSE_SEARCHES]),
                               lambda self, n: _set(self, COARSE_SEARCHES, n))

    @property
    def length_scale(self) -> float:
        if np.isnan(self._scale[0]):
            r = self._grid_positions()
            self._scale[0] = float(np.linalg.norm(r.max(axis=0) - r.min(axis=0))) or 1.0
        return float(self._scale[0])

    def _tol2(self):
        return (self.tol * self.length_scale) ** 2

    def _edge2(self):
        """(edge_tol · length scale)² [m²]."""
        return (self.edge_tol * self.length_scale) ** 2

    def _zero(self):
        """|g_η|, |g_ξ| [m] that count as zero at the coarse grid's nodes."""
        return np.sqrt(max(self._tol2(), self._edge2()))

    @property
    def newton_work(self):
        """The compiled Newton's work arrays (the contour's ``kernel_workspace()`` and
        g (3,)), for a fused detection (:mod:`mbs.run.fused_detection`); None on the
        reference route."""
        return self._work

    def newton_settings(self):
        """(largest step per surface coordinate (tuple), (tol · length scale)² [m²],
        (edge_tol · length scale)² [m²], iterations) of Newton, as the kernels take them;
        None while the length scale is not known (it is fixed at the first search, module
        docstring)."""
        if np.isnan(self._scale[0]):
            return None
        return tuple(ax.max_step for ax in self.axes), self._tol2(), self._edge2(), self.max_iter

    def _grid_positions(self):
        """Positions of the grid nodes (k, 3) [m] at the contour's current state."""
        p = self._point
        grids = np.meshgrid(*(ax.nodes for ax in self.axes), indexing="ij")
        return np.array([self.contour.evaluate(p, *c).r.copy() for c in zip(*(g.ravel() for g in grids))])


class Contact2sSearch(_Search):
    """Closest point of a 2s contour to a point (thesis Sec. 3.3, Algorithms 4–6; see
    the module docstring).

    Parameters
    ----------
    contour : 2s contour (``dim == 2``: neutral 2s, band, cylinder, sphere, plane)
    n_eta, n_xi : int
        Cells of the equally spaced coarse grid per surface coordinate (thesis Fig. 3.6:
        4 × 3); ignored when ``nodes`` is given.
    nodes : (eta_nodes, xi_nodes) or None
        Coarse-grid node coordinates (e.g. the FE node parameters).
    tol, max_iter, length_scale, edge_tol : see :class:`_Search`.
    compiled : bool
        Newton in the numba kernel on a compiled neutral contour (default), else the
        Python reference.
    """

    dim = 2

    def __init__(self, contour, n_eta=8, n_xi=8, nodes=None, tol=1e-10, max_iter=20, length_scale=None,
                 compiled=True, edge_tol=None):
        super().__init__(contour, tol, max_iter, length_scale, compiled, EDGE_TOL if edge_tol is None else edge_tol)
        self.axes = (_Axis(contour.domain[0], contour.closed[0]), _Axis(contour.domain[1], contour.closed[1]))
        if nodes is None:
            self.set_equal_spacing(n_eta, n_xi)
        else:
            self.set_nodes(*nodes)

    def set_equal_spacing(self, n_eta, n_xi):
        """A coarse grid of n_eta × n_xi equal cells."""
        self.axes[0].set_cells(n_eta)
        self.axes[1].set_cells(n_xi)
        self._alloc()

    def set_nodes(self, eta_nodes, xi_nodes):
        """A coarse grid through the given node coordinates."""
        self.axes[0].set_nodes(eta_nodes)
        self.axes[1].set_nodes(xi_nodes)
        self._alloc()

    def _alloc(self):
        self._G = np.zeros((2, self.axes[0].nodes.size, self.axes[1].nodes.size))

    def solve(self, r_point, start=None):
        """Surface coordinates (η, ξ) of the contact point C2 of the point at ``r_point``
        (3,) [m], or None when there is none inside the domain. ``start``: the last
        successful (η, ξ) (warm start)."""
        r_point = np.asarray(r_point, dtype=float)
        self.hole[:] = np.nan
        if start is not None:
            root = self._newton(r_point, start[0], start[1])
            if root is not None:
                return root[:2]
            if not np.isnan(self.hole[0]):
                return None                      # the nearest point lies in a hole: no contact point
        root = self._coarse(r_point)
        if root is not None:
            self.hole[:] = np.nan
        return None if root is None else root[:2]

    def _coarse(self, r_point):
        """Algorithm 4–6: sign changes of g_η, g_ξ on the grid, Newton in each candidate
        cell, the nearest root. Returns (η, ξ, |g|²) or None."""
        self.coarse_searches += 1
        ax_e, ax_x = self.axes
        p, D, G = self._point, self._point.derivs, self._G
        for i, eta in enumerate(ax_e.nodes):
            for j, xi in enumerate(ax_x.nodes):
                self.contour.evaluate(p, eta, xi)
                g = np.subtract(r_point, D[VALUE], out=self._g)
                G[0, i, j] = _unit_projection(D[D_ETA], g)
                G[1, i, j] = _unit_projection(D[D_XI], g)
        I0, I1, J0, J1 = ax_e.lo[:, None], ax_e.hi[:, None], ax_x.lo[None, :], ax_x.hi[None, :]
        corners = np.stack([G[:, I0, J0], G[:, I1, J0], G[:, I0, J1], G[:, I1, J1]])
        candidates = _sign_change(corners, self._zero()).all(axis=0)
        best = None
        for i, j in zip(*np.nonzero(candidates)):
            root = self._newton(r_point, ax_e.centres[i], ax_x.centres[j])
            if root is not None and (best is None or root[2] < best[2]):
                best = root
        return best

    def _newton(self, r_point, eta, xi):
        """Newton on eq. 3.6 from (η, ξ); returns (η, ξ, |g|²) at a local minimum of the
        distance, or None. The kernel :func:`._detection_kernels.newton_2s` (on a band or
        cylinder :func:`._detection_kernels.newton_offset`) when :attr:`compiled`, else
        :meth:`_newton_reference`."""
        if not self.compiled:
            return self._newton_reference(r_point, eta, xi)
        self.newton_solves += 1
        ax_e, ax_x = self.axes
        contour = self.contour
        if isinstance(contour, OffsetContour):
            found, eta, xi, gg, k, steps = K.newton_offset(
                r_point, float(eta), float(xi), *contour.neutral.kernel_data, contour.neutral.normal_ref,
                *contour.offset_law, ax_x.a, ax_x.b, ax_x.closed, ax_e.max_step, ax_x.max_step, self._tol2(),
                self._edge2(), self.max_iter, *self._work)
        else:
            found, eta, xi, gg, k, steps = K.newton_2s(r_point, float(eta), float(xi), *contour.kernel_data,
                                                       ax_e.max_step, ax_x.max_step, self._tol2(), self._edge2(),
                                                       self.max_iter, *self._work)
        self.newton_iterations += steps
        if not found or not self._on_material(eta, xi):
            return None
        self.last_iterations = k
        return eta, xi, gg

    def _on_material(self, eta, xi) -> bool:
        """False when the contour is trimmed and (η, ξ) lies in one of its holes (then
        kept in :attr:`hole`)."""
        trim = self.contour.trim
        if trim is None or trim.contains(eta, xi):
            return True
        self.hole[:] = eta, xi
        return False

    def _newton_reference(self, r_point, eta, xi):
        """The Python reference of :meth:`_newton`, over ``contour.evaluate``."""
        self.newton_solves += 1
        ax_e, ax_x = self.axes
        eta, _ = ax_e.wrap(float(eta))
        xi, _ = ax_x.wrap(float(xi))
        p, D, tol2, edge2, clipped = self._point, self._point.derivs, self._tol2(), self._edge2(), 0
        for k in range(self.max_iter + 1):
            self.contour.evaluate(p, eta, xi)
            g = np.subtract(r_point, D[VALUE], out=self._g)
            te, tx = D[D_ETA], D[D_XI]
            f0, f1 = te @ g, tx @ g
            a, b, c = te @ te, te @ tx, tx @ tx
            h11, h12, h22 = D[D_ETA_ETA] @ g - a, D[D_ETA_XI] @ g - b, D[D_XI_XI] @ g - c
            det = h11 * h22 - h12 * h12
            minimum = h11 < 0.0 and det > _SINGULAR * a * c
            if (K.stationary(f0, a, tol2, edge2, ax_e.side(eta))
                    and K.stationary(f1, c, tol2, edge2, ax_x.side(xi))):
                if not minimum or not self._on_material(eta, xi):
                    return None  # a maximum or saddle of the distance, or a hole: not the contact point
                self.last_iterations = k
                return eta, xi, g @ g
            if k == self.max_iter:
                break
            self.newton_iterations += 1
            if not minimum:  # Gauss–Newton: a descent direction of |g|²
                h11, h12, h22, det = -a, -b, -c, a * c - b * b
                if det <= _SINGULAR * a * c:
                    return None  # degenerate parametrization (e.g. a sphere's pole)
            eta, out_e = ax_e.step(eta, (h12 * f1 - h22 * f0) / det)
            xi, out_x = ax_x.step(xi, (h12 * f0 - h11 * f1) / det)
            clipped = clipped + 1 if (out_e or out_x) else 0
            if clipped == 2:
                return None
        return None


class Contact1sSearch(_Search):
    """Closest point of a 1s contour (curve) to a point: eq. 3.6 with the one tangent
    projection g_η = t_ηᵀ (r_P − r(η)), the search of :class:`Contact2sSearch` in 1D.

    Parameters
    ----------
    contour : 1s contour (``dim == 1``)
    n : int
        Cells of the equally spaced coarse grid; ignored when ``nodes`` is given.
    nodes : (k,) or None
        Coarse-grid node coordinates.
    tol, max_iter, length_scale, compiled, edge_tol : see :class:`Contact2sSearch`.
    """

    dim = 1

    def __init__(self, contour, n=16, nodes=None, tol=1e-10, max_iter=20, length_scale=None, compiled=True,
                 edge_tol=None):
        super().__init__(contour, tol, max_iter, length_scale, compiled, EDGE_TOL if edge_tol is None else edge_tol)
        self.axes = (_Axis(contour.domain, contour.closed[0]),)
        if nodes is None:
            self.set_equal_spacing(n)
        else:
            self.set_nodes(nodes)

    def set_equal_spacing(self, n):
        """A coarse grid of n equal cells."""
        self.axes[0].set_cells(n)
        self._G = np.zeros(self.axes[0].nodes.size)

    def set_nodes(self, eta_nodes):
        """A coarse grid through the given node coordinates."""
        self.axes[0].set_nodes(eta_nodes)
        self._G = np.zeros(self.axes[0].nodes.size)

    def solve(self, r_point, start=None):
        """Curve coordinate η of the contact point of the point at ``r_point`` (3,) [m], or
        None when there is none inside the domain. ``start``: the last successful η."""
        r_point = np.asarray(r_point, dtype=float)
        if start is not None:
            root = self._newton(r_point, start)
            if root is not None:
                return root[0]
        root = self._coarse(r_point)
        return None if root is None else root[0]

    def _coarse(self, r_point):
        self.coarse_searches += 1
        ax = self.axes[0]
        p, D, G = self._point, self._point.derivs, self._G
        for i, eta in enumerate(ax.nodes):
            self.contour.evaluate(p, eta)
            G[i] = _unit_projection(D[D_ETA], np.subtract(r_point, D[VALUE], out=self._g))
        candidates = _sign_change(np.stack([G[ax.lo], G[ax.hi]]), self._zero())
        best = None
        for i in np.nonzero(candidates)[0]:
            root = self._newton(r_point, ax.centres[i])
            if root is not None and (best is None or root[1] < best[1]):
                best = root
        return best

    def _newton(self, r_point, eta):
        """Newton on t_ηᵀ (r_P − r(η)) = 0 from η; returns (η, |g|²) at a local minimum of
        the distance, or None. The kernel :func:`._detection_kernels.newton_1s` when
        :attr:`compiled`, else :meth:`_newton_reference`."""
        if not self.compiled:
            return self._newton_reference(r_point, eta)
        self.newton_solves += 1
        found, eta, gg, k, steps = K.newton_1s(r_point, float(eta), *self.contour.kernel_data, self.axes[0].max_step,
                                               self._tol2(), self._edge2(), self.max_iter, *self._work)
        self.newton_iterations += steps
        if not found:
            return None
        self.last_iterations = k
        return eta, gg

    def _newton_reference(self, r_point, eta):
        """The Python reference of :meth:`_newton`, over ``contour.evaluate``."""
        self.newton_solves += 1
        ax = self.axes[0]
        eta, _ = ax.wrap(float(eta))
        p, D, tol2, edge2, clipped = self._point, self._point.derivs, self._tol2(), self._edge2(), 0
        for k in range(self.max_iter + 1):
            self.contour.evaluate(p, eta)
            g = np.subtract(r_point, D[VALUE], out=self._g)
            te = D[D_ETA]
            f, a = te @ g, te @ te
            h = D[D_ETA_ETA] @ g - a
            minimum = h < -_SINGULAR * a
            if K.stationary(f, a, tol2, edge2, ax.side(eta)):
                if not minimum:
                    return None  # a maximum of the distance: not the contact point
                self.last_iterations = k
                return eta, g @ g
            if k == self.max_iter or a == 0.0:
                break
            self.newton_iterations += 1
            eta, out = ax.step(eta, -f / (h if minimum else -a))  # else Gauss–Newton
            clipped = clipped + 1 if out else 0
            if clipped == 2:
                return None
        return None

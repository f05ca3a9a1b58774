"""α–Ω decision boundaries between SimpleRB and CoupledRB (report Sec. 4.1, eq. 29-32; Sec. 5.4, Fig. 9).

SimpleRB ignores the fictitious forces of the rotating body frame; the question is
for which angular accelerations α and velocities Ω the deformation they cause is
negligible (SimpleRB), noticeable (CoupledRB) or beyond linear elasticity.

Fictitious forces (eq. 22/29) with the Coriolis term dropped and b ≈ b0 (the
undeformed positions relative to the centre of mass), per node n:

    f_n = −m_n α × b_n − m_n Ω × (Ω × b_n) = m_n [b_n]× α + m_n (|Ω|² b_n − (Ω·b_n) Ω).

The α part is *linear* in α, the Ω part *quadratic* in Ω.

Force limit (eq. 30-31): |f_n| <= m_n |b_n| (|α| + |Ω|²), so the fictitious forces
stay below f_lim when |α| + |Ω|² <= f_lim / max_n(m_n |b_n|) (:func:`force_limit`).

Displacement limit (eq. 32), derived properly. The report writes
max_nodes(P (Pᵀ ⊙ 1/ω²) m|b|) (|α| + |Ω|²): it projects the *magnitudes* m_n|b_n|
as if they were a force vector, and its "≥" points the wrong way for a bound. We
use instead the quasi-static elastic response of the retained modes (eq. 12 with
the oscillating part bounded below):

    u = Φ diag(1/ω²) Φᵀ f,

which is linear in f, hence u = U_α α + |Ω|² u_Ω(Ω/|Ω|) with U_α (3N, 3) and
u_Ω a quadratic form in the unit direction. Then

    d_alpha = max_{|α̂|=1} max_n |u_n| = max_n σ_max(U_α,n)   (3x3 node blocks, exact),
    d_omega = max_{|Ω̂|=1} max_n |u_n(Ω̂)|                        (sampled + refined),

and by the triangle inequality the displacement for (α, Ω) is at most
d_alpha |α| + d_omega |Ω|² quasi-statically. A suddenly applied constant load on an
undamped oscillator peaks at twice its static response (r = F/ω² (1 − cos ωt),
eq. 10), so the estimate is d ≈ k_dyn (d_alpha |α| + d_omega |Ω|²) with k_dyn = 2 by
default (exact for one dominant mode; 1 gives the static estimate). The report's
single-number form is |α| + |Ω|² <= d_lim / (k_dyn max(d_alpha, d_omega)).

Mass: ``masses`` is the lumped node masses (N,) or, for a body with a consistent mass
matrix, the scalar M_s (N, N) sparse; the fictitious loads are then the consistent
f = −M (α × b) − M (Ω × (Ω × b)) (M = M_s ⊗ 1₃, :func:`preprocess.body.mass_times`) and
the centre of mass that of M. The force limit (eq. 30-31) is a per-node bound and takes
the lumped masses only.

Inertia relief: for a free body whose modes are M-orthogonal to the rigid modes
(preprocess.modes.free_modes), the α part −M(α × b) is M times a rigid rotation
mode, so Φᵀ f_α = 0 and d_alpha vanishes (to rounding): the torque that causes α
and its d'Alembert load balance. Only the centrifugal part deforms such a body.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.optimize import minimize

from ffrmbs.errors import ModelError
from preprocess.body import mass_times

SIMPLE, COUPLED, OUTSIDE = "SimpleRB", "CoupledRB", "outside linear elasticity"
_MONOMIALS = ((0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2))  # q = (x², y², z², xy, xz, yz)


def _positions(u0, masses):
    """Validated u0 (N, 3) [m], masses (N,) or sparse M_s (N, N) [kg] and b = u0 − centre
    of mass (N, 3) [m], the centre of mass Σ w u0 / Σ w with w = M_s 1 (w = masses when lumped)."""
    u0 = np.asarray(u0, dtype=float)
    if sp.issparse(masses):
        if u0.ndim != 2 or u0.shape[1] != 3 or masses.shape != (u0.shape[0],) * 2:
            raise ModelError(f"u0 must be (N, 3) and the mass matrix (N, N), got {u0.shape} and {masses.shape}")
        w = np.asarray(masses.sum(axis=1)).ravel()
        return u0, masses, u0 - w @ u0 / w.sum()
    masses = np.asarray(masses, dtype=float)
    if u0.ndim != 2 or u0.shape[1] != 3 or masses.shape != (u0.shape[0],):
        raise ModelError(f"u0 must be (N, 3) and masses (N,), got {u0.shape} and {masses.shape}")
    if np.any(masses <= 0):
        raise ModelError("node masses must be positive")
    return u0, masses, u0 - masses @ u0 / masses.sum()


def force_limit(u0, masses, f_lim) -> float:
    """Right-hand side of report eq. 31: f_lim / max_n(m_n |b_n|) [1/s²].

    ``u0`` (N, 3) [m], ``masses`` (N,) [kg], ``f_lim`` [N]: the largest fictitious
    node force accepted as negligible; b_n = u0_n − centre of mass. SimpleRB is
    acceptable while |α| + |Ω|² stays below the returned value (eq. 30 bounds every
    node force by m_n |b_n| (|α| + |Ω|²)). Lumped node masses only (a ModelError for a
    mass matrix: its node forces are not m_n times a node's acceleration).
    """
    if sp.issparse(masses):
        raise ModelError("force_limit takes lumped node masses (N,), not a mass matrix")
    _, masses, b = _positions(u0, masses)
    if not f_lim > 0:
        raise ModelError(f"f_lim must be positive, not {f_lim}")
    return float(f_lim / np.max(masses * np.linalg.norm(b, axis=1)))


def _static_response(phi, omega2, f):
    """u = Φ diag(1/ω²) Φᵀ f: quasi-static modal response (eq. 12) of loads f (3N, k) → (3N, k) [m]."""
    return phi @ ((phi.T @ f) / omega2[:, None])


def alpha_response(b, masses, phi, omega2) -> np.ndarray:
    """U_α (N, 3, 3) [m s²]: node displacement per unit α, u_n = U_α,n α.

    Column k is the static response to f = −M (e_k × b) (eq. 29, α = e_k; f_n =
    −m_n e_k × b_n when lumped), ``masses`` as :func:`preprocess.body.mass_times` takes it.
    """
    a = -np.cross(np.eye(3)[None, :, :], b[:, None, :])  # (N, k, 3) accelerations
    f = mass_times(masses, a.transpose(0, 2, 1).reshape(-1, 3))
    return _static_response(phi, omega2, f).reshape(-1, 3, 3)


def omega_response(b, masses, phi, omega2) -> np.ndarray:
    """H (N, 3, 6) [m s²]: node displacement per |Ω|², u_n = H_n q(Ω̂) for unit Ω̂.

    q(Ω̂) = (x², y², z², xy, xz, yz). The centrifugal force of eq. 29 is the quadratic
    form f_n,i = Σ_kl T_n,ikl Ω̂_k Ω̂_l with the symmetric coefficients
    T_n,ikl = m_n (δ_kl b_n,i − (δ_ik b_n,l + δ_il b_n,k) / 2) (using |Ω̂| = 1), with a
    mass matrix M applied to the accelerations T_n,ikl / m_n instead;
    column (k, l) of H is the response to T_kk, resp. T_kl + T_lk for k ≠ l.
    """
    eye = np.eye(3)
    T = (np.einsum("kl,ni->nikl", eye, b)
         - 0.5 * (np.einsum("ik,nl->nikl", eye, b) + np.einsum("il,nk->nikl", eye, b)))
    C = np.stack([T[:, :, k, l] * (1 if k == l else 2) for k, l in _MONOMIALS], axis=-1)  # (N, 3, 6)
    return _static_response(phi, omega2, mass_times(masses, C.reshape(-1, 6))).reshape(-1, 3, 6)


def _monomials(x) -> np.ndarray:
    """q (6, k) of directions x (3, k) (not normalized)."""
    return np.stack([x[k] * x[l] for k, l in _MONOMIALS])


def fibonacci_half_sphere(n) -> np.ndarray:
    """n nearly uniform unit vectors (3, n) on the half sphere z > 0 (Fibonacci lattice)."""
    i = np.arange(n)
    z = (i + 0.5) / n
    r = np.sqrt(1.0 - z * z)
    t = i * np.pi * (3.0 - np.sqrt(5.0))
    return np.stack([r * np.cos(t), r * np.sin(t), z])


def _max_node_norm(H, x, chunk=4_000_000):
    """max_n |H_n q(x_j)| per direction j → (values (k,), node index (k,)), in chunks of directions."""
    step = max(1, chunk // (3 * H.shape[0]))
    vals, nodes = [], []
    for s in range(0, x.shape[1], step):
        norms = np.linalg.norm(H @ _monomials(x[:, s:s + step]), axis=1)  # (N, k)
        nodes.append(norms.argmax(axis=0))
        vals.append(norms.max(axis=0))
    return np.concatenate(vals), np.concatenate(nodes)


def _refine(Hn, x0):
    """Local maximum of |H_n q(x̂)|² over unit x̂ from x0 (BFGS on the scale-invariant
    g(x) = |H_n q(x)|² / |x|⁴ with its exact gradient, H_n scaled to unit norm so
    the tolerance is relative); returns the unit direction."""
    Hn = Hn / np.linalg.norm(Hn)

    def fun(x):
        xx = x @ x
        s = Hn @ _monomials(x[:, None])[:, 0]
        dq = np.array([[2 * x[0], 0, 0], [0, 2 * x[1], 0], [0, 0, 2 * x[2]],
                       [x[1], x[0], 0], [x[2], 0, x[0]], [0, x[2], x[1]]])  # dq/dx (6, 3)
        g = s @ s / xx ** 2
        grad = 2 * (s @ Hn @ dq) / xx ** 2 - 4 * g * x / xx
        return -g, -grad

    x = minimize(fun, x0, jac=True, method="BFGS", options={"gtol": 1e-12}).x
    return x / np.linalg.norm(x)


def max_omega_response(H, n_directions=1000, n_refine=8):
    """d_omega = max over unit Ω̂ and nodes of |H_n q(Ω̂)| [m s²] and the maximizing Ω̂ (3,).

    q(−Ω̂) = q(Ω̂), so the half sphere suffices: ``n_directions`` Fibonacci points,
    then the ``n_refine`` best (direction, node) pairs refined by a local optimizer
    and re-evaluated over all nodes.
    """
    x = fibonacci_half_sphere(n_directions)
    vals, nodes = _max_node_norm(H, x)
    best = np.argsort(-vals)[:n_refine]
    refined = np.stack([_refine(H[nodes[j]], x[:, j]) for j in best], axis=1)
    rvals, _ = _max_node_norm(H, refined)
    cand = np.concatenate([vals[best], rvals])
    dirs = np.concatenate([x[:, best], refined], axis=1)
    j = int(np.argmax(cand))
    return float(cand[j]), dirs[:, j]


def _magnitude(v) -> float:
    """|v| of a scalar magnitude or a vector (3,)."""
    return float(np.linalg.norm(np.atleast_1d(np.asarray(v, dtype=float))))


@dataclass(frozen=True)
class DecisionBoundaries:
    """Displacement-limited α–Ω decision boundaries (report eq. 32, Fig. 9).

    ``d_alpha`` [m per rad/s²] and ``d_omega`` [m per (rad/s)²]: largest quasi-static
    node displacement per unit |α| and per unit |Ω|²; ``alpha_direction`` and
    ``omega_direction`` (3,) the unit directions attaining them; ``d_negligible`` and
    ``d_linear`` [m] the displacement limits (report Sec. 5.4: 1 µm and 5 cm);
    ``k_dyn`` the dynamic amplification (2: suddenly applied load).
    """

    d_alpha: float
    d_omega: float
    alpha_direction: np.ndarray
    omega_direction: np.ndarray
    d_negligible: float
    d_linear: float
    k_dyn: float

    def displacement(self, alpha, omega) -> float:
        """Estimated largest displacement k_dyn (d_alpha |α| + d_omega |Ω|²) [m];
        ``alpha`` [rad/s²] and ``omega`` [rad/s] as magnitudes or vectors (3,)."""
        return self.k_dyn * (self.d_alpha * _magnitude(alpha) + self.d_omega * _magnitude(omega) ** 2)

    def recommend(self, alpha, omega) -> str:
        """The :meth:`region` of the estimated displacement for α [rad/s²] and Ω [rad/s]."""
        return self.region(self.displacement(alpha, omega))

    def region(self, d) -> str:
        """"SimpleRB" (d below d_negligible), "outside linear elasticity" (above d_linear)
        or "CoupledRB" (between) for a displacement d [m] (the regions of report Fig. 9)."""
        return SIMPLE if d < self.d_negligible else OUTSIDE if d > self.d_linear else COUPLED

    def sum_limit(self, d_lim) -> float:
        """The report's single-number form: |α| + |Ω|² <= d_lim / (k_dyn max(d_alpha, d_omega)) [1/s²]."""
        return d_lim / (self.k_dyn * max(self.d_alpha, self.d_omega))

    @property
    def sum_limits(self) -> tuple[float, float]:
        """(SimpleRB/CoupledRB, CoupledRB/outside) limits of |α| + |Ω|² [1/s²] (report Sec. 5.4: 1.19, 59570)."""
        return self.sum_limit(self.d_negligible), self.sum_limit(self.d_linear)

    def plot(self, path=None, ax=None, points=None):
        """Fig. 9 style plot: |Ω| [rad/s] (x, log) against |α| [rad/s²] (y, log), regions
        green (SimpleRB), yellow (CoupledRB), red (outside linear elasticity).

        ``points``: optional (α, Ω, label) triples, marked and coloured by their
        recommendation; α = 0 or Ω = 0 are drawn at the axis edge (as report Fig. 9
        does). Draws into ``ax`` if given, else a new Figure; writes a PNG to ``path``
        if given. Returns the Figure.
        """
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure
        from matplotlib.patches import Patch

        if ax is None:
            fig = Figure(figsize=(6.4, 4.8))
            FigureCanvasAgg(fig)
            ax = fig.add_subplot()
        fig = ax.figure
        points = [(_magnitude(a), _magnitude(w), str(lab)) for a, w, lab in (points or [])]
        s_neg, s_lin = self.sum_limits
        a_range = [s_neg / 100, s_lin * 100]
        w_range = [np.sqrt(s_neg) / 10, np.sqrt(s_lin) * 10]
        for a, w, _ in points:
            a_range = [min(a_range[0], a) if a > 0 else a_range[0], max(a_range[1], 2 * a)]
            w_range = [min(w_range[0], w) if w > 0 else w_range[0], max(w_range[1], 2 * w)]
        W, A = np.meshgrid(np.geomspace(*w_range, 400), np.geomspace(*a_range, 400))
        D = self.k_dyn * (self.d_alpha * A + self.d_omega * W ** 2)
        colours = {SIMPLE: "#7fc97f", COUPLED: "#ffe680", OUTSIDE: "#f08080"}
        top = max(D.max(), self.d_linear) * 10
        ax.contourf(W, A, D, levels=[0, self.d_negligible, self.d_linear, top], colors=list(colours.values()))
        ax.contour(W, A, D, levels=[self.d_negligible, self.d_linear], colors="k", linewidths=0.8)
        for a, w, label in points:
            x, y = max(w, w_range[0]), max(a, a_range[0])
            ax.plot(x, y, "o", mec="k", mfc=colours[self.recommend(a, w)], clip_on=False, zorder=3)
            ax.annotate(label, (x, y), xytext=(4, 4), textcoords="offset points", fontsize=8)
        ax.set(xscale="log", yscale="log", xlim=w_range, ylim=a_range,
               xlabel="|Ω| [rad/s]", ylabel="|α| [rad/s²]",
               title=f"α–Ω decision boundaries ({self.d_negligible:g} m, {self.d_linear:g} m; k_dyn = {self.k_dyn:g})")
        ax.legend(handles=[Patch(color=c, label=k) for k, c in colours.items()], loc="upper center",
                  bbox_to_anchor=(0.5, -0.12), ncol=3, fontsize=8, frameon=False)
        if path is not None:
            fig.savefig(path, dpi=120, bbox_inches="tight")
        return fig


def decision_boundaries(u0, masses, phi, omega2, d_negligible=1e-6, d_linear=0.05, k_dyn=2.0,
                        n_directions=1000) -> DecisionBoundaries:
    """Displacement-limited decision boundaries (report eq. 32, derived in the module docstring).

    ``u0`` (N, 3) [m], ``masses`` (N,) or sparse M_s (N, N) [kg] (module docstring),
    ``phi`` (3N, n) mass-normalized elastic
    modes [kg^-1/2], ``omega2`` (n,) [rad²/s²] > 0; b is taken from the centre of
    mass (the B frame origin, report Fig. 3). ``d_negligible`` < ``d_linear`` [m];
    ``k_dyn`` >= 1 the dynamic amplification (2 for a suddenly applied load, 1 for the
    static estimate). The response uses the given modes only: truncation
    underestimates the static deflection slightly (use preprocess.modes.all_modes for
    the exact static response of a small model).
    """
    u0, masses, b = _positions(u0, masses)
    phi = np.asarray(phi, dtype=float)
    omega2 = np.asarray(omega2, dtype=float)
    if phi.ndim != 2 or phi.shape[0] != 3 * len(u0) or omega2.shape != (phi.shape[1],):
        raise ModelError(f"phi must be (3N, n) = ({3 * len(u0)}, n) and omega2 (n,), "
                         f"got {phi.shape}, {omega2.shape}")
    if np.any(omega2 <= 0):
        raise ModelError("omega2 must be positive: pass the elastic modes only (rigid modes: report Sec. 3.3)")
    if not 0 < d_negligible < d_linear:
        raise ModelError(f"need 0 < d_negligible < d_linear, got {d_negligible}, {d_linear}")
    if not k_dyn >= 1:
        raise ModelError(f"k_dyn must be >= 1 (2: suddenly applied load, 1: static), not {k_dyn}")
    U = alpha_response(b, masses, phi, omega2)
    _, sv, vt = np.linalg.svd(U)
    n_alpha = int(np.argmax(sv[:, 0]))
    d_omega, w_dir = max_omega_response(omega_response(b, masses, phi, omega2), n_directions)
    return DecisionBoundaries(float(sv[n_alpha, 0]), d_omega, vt[n_alpha, 0], w_dir,
                              float(d_negligible), float(d_linear), float(k_dyn))

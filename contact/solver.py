"""The contact problem of one Moreau time step on velocity level (DESIGN stage 5).

Given the Delassus matrix G = Wᵀ M̂⁻¹ W (m, m) [1/kg], the free end-of-step relative
velocities ξ_free (m,) [m/s] and the pre-step ones γ⁻ = Wᵀ u_k (m,) [m/s], find the
impulses Λ (m,) [N s] with

    γ⁺ = ξ_free + G Λ,     Λ_c = prox_{C_c}(Λ_c − r_c ξ_c),   ξ_c = γ⁺_c + ε_c γ⁻_c

for every contact c (its law's inclusion, :mod:`contact.laws`; thesis eq. 3.1c-d).
Λ is the concatenation of the contacts' blocks in the order of the laws, a spatial
contact's block being ``[N, T1, T2]``. The integrator then sets
u_{k+1} = u_free + M̂⁻¹ W Λ.

Methods (:class:`ProxSolver`):

* ``"gauss-seidel"``: projected Gauss–Seidel (nonsmooth contact dynamics, Moreau 1988,
  Jean 1999), row by row with r_i = α / G_ii (Studer 2009, sec. 6.3; Acary & Brogliato
  2008, ch. 12); for a Coulomb contact r_T = α / λ_max(G_TT) on both tangential rows, so
  that the disk projection stays isotropic. Converges for α in (0, 2) on frictionless
  and bilateral problems with G positive definite (projected SOR, Cryer 1971); with
  friction the iteration can cycle, and then halves its r until it converges
  (:func:`contact._kernels.prox_iterate`); convergence is usual, not guaranteed.
* ``"jacobi"``: all contacts from the same Λ, r_i = α / (G_ii ρ) with ρ a Gershgorin
  bound of λ_max(D^-1/2 G D^-1/2), D = diag(G), so that the iteration contracts for
  frictionless problems (Studer 2009, sec. 6.2).
* ``"newton"``: a semismooth Newton method on the Fischer–Burmeister reformulation
  φ(Λ_i, r_i ξ_i) = sqrt(Λ_i² + r_i² ξ_i²) − Λ_i − r_i ξ_i = 0 of the unilateral rows
  and r_i ξ_i = 0 of the bilateral rows, r_i = 1 / G_ii, with an Armijo line search on
  ½|Φ|² (the Newton direction H d = −Φ is a descent direction, ∇Ψᵀd = −|Φ|²; a singular
  H falls back to least squares and then to the gradient; De Luca, Facchinei & Kanzow
  1996; Acary & Brogliato 2008, ch. 12). Local convergence is quadratic and does
  not degrade with the conditioning of G (large mass ratios), where the prox iterations
  slow down. When the line search finds no descent (a singular H: more contacts than
  the bodies have velocities), a subspace step (below) from Λ clipped to Λ ≥ 0 takes the
  Newton step's place (counted as one), and Newton goes on from there. It covers
  :class:`~contact.laws.UnilateralNewtonImpact` and :class:`~contact.laws.Bilateral`
  contacts. A problem with friction is solved by the Gauss–Seidel iteration below that
  starts with a Newton phase on the natural map.

Subspace steps (``subspace_every`` > 0): the sweeps fix the
active set (the rows with Λ_i > 0) within a few iterations but crawl towards the
impulses on it when G is ill-conditioned or singular — a face of point contacts on a
plane has far more contacts than the velocities it moves (rank G = 9 for 81 contacts of a
rod with 6 modes) and eigenvalues from the rigid motion down to the stiff modes. Every
``subspace_every`` sweeps, preconditioned conjugate gradients minimize ½ ΛᵀGΛ + cᵀΛ on
the active rows (:func:`contact._kernels.subspace_step`; PGS-SM, Silcowitz, Niebe &
Erleben 2010); the objective never increases, so the sweeps' convergence is kept. Each
conjugate-gradient step counts as one iteration. With friction the problem is no
minimization, and the coupled sweeps crawl while the closed set changes (a face of 25
contacts with μ = 0.3 whose first impulse is carried by 5 of them): every
``NORMAL_PHASE_FACTOR`` · ``subspace_every`` sweeps a normal phase solves the normal
problem with the tangential impulses held, a frictionless problem, by sweeps over the
normal rows and subspace steps (:func:`contact._kernels.normal_phase`; the normal half of
the staggered projections of Kaufman, Sueda, James & Pai 2008); each of its row passes
counts as one iteration. The sweeps still converge linearly at a rate set by the
conditioning of G, slowly where the few contacts that carry a face's load slide by
velocities 1e-4 of ξ_free; so every NEWTON_EVERY sweeps a Newton phase takes
semismooth Newton steps on the natural map F(Λ) = (Λ − prox_C(Λ − r ξ)) / r (Alart &
Curnier 1991), with r a thousand times the sweeps' (the stick–slip switch then follows the
velocities), the direction from Gaussian elimination with complete pivoting (a basic
solution where G is singular) and an Armijo line search on |F|²; where the line search
fails the sweeps go on (:func:`contact._kernels.newton_phase`). Each Newton step counts
as one iteration. Convergence stays usual, not guaranteed.

Convergence: an iteration stops when the scaled change max_i |ΔΛ_i| / r_i (prox
methods) and the natural-map residual max_i |Λ_i − prox(Λ − r ξ)_i| / r_i [m/s] (zero
exactly at a solution, for any r > 0) are below ``tol`` · max|c| (c = ξ_free + ε γ⁻)
plus a bound of the rounding error of ξ = c + G Λ, 8 ε (m + 1) max_i (|c_i| + Σ_j
|G_ij Λ_j|) (:func:`contact._kernels.prox_iterate`), which dominates when large
impulses cancel, as in a stack of very different masses. Without convergence the last
iterate comes back with ``converged=False``; the integrator decides.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ffrmbs.errors import ModelError

from . import _kernels as kern
from .laws import Bilateral, UnilateralCoulombContact, UnilateralNewtonImpact

METHODS = ("gauss-seidel", "jacobi", "newton")
ARMIJO_SIGMA = 1e-4          # sufficient decrease of the merit ½|Φ|²
LM_MU = 1e-3
ARMIJO_MIN_STEP = 1e-12      # smallest line-search step before giving up
TINY_DIAGONAL = 1e-14        # G_ii below this times max G_jj: row touches no mass
SUBSPACE_EVERY = 10          # sweeps between the subspace steps of the prox methods
WORK_ROWS = 6                # rows of the scratch array of ProxSolver.solve_into


class ContactSet:
    """The set-valued laws of one contact problem and their rows in Λ, encoded for numba.

    Parameters
    ----------
    laws : sequence of set-valued laws
        :class:`~contact.laws.UnilateralNewtonImpact`, :class:`~contact.laws.Bilateral`
        or :class:`~contact.laws.UnilateralCoulombContact`; Λ holds their blocks in this
        order.

    Attributes
    ----------
    laws : tuple
    offsets : ndarray (n_laws,) int
        First row of each law's block in Λ.
    m : int
        Number of rows of Λ.
    restitution : ndarray (m,)
        ε of every row (ξ = γ⁺ + ε γ⁻).
    kinds, entry_offsets, mu : ndarray
        The kernel encoding (:mod:`contact._kernels`): a Bilateral of dim k is k scalar
        entries, the other laws one entry each.
    frictional : bool
        Whether a law has friction.
    """

    def __init__(self, laws):
        self.laws = tuple(laws)
        offsets, kinds, entry_offsets, mu, eps = [], [], [], [], []
        m = 0
        for law in self.laws:
            if isinstance(law, Bilateral):
                kinds += [kern.BILATERAL] * law.dim
                entry_offsets += list(range(m, m + law.dim))
                mu += [0.0] * law.dim
            elif isinstance(law, (UnilateralNewtonImpact, UnilateralCoulombContact)):
                frictional = isinstance(law, UnilateralCoulombContact)
                kinds.append(kern.COULOMB if frictional else kern.UNILATERAL)
                entry_offsets.append(m)
                mu.append(law.mu if frictional else 0.0)
            else:
                raise ModelError(
                    f"contact solver: {law!r} is not a set-valued contact law it solves "
                    "(UnilateralNewtonImpact, Bilateral, UnilateralCoulombContact)")
            offsets.append(m)
            eps.append(law.restitution)
            m += law.dim
        self.offsets = np.array(offsets, dtype=np.int64)
        self.m = m
        self.restitution = np.concatenate(eps) if eps else np.zeros(0)
        self.kinds = np.array(kinds, dtype=np.int64)
        self.entry_offsets = np.array(entry_offsets, dtype=np.int64)
        self.mu = np.array(mu, dtype=float)
        self.frictional = bool(np.any(self.kinds == kern.COULOMB))
        self.tangent_at = self.entry_offsets[self.kinds == kern.COULOMB] + 1

    def tangent_rows(self):
        """First tangential row (T1) of every Coulomb contact, (n_c,) int."""
        return self.tangent_at


@dataclass
class ContactSolution:
    """Result of :meth:`ProxSolver.solve`.

    Attributes
    ----------
    lam : ndarray (m,) [N s]
        The impulses Λ (the last iterate when not converged).
    gamma_plus : ndarray (m,) [m/s]
        γ⁺ = ξ_free + G Λ.
    iterations : int
        Sweeps (prox methods) or Newton steps.
    residual : float [m/s]
        Natural-map residual max_i |Λ_i − prox(Λ − r ξ)_i| / r_i of ``lam``.
    converged : bool
    """

    lam: np.ndarray
    gamma_plus: np.ndarray
    iterations: int
    residual: float
    converged: bool


class ProxSolver:
    """Solver of the velocity-level contact problem (module docstring).

    Parameters
    ----------
    method : {"gauss-seidel", "jacobi", "newton"}
    r : "auto" or float > 0 [kg]
        Prox factors: "auto" the per-row choice of the method (module docstring), a
        number the same r on every row (prox methods only; Newton always scales by
        1 / G_ii).
    relaxation : float in (0, 2)
        α of the automatic r of the prox methods.
    tol : float > 0
        Relative tolerance of the velocities [-] (times max|ξ_free + ε γ⁻|, module docstring).
    max_iter : int >= 1 or None
        Most sweeps or Newton steps; None: 10000 sweeps, 100 Newton steps.
    subspace_every : int >= 0
        Prox methods: a conjugate-gradient subspace step on the active rows every this
        many sweeps, with friction a normal phase every NORMAL_PHASE_FACTOR times as many
        (module docstring); 0 never.
    """

    def __init__(self, method="gauss-seidel", r="auto", relaxation=1.0, tol=1e-10,
                 max_iter=None, subspace_every=SUBSPACE_EVERY):
        if method not in METHODS:
            raise ModelError(f"ProxSolver: method must be one of {METHODS}, got {method!r}")
        if not (isinstance(r, str) and r == "auto"):
            if isinstance(r, str) or not (math.isfinite(float(r)) and float(r) > 0.0):
                raise ModelError(f"ProxSolver: r must be 'auto' or a number > 0, got {r!r}")
            r = float(r)
        relaxation = float(relaxation)
        if not 0.0 < relaxation < 2.0:
            raise ModelError(f"ProxSolver: relaxation must lie in (0, 2), got {relaxation!r}")
        tol = float(tol)
        if not (math.isfinite(tol) and tol > 0.0):
            raise ModelError(f"ProxSolver: tol must be a number > 0, got {tol!r}")
        if max_iter is None:
            max_iter = 100 if method == "newton" else 10_000
        if int(max_iter) != max_iter or max_iter < 1:
            raise ModelError(f"ProxSolver: max_iter must be an integer >= 1, got {max_iter!r}")
        if int(subspace_every) != subspace_every or subspace_every < 0:
            raise ModelError(f"ProxSolver: subspace_every must be an integer >= 0, got {subspace_every!r}")
        self.subspace_every = int(subspace_every)
        self.method, self.r, self.relaxation = method, r, relaxation
        self.tol, self.max_iter = tol, int(max_iter)

    def solve(self, contacts, G, xi_free, gamma_pre, lam0=None, validate=True) -> ContactSolution:
        """Impulses Λ of one time step.

        Parameters
        ----------
        contacts : ContactSet or sequence of set-valued laws
        G : array (m, m) [1/kg]
            Delassus matrix Wᵀ M̂⁻¹ W (symmetric positive semi-definite).
        xi_free : array (m,) [m/s]
            Free end-of-step relative velocities.
        gamma_pre : array (m,) [m/s]
            Pre-step relative velocities γ⁻ (restitution).
        lam0 : array (m,) [N s], optional
            Warm start, e.g. the previous step's Λ of the same contacts; zero by default.
        validate : bool
            False skips the checks of shapes and finiteness (for an integrator that
            assembles consistent float arrays itself; ``lam0`` is then required and is
            overwritten with Λ).
        """
        cs = contacts if isinstance(contacts, ContactSet) else ContactSet(contacts)
        if validate:
            G, xi_free, gamma_pre, lam = _checked(cs, G, xi_free, gamma_pre, lam0)
        else:
            lam = lam0
        gamma_plus = np.empty(cs.m)
        it, residual, converged = self.solve_into(cs, G, xi_free, gamma_pre, lam, gamma_plus,
                                                  np.empty((WORK_ROWS, cs.m)))
        return ContactSolution(lam, gamma_plus, it, residual, converged)

    def solve_into(self, cs, G, xi_free, gamma_pre, lam, gamma_plus, work, newton_scratch=None):
        """:meth:`solve` on consistent float arrays without validation: Λ in place in
        ``lam`` (its warm start on entry), γ⁺ = ξ_free + G Λ into ``gamma_plus``,
        ``work`` (WORK_ROWS, m) scratch, ``newton_scratch`` the scratch of the Newton phases
        of a problem with friction (:func:`newton_work`; made here when None); returns
        (iterations, residual [m/s], converged). The Gauss–Seidel method with automatic r,
        and the Newton method with friction, are one kernel call
        (:func:`contact._kernels.gauss_seidel_solve`) and allocate nothing."""
        frictional_newton = self.method == "newton" and cs.frictional
        if frictional_newton or (self.method == "gauss-seidel" and self.r == "auto"):
            J, pivots, local = newton_scratch if newton_scratch is not None else newton_work_for(cs)
            it, residual, converged = kern.gauss_seidel_solve(
                G, xi_free, gamma_pre, cs.restitution, cs.kinds, cs.entry_offsets, cs.mu, cs.tangent_at,
                self.relaxation, TINY_DIAGONAL, self.tol, self.max_iter, self.subspace_every, lam, gamma_plus, work,
                frictional_newton, J, pivots, local)
            return int(it), float(residual), bool(converged)
        c, r, xi, r_work = work[0], work[1], work[2], work[3]
        np.multiply(cs.restitution, gamma_pre, out=c)
        np.add(xi_free, c, out=c)
        if not np.any(c):               # Λ = 0 solves every law
            lam.fill(0.0)
            gamma_plus[:] = xi_free
            return 0, 0.0, True
        if self.method == "newton":
            it, residual, converged = self._newton(cs, G, c, _diagonal(G) ** -1.0, lam, work[4:6])
        else:
            self._prox_factors(cs, G, r)
            J, pivots, local = newton_scratch if newton_scratch is not None else newton_work_for(cs)
            it, residual, converged = kern.prox_iterate(
                G, c, r, cs.kinds, cs.entry_offsets, cs.mu, lam, xi, r_work, self.method == "jacobi",
                self.tol, self.max_iter, self.subspace_every, work[4], work[5], False, J, pivots[0], pivots[1],
                local)
        np.matmul(G, lam, out=gamma_plus)
        np.add(xi_free, gamma_plus, out=gamma_plus)
        return int(it), float(residual), bool(converged)

    def _prox_factors(self, cs, G, r):
        """r (m,) [kg] of the prox methods (module docstring) into ``r``."""
        if self.r != "auto":
            r[:] = self.r
            return
        kern.diagonal_floor(G, TINY_DIAGONAL, r)
        alpha = self.relaxation
        if self.method == "jacobi":
            s = np.sqrt(r)
            alpha /= np.max(np.sum(np.abs(G) / np.outer(s, s), axis=1))
        if cs.tangent_at.size:
            d = r.copy()
            np.divide(alpha, d, out=r)
            for t in cs.tangent_at:
                a, b, e = G[t, t], G[t, t + 1], G[t + 1, t + 1]
                lam_max = 0.5 * (a + e) + math.hypot(0.5 * (a - e), b)
                r[t:t + 2] = alpha / max(lam_max, d[t], d[t + 1])
        else:
            np.divide(alpha, r, out=r)

    def _newton(self, cs, G, c, r, lam, work):
        """Fischer–Burmeister semismooth Newton (module docstring); Λ in place; ``work``
        (2, m) scratch of the subspace step."""
        unilateral = np.zeros(cs.m, dtype=bool)
        unilateral[cs.entry_offsets[cs.kinds == kern.UNILATERAL]] = True
        np.maximum(lam, 0.0, out=lam, where=unilateral)
        RG = r[:, None] * G
        xi = np.empty(cs.m)

        def merit(lam):
            v_terms = kern.velocities(G, c, lam, xi)
            b = r * xi
            norm = np.hypot(lam, b)
            phi = np.where(unilateral, norm - lam - b, b)
            return phi, b, norm, v_terms

        c_ref = float(np.max(np.abs(c)))
        phi, b, norm, v_terms = merit(lam)
        for it in range(self.max_iter + 1):
            residual = kern.prox_step(xi, r, cs.kinds, cs.entry_offsets, cs.mu, lam, False)
            accepted = residual <= kern.threshold(self.tol, c_ref, cs.m, v_terms)
            if accepted and (it > 0 or not phi.any()):
                return it, residual, True                 # a warm start is refined once unless exact
            if it == self.max_iter:
                break
            safe = np.where(norm > 0.0, norm, 1.0)
            da = np.where(norm > 0.0, lam / safe, math.sqrt(0.5)) - 1.0
            db = np.where(norm > 0.0, b / safe, math.sqrt(0.5)) - 1.0
            H = np.where(unilateral[:, None], db[:, None] * RG, RG)
            H[np.flatnonzero(unilateral), np.flatnonzero(unilateral)] += da[unilateral]
            grad = H.T @ phi
            try:
                d = np.linalg.solve(H, -phi)
            except np.linalg.LinAlgError:
                d = np.linalg.lstsq(H, -phi, rcond=None)[0]
            if not (np.all(np.isfinite(d)) and grad @ d < 0.0):   # lstsq gave no descent
                d = -grad
            trial = self._armijo(merit, lam, d, 0.5 * phi @ phi, grad @ d)
            if trial is None:                             # no descent left along d
                np.maximum(lam, 0.0, out=lam, where=unilateral)
                if not (self.subspace_every and kern.subspace_step(
                        G, c, r, cs.kinds, cs.entry_offsets, lam, xi, work[0], work[1],
                        kern.threshold(self.tol, c_ref, cs.m, v_terms), cs.m)):
                    return it, residual, accepted         # solved if within the tolerance
                trial = lam
            lam[:] = trial
            phi, b, norm, v_terms = merit(lam)
        return self.max_iter, residual, False

    @staticmethod
    def _armijo(merit, lam, d, psi, slope):
        """Λ + s d with the largest s = 2^-k whose merit ½|Φ|² decreases by at least
        ARMIJO_SIGMA s |slope|, or None below ARMIJO_MIN_STEP."""
        step = 1.0
        while step >= ARMIJO_MIN_STEP:
            trial = lam + step * d
            phi_t = merit(trial)[0]
            if 0.5 * phi_t @ phi_t <= psi + ARMIJO_SIGMA * step * slope:
                return trial
            step *= 0.5
        return None


def newton_work(m):
    """Scratch of the Newton phases of an m-row problem with friction: (J (m, m),
    pivots (2, m) int64, local (5, 3)) (:func:`contact._kernels.newton_phase`)."""
    return np.empty((m, m)), np.empty((2, m), dtype=np.int64), np.empty((5, 3))


def newton_work_for(cs):
    """:func:`newton_work` of ``cs``'s rows with friction, empty stand-ins without (the
    kernels never touch them)."""
    return newton_work(cs.m if cs.frictional else 0)


def _diagonal(G):
    """diag(G) with rows that touch no mass (G_ii ≈ 0) replaced by max G_jj (or 1)
    (the numpy reference of :func:`contact._kernels.diagonal_floor`)."""
    d = np.diag(G).copy()
    d_max = float(np.max(d, initial=0.0))
    if d_max <= 0.0:
        return np.ones_like(d)
    return np.where(d > TINY_DIAGONAL * d_max, d, d_max)


def _checked(cs, G, xi_free, gamma_pre, lam0):
    """Validated float copies (G, ξ_free, γ⁻, Λ0) or ModelError."""
    G = np.asarray(G, dtype=float)
    m = cs.m
    if G.ndim != 2 or G.shape[0] != G.shape[1]:
        raise ModelError(f"contact solver: G must be square, got shape {G.shape}")
    if G.shape[0] != m:
        raise ModelError(f"contact solver: G is {G.shape[0]} x {G.shape[0]}, the laws have "
                         f"{m} rows")
    arrays = [G]
    for name, x in (("xi_free", xi_free), ("gamma_pre", gamma_pre),
                    ("lam0", np.zeros(m) if lam0 is None else lam0)):
        x = np.array(x, dtype=float)
        if x.shape != (m,):
            raise ModelError(f"contact solver: {name} must have shape ({m},), got {x.shape}")
        arrays.append(x)
    for name, x in zip(("G", "xi_free", "gamma_pre", "lam0"), arrays):
        if not np.all(np.isfinite(x)):
            raise ModelError(f"contact solver: {name} has non-finite entries")
    scale = float(np.max(np.abs(G), initial=0.0))
    if np.any(np.diag(G) < -TINY_DIAGONAL * scale):
        raise ModelError("contact solver: G has a negative diagonal entry; it must be "
                         "positive semi-definite")
    G = np.ascontiguousarray(G)
    return G, arrays[1], arrays[2], arrays[3]

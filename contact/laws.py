"""Contact force laws on velocity level for Moreau's midpoint time-stepping (issue 6).

Sign conventions (all laws). Per contact the normal gap ``g_N`` [m] is positive when the
contours are apart and negative when they penetrate; the normal relative velocity
``gamma_N = ġ_N`` [m/s] is positive when they separate. The tangential relative velocity
``gamma_T`` [m/s] (2,) is the velocity of the contact point on contour 2 relative to
contour 1 in the contact frame's tangents ``(t1, t2)``. The wrench matrix W (columns the
gradients of the contact velocities, thesis eq. 3.1c, 4.1) maps the reactions into the
generalized directions, so a positive normal reaction pushes the contours apart and a
tangential reaction acts along +t on contour 2. Rows of one contact in Λ are ordered
``[N, T1, T2]``.

Set-valued laws (``kind = "set-valued"``) relate the impulse Λ [N s] (force × Δt) of one
time step to the post-step velocity γ⁺ = ξ_free + G Λ through an inclusion, written as a
proximal point equation (Moreau 1988; Alart & Curnier 1991; Studer 2009, ch. 4)

    Λ = prox_C(Λ − r ξ),      ξ = γ⁺ + ε γ⁻,                          (*)

with C the law's admissible set of impulses, ε its restitution coefficients
(:attr:`restitution`), γ⁻ the pre-step velocity and any r > 0 [N s²/m = kg]. A law's
:meth:`project` is prox_C; the solver (:mod:`contact.solver`) iterates (*) over all
contacts. Single-valued laws (``kind = "single-valued"``) give a force [N] as a function
of the contact kinematics; the integrator adds it to h (thesis eq. 3.1b) and may use
:meth:`derivatives` in a linearly implicit step. A law's ``units`` ({parameter: unit})
name the units of its parameters for messages and scene files (dimensionless ones left out).

References: J.J. Moreau, Unilateral contact and dry friction in finite freedom dynamics,
CISM 302, 1988. M. Jean, The non-smooth contact dynamics method, CMAME 177, 1999.
C. Studer, Numerics of Unilateral Contacts and Friction, LNACM 47, Springer 2009.
V. Acary & B. Brogliato, Numerical Methods for Nonsmooth Dynamical Systems, LNACM 35,
Springer 2008. C. Glocker, Set-Valued Force Laws, Springer 2001 (thesis [14]).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np

from ffrmbs.errors import ModelError


def _coefficient(law, name, value, low, high=math.inf) -> float:
    value = float(value)
    if not (math.isfinite(value) and low <= value <= high):
        bounds = f"[{low:g}, {high:g}]" if math.isfinite(high) else f">= {low:g}"
        raise ModelError(f"{law}: {name} must be finite and {bounds}, got {value!r}")
    return value


def project_disk(z_T, radius):
    """Euclidean projection of ``z_T`` (..., 2) onto the disk |x| <= ``radius`` (>= 0)."""
    z_T = np.asarray(z_T, dtype=float)
    norm = np.linalg.norm(z_T, axis=-1, keepdims=True)
    radius = np.asarray(radius, dtype=float)[..., None]
    scale = np.where(norm > radius, radius / np.where(norm > 0.0, norm, 1.0), 1.0)
    return z_T * scale


@dataclass(frozen=True)
class UnilateralNewtonImpact:
    """Newton's impact law for a closed unilateral contact (Moreau 1988; Glocker 2001).

    For a contact closed at the midpoint (g_N <= 0), with ξ_N = γ⁺_N + e γ⁻_N [m/s]:

        Λ_N >= 0,   ξ_N >= 0,   Λ_N ξ_N = 0
        ⇔  −ξ_N ∈ N_{R+}(Λ_N)  ⇔  Λ_N = prox_{R+}(Λ_N − r ξ_N) = max(0, Λ_N − r ξ_N).

    e = 0 is a perfectly plastic impact and a persistent contact (γ⁺_N = 0), e = 1 an
    elastic one (γ⁺_N = −γ⁻_N). A single impact conserves or dissipates kinetic energy
    when all closed contacts share one e (Glocker 2001; see the tests).

    Parameters
    ----------
    e : float in [0, 1]
        Newton's coefficient of restitution [-].
    """

    e: float = 0.0
    kind: ClassVar[str] = "set-valued"
    dim: ClassVar[int] = 1

    def __post_init__(self):
        object.__setattr__(self, "e", _coefficient(self, "e", self.e, 0.0, 1.0))

    @property
    def restitution(self):
        """ε (1,): ξ = γ⁺ + ε γ⁻."""
        return np.array([self.e])

    def project(self, z):
        """prox_{R+}(z) = max(0, z) [N s], elementwise."""
        return np.maximum(np.asarray(z, dtype=float), 0.0)


@dataclass(frozen=True)
class Bilateral:
    """A bilateral constraint on velocity level: γ⁺ = 0 (joints, point on curve).

    Λ ∈ R^dim is free: −γ⁺ ∈ N_R(Λ) = {0}  ⇔  Λ = prox_R(Λ − r γ⁺) = Λ − r γ⁺.

    Parameters
    ----------
    dim : int >= 1
        Number of scalar constraints (rows of Λ).
    """

    dim: int = 1
    kind: ClassVar[str] = "set-valued"

    def __post_init__(self):
        if int(self.dim) != self.dim or self.dim < 1:
            raise ModelError(f"Bilateral: dim must be an integer >= 1, got {self.dim!r}")
        object.__setattr__(self, "dim", int(self.dim))

    @property
    def restitution(self):
        """ε (dim,) = 0: ξ = γ⁺."""
        return np.zeros(self.dim)

    def project(self, z):
        """prox_R(z) = z [N s]."""
        return np.array(z, dtype=float)


@dataclass(frozen=True)
class SpatialCoulombFriction:
    """Spatial Coulomb friction on velocity level (Moreau 1988; Studer 2009, sec. 4.2).

    With ξ_T = γ⁺_T + e_T γ⁻_T (2,) [m/s] and the normal impulse Λ_N >= 0 of the same
    contact, the tangential impulse Λ_T (2,) [N s] satisfies

        Λ_T ∈ −μ Λ_N ∂|ξ_T|  ⇔  −ξ_T ∈ N_{C(μΛ_N)}(Λ_T)
                             ⇔  Λ_T = prox_{C(μΛ_N)}(Λ_T − r ξ_T),

    C(ρ) = {x ∈ R², |x| <= ρ} the friction disk: stick ξ_T = 0 with |Λ_T| <= μ Λ_N, or
    slip Λ_T = −μ Λ_N ξ_T / |ξ_T|. The r of the two tangential rows must be equal.
    Used inside :class:`UnilateralCoulombContact`, which supplies Λ_N.

    Parameters
    ----------
    mu : float >= 0
        Coefficient of friction [-].
    """

    mu: float
    kind: ClassVar[str] = "set-valued"
    dim: ClassVar[int] = 2

    def __post_init__(self):
        object.__setattr__(self, "mu", _coefficient(self, "mu", self.mu, 0.0))

    def project(self, z_T, lam_N):
        """prox onto the disk of radius μ Λ_N: ``z_T`` (2,) [N s], ``lam_N`` >= 0 [N s]."""
        return project_disk(z_T, self.mu * lam_N)


@dataclass(frozen=True)
class UnilateralCoulombContact:
    """A closed spatial contact: Newton's impact law in N plus Coulomb friction in T.

    Rows ``[N, T1, T2]`` of Λ; ξ = (γ⁺_N + e γ⁻_N, γ⁺_T + e_T γ⁻_T); the inclusions of
    :class:`UnilateralNewtonImpact` and :class:`SpatialCoulombFriction` hold together,
    the friction disk's radius being μ Λ_N. The impact conserves or dissipates kinetic
    energy for e_T = e (any e in [0, 1]) and for e = e_T = 0 (see the tests).

    Parameters
    ----------
    e : float in [0, 1]
        Normal coefficient of restitution [-].
    mu : float >= 0
        Coefficient of friction [-].
    e_T : float in [0, 1]
        Tangential coefficient of restitution [-] (0: no tangential rebound).
    """

    e: float
    mu: float
    e_T: float = 0.0
    normal: UnilateralNewtonImpact = field(init=False, repr=False, compare=False)
    friction: SpatialCoulombFriction = field(init=False, repr=False, compare=False)
    kind: ClassVar[str] = "set-valued"
    dim: ClassVar[int] = 3

    def __post_init__(self):
        object.__setattr__(self, "normal", UnilateralNewtonImpact(self.e))
        object.__setattr__(self, "friction", SpatialCoulombFriction(self.mu))
        object.__setattr__(self, "e", self.normal.e)
        object.__setattr__(self, "mu", self.friction.mu)
        object.__setattr__(self, "e_T", _coefficient(self, "e_T", self.e_T, 0.0, 1.0))

    @property
    def restitution(self):
        """ε (3,) = (e, e_T, e_T): ξ = γ⁺ + ε γ⁻."""
        return np.array([self.e, self.e_T, self.e_T])

    def project(self, z):
        """prox of ``z`` (3,) [N s]: N onto R+, then T onto the disk of radius μ Λ_N."""
        z = np.asarray(z, dtype=float)
        lam_N = self.normal.project(z[0])
        return np.concatenate(([lam_N], self.friction.project(z[1:], lam_N)))


@dataclass(frozen=True)
class LinearRegularizedUnilateralConstraint:
    """A penalty (spring-damper) normal contact force, single-valued (thesis sec. 5, S3/S4).

        F_N = max(0, −k g_N − d ġ_N)   if g_N < 0,      F_N = 0   if g_N >= 0      [N]

    with g_N > 0 apart (m) and ġ_N > 0 separating (m/s); F_N >= 0 pushes the contours
    apart (it enters h as W_N F_N). The damper never pulls: F_N is clipped at 0.

    Parameters
    ----------
    k : float >= 0
        Stiffness [N/m].
    d : float >= 0
        Damping [N s/m].
    """

    k: float
    d: float = 0.0
    kind: ClassVar[str] = "single-valued"
    dim: ClassVar[int] = 1
    units: ClassVar[dict] = {"k": "N/m", "d": "N s/m"}

    def __post_init__(self):
        object.__setattr__(self, "k", _coefficient(self, "k", self.k, 0.0))
        object.__setattr__(self, "d", _coefficient(self, "d", self.d, 0.0))

    def _active(self, g_N, gd_N):
        g_N, gd_N = np.asarray(g_N, dtype=float), np.asarray(gd_N, dtype=float)
        return (g_N < 0.0) & (-self.k * g_N - self.d * gd_N > 0.0), g_N, gd_N

    def force(self, g_N, gd_N):
        """F_N [N] for gaps ``g_N`` [m] and gap rates ``gd_N`` [m/s] (broadcast)."""
        active, g_N, gd_N = self._active(g_N, gd_N)
        return np.where(active, -self.k * g_N - self.d * gd_N, 0.0)

    def derivatives(self, g_N, gd_N):
        """(∂F_N/∂g_N [N/m], ∂F_N/∂ġ_N [N s/m]): (−k, −d) where F_N > 0, else (0, 0)."""
        active, _, _ = self._active(g_N, gd_N)
        return np.where(active, -self.k, 0.0), np.where(active, -self.d, 0.0)


@dataclass(frozen=True)
class RegularizedCoulombFriction:
    """Coulomb friction regularized by a linear viscous branch, single-valued.

        F_T = −μ F_N γ_T / max(|γ_T|, v_eps)      [N]

    for a tangential relative velocity γ_T (..., n_T) [m/s] (n_T = 2 spatial, 1 planar)
    and a normal force F_N >= 0 [N]: Coulomb's |F_T| = μ F_N opposite to the sliding
    velocity for |γ_T| >= v_eps, a viscous F_T = −(μ F_N / v_eps) γ_T below (continuous;
    stiction is approximated by creep at speeds below v_eps).

    Parameters
    ----------
    mu : float >= 0
        Coefficient of friction [-].
    v_eps : float > 0
        Regularization speed [m/s].
    """

    mu: float
    v_eps: float
    kind: ClassVar[str] = "single-valued"
    dim: ClassVar[int] = 2
    units: ClassVar[dict] = {"v_eps": "m/s"}

    def __post_init__(self):
        object.__setattr__(self, "mu", _coefficient(self, "mu", self.mu, 0.0))
        v_eps = _coefficient(self, "v_eps", self.v_eps, 0.0)
        if v_eps == 0.0:
            raise ModelError(f"{self}: v_eps must be > 0")
        object.__setattr__(self, "v_eps", v_eps)

    def _scaled(self, gamma_T):
        gamma_T = np.asarray(gamma_T, dtype=float)
        speed = np.linalg.norm(gamma_T, axis=-1)
        return gamma_T, speed, np.maximum(speed, self.v_eps)

    def force(self, gamma_T, F_N):
        """F_T (..., n_T) [N] for ``gamma_T`` (..., n_T) [m/s] and ``F_N`` (...) [N]."""
        gamma_T, _, denom = self._scaled(gamma_T)
        return -self.mu * (np.asarray(F_N, dtype=float) / denom)[..., None] * gamma_T

    def derivatives(self, gamma_T, F_N):
        """(∂F_T/∂γ_T (..., n_T, n_T) [N s/m], ∂F_T/∂F_N (..., n_T) [-]).

        ∂F_T/∂γ_T = −μ F_N / v_eps I below v_eps, −μ F_N / |γ_T| (I − t tᵀ) above
        (t = γ_T / |γ_T|); ∂F_T/∂F_N = −μ γ_T / max(|γ_T|, v_eps).
        """
        gamma_T, speed, denom = self._scaled(gamma_T)
        F_N = np.asarray(F_N, dtype=float)
        n_T = gamma_T.shape[-1]
        t = gamma_T / denom[..., None]
        sliding = (speed > self.v_eps)[..., None, None]
        outer = np.where(sliding, t[..., :, None] * t[..., None, :], 0.0)
        dF_dgamma = -self.mu * (F_N / denom)[..., None, None] * (np.eye(n_T) - outer)
        return dF_dgamma, -self.mu * t

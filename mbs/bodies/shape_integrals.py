"""Constant shape integrals of an FFR body and the O(n_f²) terms built from them.

Thesis eq. 2.53, 2.54 and 2.65 define, for lumped node masses m_j, undeformed positions
ū0_j = (x_1, x_2, x_3)_j and mode-shape rows Φ_j = (Φ_1; Φ_2; Φ_3)_j (3 × n_f):

    m       = Σ m_j                                   [kg]
    I1      = Σ m_j ū0_j                      (2.53)  [kg m]        (3,)
    S_bar   = Σ m_j Φ_j                       (2.54)  [kg^½]        (3, n_f)
    I_kl    = Σ m_j x_k x_l                   (2.65)  [kg m²]       (3, 3)
    I_bar   = Σ m_j x_k Φ_l                   (2.65)  [kg^½ m]      (3, 3, n_f)
    S_kl    = Σ m_j Φ_kᵀ Φ_l                  (2.65)  [-]           (3, 3, n_f, n_f)

With a consistent mass matrix M_FE = M_s ⊗ 1₃ (:func:`preprocess.fe.consistent_mass_matrix`)
the node sums become double sums over node pairs (a, b), ∫ ρ ... dV = Σ_ab M_ab ...:

    m = 1ᵀ M_s 1,  I1 = Σ_ab M_ab ū0_b,  S_bar = Σ_ab M_ab Φ_b,
    I_kl = Σ_ab M_ab x_ak x_bl,  I_bar = Σ_ab M_ab x_ak Φ_bl,  S_kl = Σ_ab M_ab Φ_akᵀ Φ_bl   (C1)

(:meth:`ShapeIntegrals.from_mass_matrix`); lumped masses are the case M_s = diag(m_j).

Everything the equations of motion need per step follows from these by contractions
with q_f and q̇_f, never by a loop over nodes. One auxiliary array carries most of it,

    G[k, l] = Σ m_j ū_k Φ_l = I_bar[k, l] + S_kl[l, k] q_f      (3, 3, n_f),

with ū = ū0 + Φ q_f (eq. 2.23): then S̄_t = I1 + S̄ q_f (eq. 2.55), the inertia tensor
Ī_θθ = tr(U) 1 − U with U[k, l] = Σ m ū_k ū_l (eq. 2.59, 2.64), and
Ī_θf = Σ m ũ Φ (eq. 2.67) whose rows are G[1,2]−G[2,1], G[2,0]−G[0,2], G[0,1]−G[1,0].
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class ShapeIntegrals:
    """The constant shape integrals of thesis eq. 2.53, 2.54, 2.65 (see module docstring)."""

    mass: float
    I1: np.ndarray
    S_bar: np.ndarray
    I_kl: np.ndarray
    I_bar: np.ndarray
    S_kl: np.ndarray
    M_ff: np.ndarray      # Σ_k S_kl[k, k] = m_ff of thesis eq. 2.69  (n_f, n_f)
    S_skew: np.ndarray    # (3, n_f, n_f): S_kl[2,1]−S_kl[1,2], S_kl[0,2]−S_kl[2,0], S_kl[1,0]−S_kl[0,1]

    @classmethod
    def from_nodes(cls, u0, phi, masses) -> "ShapeIntegrals":
        """Sum over the nodes once: ``u0`` (N, 3) [m], ``phi`` (3N, n_f) node-major,
        ``masses`` (N,) [kg]. Cost O(N n_f²), paid once per body."""
        u0 = np.asarray(u0, dtype=float)
        m = np.asarray(masses, dtype=float)
        n_f = phi.shape[1]
        P = np.asarray(phi, dtype=float).reshape(len(m), 3, n_f)
        mP = m[:, None, None] * P
        S_kl = np.empty((3, 3, n_f, n_f))
        for k in range(3):
            for l in range(3):
                S_kl[k, l] = mP[:, k, :].T @ P[:, l, :]
        S_skew = np.stack([S_kl[2, 1] - S_kl[1, 2], S_kl[0, 2] - S_kl[2, 0], S_kl[1, 0] - S_kl[0, 1]])
        return cls(
            mass=float(m.sum()),
            I1=m @ u0,
            S_bar=mP.sum(axis=0),
            I_kl=(m[:, None] * u0).T @ u0,
            I_bar=np.einsum("jk,jla->kla", m[:, None] * u0, P),
            S_kl=S_kl,
            M_ff=S_kl[0, 0] + S_kl[1, 1] + S_kl[2, 2],
            S_skew=S_skew,
        )

    @classmethod
    def from_mass_matrix(cls, u0, phi, mass_matrix) -> "ShapeIntegrals":
        """The shape integrals (C1) of a scalar mass matrix ``mass_matrix`` M_s (N, N)
        [kg] (sparse or dense, symmetric): ``u0`` (N, 3) [m], ``phi`` (3N, n_f)
        node-major. With Y = M_s X for X = [1, ū0, Φ] each integral is a product XᵀY;
        cost O(nnz(M_s) n_f + N n_f²), paid once per body."""
        u0 = np.asarray(u0, dtype=float)
        n = u0.shape[0]
        n_f = phi.shape[1]
        P = np.asarray(phi, dtype=float).reshape(n, 3, n_f)
        MP = np.asarray(mass_matrix @ P.reshape(n, 3 * n_f)).reshape(n, 3, n_f)   # Σ_b M_ab Φ_b
        Mu = np.asarray(mass_matrix @ u0)                                         # Σ_b M_ab ū0_b
        w = np.asarray(mass_matrix.sum(axis=1)).ravel()                           # Σ_b M_ab
        S_kl = np.empty((3, 3, n_f, n_f))
        for k in range(3):
            for l in range(3):
                S_kl[k, l] = P[:, k, :].T @ MP[:, l, :]
        S_kl = 0.5 * (S_kl + S_kl.transpose(1, 0, 3, 2))      # S_kl[k, l] = S_kl[l, k]ᵀ exactly
        S_skew = np.stack([S_kl[2, 1] - S_kl[1, 2], S_kl[0, 2] - S_kl[2, 0], S_kl[1, 0] - S_kl[0, 1]])
        I_kl = u0.T @ Mu
        return cls(
            mass=float(w.sum()),
            I1=w @ u0,
            S_bar=MP.sum(axis=0),
            I_kl=0.5 * (I_kl + I_kl.T),
            I_bar=np.einsum("jk,jlf->klf", u0, MP),
            S_kl=S_kl,
            M_ff=S_kl[0, 0] + S_kl[1, 1] + S_kl[2, 2],
            S_skew=S_skew,
        )

    @property
    def n_modes(self) -> int:
        return self.S_bar.shape[1]

    def deformed(self, q_f):
        """(S̄_t (3,), Ī_θθ (3, 3), Ī_θf (3, n_f), G (3, 3, n_f)) at the elastic coordinates
        ``q_f`` (eq. 2.55, 2.59/2.64, 2.67); O(n_f²)."""
        Sq = self.S_kl @ q_f                       # Sq[a, b] = S_kl[a, b] q_f   (3, 3, n_f)
        G = self.I_bar + Sq.transpose(1, 0, 2)     # G[k, l] = Ī_kl + S_lk q_f
        S_t = self.I1 + self.S_bar @ q_f
        U = self.I_kl + self.I_bar.transpose(1, 0, 2) @ q_f + G @ q_f   # Σ m ū_k ū_l
        I_thth = np.trace(U) * np.eye(3) - U
        I_thf = np.stack([G[1, 2] - G[2, 1], G[2, 0] - G[0, 2], G[0, 1] - G[1, 0]])
        return S_t, I_thth, I_thf, G

    def quadratic_velocity(self, A, omega_bar, qdot_f, S_t, I_thth, G):
        """Q_v = −Σ m_j J_Tjᵀ J̇_Tj u in the coordinates (Ṙ, ω̄, q̇_f), from the shape
        integrals only (thesis eq. 2.77–2.79, derived for body-frame ω̄):

            (Q_v)_R = −A [ω̃² S̄_t + 2 ω̃ S̄ q̇_f]
            (Q_v)_θ = −ω̃ Ī_θθ ω̄ − 2 (tr P ω̄ − Pᵀ ω̄),       P[k, l] = G[k, l] q̇_f
            (Q_v)_f = −(Σ_kl ω_k ω_l G[k, l] − |ω̄|² Σ_k G[k, k]) − 2 Σ_kl ω̃_kl S_kl q̇_f

        Returns the three blocks (3,), (3,), (n_f,).
        """
        w = omega_bar
        wt = np.array([[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]])
        Sqd = self.S_bar @ qdot_f
        Q_R = -A @ (wt @ (wt @ S_t) + 2.0 * (wt @ Sqd))
        P = G @ qdot_f
        Q_th = -np.cross(w, I_thth @ w) - 2.0 * (np.trace(P) * w - P.T @ w)
        Q_f = -(np.einsum("k,l,kla->a", w, w, G) - (w @ w) * (G[0, 0] + G[1, 1] + G[2, 2]))
        Q_f -= 2.0 * np.einsum("k,kab,b->a", w, self.S_skew, qdot_f)
        return Q_R, Q_th, Q_f

"""Mode truncation by the report's effective mass (report Sec. 4.3, eq. 36; Sec. 5.3, Table 2).

The mode displacement method keeps the modes that carry most of the response.
The report ranks modes by an "effective mass" (eq. 36)

    m_j^eff = |Pᵀ M f_ext|_j / ω_j²,

and keeps the smallest set holding at least 90 % of the sum over ALL elastic modes
(the EN 1998-1 cut-off, report footnote 7). Rigid-body modes are excluded: they are
handled by rigid-body motion (report Sec. 3.3).

Derivation and the typo in eq. 36
---------------------------------
With mass-normalized modes (Pᵀ M P = I, eq. 3) the modal force is F = Pᵀ f_ext
(eq. 5, eq. 33) and a constant load F_j gives the modal amplitude

    r_j = F_j / ω_j² · (1 − cos ω_j t)        (eq. 10/12, one step from rest),

i.e. a quasi-static part F_j / ω_j² plus an oscillation of the same size. The
report's text says eq. 36 is "the inner product of f_ext with each mode ... factor
1/ω² ... as per Equation 12", which is |φ_jᵀ f_ext| / ω_j² — the size of mode j's
quasi-static amplitude [m kg^1/2]. The M in eq. 36 does not belong there: Pᵀ M u
projects a *displacement* u onto the modes (it inverts u = P r); a *force* projects
with Pᵀ alone. Both are offered:

* ``weighting="static"`` (default): m_j = |φ_jᵀ f| / ω_j²  [m kg^1/2];
* ``weighting="report"``: eq. 36 literally, m_j = |φ_jᵀ M f| / ω_j²  [m kg^3/2],
  for reproducing the style of the report's Table 2 percentages. With lumped
  masses it weights each node's force by its mass, so it differs from "static"
  wherever loaded nodes have unequal masses (e.g. tet10 corner vs mid-edge nodes).

Also: the column headed "ω" in Table 2 holds ω² (39224 rad²/s² is the 198 rad/s
first bending mode of the clamped 1 x 1 x 5 m steel beam).

For a load history (n_t step loads, eq. 9) the measure is taken per mode as the
maximum over the load steps. Note that |F_j| is not invariant under a change of
basis inside a (nearly) degenerate eigenspace, such as the two first bending modes
of a square beam; the split between such partner modes depends on the eigensolver.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from ffrmbs.errors import ModelError
from preprocess.body import mass_times
from preprocess.modes import all_modes

WEIGHTINGS = ("static", "report")
ORDERS = ("largest", "lowest")
_REL_TOL = 1e-12  # a fraction reached to rounding counts as reached


def _force_history(forces, n_nodes) -> np.ndarray:
    """``forces`` (N, 3) or (n_t, N, 3) [N] as an (n_t, 3N) array."""
    f = np.asarray(forces, dtype=float)
    if f.ndim == 2:
        f = f[None]
    if f.ndim != 3 or f.shape[1:] != (n_nodes, 3):
        raise ModelError(f"forces must have shape ({n_nodes}, 3) or (n_t, {n_nodes}, 3), not {np.shape(forces)}")
    return f.reshape(f.shape[0], 3 * n_nodes)


def effective_masses(phi, omega2, masses, forces, weighting="static") -> np.ndarray:
    """Effective mass of each mode for a load (report eq. 36, see module docstring).

    Parameters
    ----------
    phi : (3N, n) mass-normalized elastic modes [kg^-1/2], node-major rows.
    omega2 : (n,) eigenvalues ω² [rad²/s²], all > 0 (rigid modes are treated
        separately, report Sec. 3.3).
    masses : (N,) lumped node masses, or the body's sparse consistent M_s (N, N) [kg]
        (the mass the modes are normalized with; ``BodyData.mass``).
    forces : (N, 3) nodal forces [N], or a step history (n_t, N, 3).
    weighting : "static" — |φ_jᵀ f| / ω_j², the quasi-static modal amplitude of
        eq. 12 [m kg^1/2]; "report" — eq. 36 literally, |φ_jᵀ M f| / ω_j² [m kg^3/2].

    Notes
    -----
    Returns (n,) m_eff; for a history, per mode the maximum over the load steps.
    """
    phi = np.asarray(phi, dtype=float)
    omega2 = np.asarray(omega2, dtype=float)
    if not sp.issparse(masses):
        masses = np.asarray(masses, dtype=float)
    n_nodes = masses.shape[0]
    if weighting not in WEIGHTINGS:
        raise ModelError(f"weighting must be one of {WEIGHTINGS}, not {weighting!r}")
    if phi.ndim != 2 or phi.shape[0] != 3 * n_nodes or omega2.shape != (phi.shape[1],):
        raise ModelError(f"phi {phi.shape}, omega2 {omega2.shape} and masses {masses.shape} "
                         "do not fit: need phi (3N, n), omega2 (n,), masses (N,)")
    if np.any(omega2 <= 0):
        raise ModelError(f"modes {np.flatnonzero(omega2 <= 0) + 1} have ω² <= 0; rigid-body modes are "
                         "treated separately (report Sec. 3.3) — pass only the elastic modes")
    f = _force_history(forces, n_nodes)
    if weighting == "report":
        f = mass_times(masses, f.T).T
    return np.abs(f @ phi).max(axis=0) / omega2


def select_modes(m_eff, fraction=0.9, order="largest", total=None) -> np.ndarray:
    """The smallest set of modes holding at least ``fraction`` of ``total`` (report Sec. 4.3).

    ``m_eff`` (n,) effective masses (:func:`effective_masses`) of modes sorted by
    ascending ω²; ``total`` the reference sum, by default ``m_eff.sum()`` (the
    report uses the sum over all modes, :func:`preprocess.modes.all_modes`).
    ``order="largest"`` takes modes by decreasing m_eff (the report's "modes 1, 2
    and 4", Sec. 5.3); ``order="lowest"`` takes the first k modes.
    Returns the sorted 0-based indices. A ModelError says how much all given modes
    hold when that is less than ``fraction`` of ``total``.
    """
    m_eff = np.asarray(m_eff, dtype=float)
    if order not in ORDERS:
        raise ModelError(f"order must be one of {ORDERS}, not {order!r}")
    if not 0.0 < fraction <= 1.0:
        raise ModelError(f"fraction must be in (0, 1], not {fraction}")
    if m_eff.ndim != 1 or m_eff.size == 0 or np.any(m_eff < 0):
        raise ModelError("m_eff must be a non-empty 1-D array of non-negative effective masses")
    total = m_eff.sum() if total is None else float(total)
    if not total > 0:
        raise ModelError(f"the total effective mass must be positive, not {total}")
    target = fraction * total * (1.0 - _REL_TOL)
    if m_eff.sum() < target:
        raise ModelError(
            f"the {m_eff.size} given modes hold {m_eff.sum() / total:.2%} of the total effective mass, "
            f"less than {fraction:.0%}; more modes are needed")
    ranked = np.argsort(-m_eff, kind="stable") if order == "largest" else np.arange(m_eff.size)
    k = int(np.argmax(np.cumsum(m_eff[ranked]) >= target)) + 1
    return np.sort(ranked[:k])


def effective_mass_table(omega2, m_eff, selected=None, total=None) -> str:
    """A markdown table in the style of report Table 2.

    Columns: mode (1-based), ω² [rad²/s²] (the report's column headed "ω" holds ω²),
    m_eff, % of ``total`` (default the sum of ``m_eff``), and "x" for modes in
    ``selected`` (0-based indices). Closing rows: the sum over the listed modes and,
    when ``total`` differs from it, the reference total (100 %).
    """
    m_eff = np.asarray(m_eff, dtype=float)
    shown = m_eff.sum()
    total = shown if total is None else float(total)
    chosen = np.zeros(m_eff.size, dtype=bool)
    if selected is not None:
        chosen[np.asarray(selected, dtype=int)] = True
    rows = ["| mode | ω² [rad²/s²] | m_eff | % | selected |", "|---:|---:|---:|---:|:---:|"]
    rows += [f"| {j + 1} | {w:.6g} | {m:.3g} | {100 * m / total:.2f}% | {'x' if c else ''} |"
             for j, (w, m, c) in enumerate(zip(omega2, m_eff, chosen))]
    label = "Total" if np.isclose(shown, total, rtol=1e-12) else "Total (listed modes)"
    rows.append(f"| {label} | - | {shown:.3g} | {100 * shown / total:.2f}% | {int(chosen.sum())} |")
    if label != "Total":
        rows.append(f"| Total (reference) | - | {total:.3g} | 100.00% | |")
    return "\n".join(rows)


@dataclass(frozen=True)
class ModeSelection:
    """Result of :func:`auto_select_modes`.

    ``indices`` sorted 0-based indices of the selected body modes; ``omega2`` (n,)
    and ``m_eff`` (n,) of the body's modes; ``fraction_held`` = Σ m_eff[indices] /
    ``total``; ``total`` the reference sum; ``total_kind`` "all modes (dense)" or
    "computed modes" (the body's modes only, when the model is too large for
    :func:`preprocess.modes.all_modes`).
    """

    indices: np.ndarray
    omega2: np.ndarray
    m_eff: np.ndarray
    fraction_held: float
    total: float
    total_kind: str

    def table(self) -> str:
        """Report Table 2 style markdown table, preceded by what the total is over."""
        return (f"Reference total over {self.total_kind}; selected modes hold {self.fraction_held:.2%}.\n\n"
                + effective_mass_table(self.omega2, self.m_eff, self.indices, self.total))


def body_clamped_nodes(data):
    """The clamped nodes of a body: the node group named by ``data.params["clamp"]``,
    else the nodes whose mode-shape rows are all zero (clamped_modes leaves them zero;
    text-file bodies carry no params); None for a free body."""
    name = data.params.get("clamp")
    if name is not None:
        if name not in data.node_groups:
            raise ModelError(f"the clamped node group {name!r} is not among the body's groups "
                             f"{sorted(data.node_groups)}")
        return data.node_groups[name]
    zero = ~data.phi.reshape(data.n_nodes, 3 * data.n_modes).any(axis=1)
    return np.flatnonzero(zero) if zero.any() else None


def auto_select_modes(data, forces, fraction=0.9, weighting="static", order="largest",
                      clamped_nodes=None, max_dof=6000) -> ModeSelection:
    """Select the body's modes holding ``fraction`` of the effective mass of ALL modes (report Sec. 4.3).

    ``data`` a :class:`preprocess.body.BodyData` whose modes are the lowest ones;
    ``forces`` (N, 3) or (n_t, N, 3) [N]. The reference total is the sum of
    :func:`effective_masses` over all elastic modes from a dense eigensolve
    (:func:`preprocess.modes.all_modes`) when the model has at most ``max_dof``
    free DOFs, else over the body's modes (``total_kind`` says which). Clamping:
    ``clamped_nodes`` if given, else :func:`body_clamped_nodes`.
    A ModelError names how many modes to preprocess when the body's modes do not
    reach ``fraction``.
    """
    omega2 = data.modal_eigenvalues()
    m_eff = effective_masses(data.phi, omega2, data.mass, forces, weighting)
    clamped = body_clamped_nodes(data) if clamped_nodes is None else np.asarray(clamped_nodes)
    n_free = 3 * data.n_nodes - (0 if clamped is None else 3 * len(clamped))
    if n_free > max_dof:
        total, kind = m_eff.sum(), "computed modes"
    else:
        w2_all, phi_all = all_modes(data.stiffness, data.mass, clamped, data.u0, max_dof)
        m_all = effective_masses(phi_all, w2_all, data.mass, forces, weighting)
        total, kind = m_all.sum(), "all modes (dense)"
    try:
        indices = select_modes(m_eff, fraction, order, total)
    except ModelError as err:  # only possible against the all-modes total
        need = max(select_modes(m_all, fraction, order).max() + 1, data.n_modes + 1)
        raise ModelError(f"{err}: preprocess at least {need} modes (the body file has {data.n_modes})") from None
    return ModeSelection(indices, omega2, m_eff, float(m_eff[indices].sum() / total), float(total), kind)

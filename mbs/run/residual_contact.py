"""Contacts on contours with residual flexibility: the compliance of each closed contact in
its contact frame, for the compliant contact problem of :mod:`contact.compliance`.

At compile time (:class:`ResidualContacts`) every contour with ``residual_flexibility``
set gets its :class:`~contours.residual.ResidualCompliance` on its body's kept modes;
the corrected contours of one body share one residual flexibility (cross-compliance
between them included), computed from one factorization of the body's stiffness, or
read from ``System.cache_dir``. Each step
(:func:`assemble`) the closed compliant contacts' rows and their compliance

    C_jk = Σ_{sides a of j, b of k on one body} s_a s_b R_jᵀ A c(a, b) Aᵀ R_k     (r × r) [m/N]

are formed, with R_j = [n, T] (3 × dim) the contact frame (world axes; [n, t2] for a point
kept on a curve), A the body's
rotation, c(a, b) the residual compliance between the two contact points (body axes,
eq. C2 of :mod:`contours.residual`) and s = +1 on a contact's contour 1 (the point side),
−1 on its contour 2: the force Λ acts along +R on side 1 and −R on side 2, and g_N, γ
measure side 1 relative to side 2 (:mod:`contact.kinematics`), so each side's
deflection opens the gap.
"""

from __future__ import annotations

import numpy as np

from contact.kinematics import PointOnCurveConstraint
from contours._residual_kernels import add_contact_block, add_table_blocks
from contours.residual import residual_compliances
from ffrmbs.errors import ModelError

from mbs.run import _stage_kernels as SK


class ResidualContacts:
    """The compliant sides of a System's contacts (module docstring).

    Parameters
    ----------
    contacts : sequence of contacts
    set_valued : sequence of bool
    cache_dir : path or None
        Where the projected static flexibility of each corrected contour is cached
        (:func:`contours.residual.residual_compliances`).

    Attributes
    ----------
    sides : tuple
        Per contact a tuple of (sign, ResidualCompliance, side) — side 1 or 2 — of its
        corrected contours (empty: a rigid contact).
    compliant : tuple of bool
        The contact has a corrected contour (the contact table's COMPLIANT column, for the
        kernels).
    compliances : dict
        The ResidualCompliance of each corrected contour, by id.
    skip : tuple of int
        Per contact the first tangent of its rows: 0 for [n, t1, t2] (a contact), 1 for
        [n, t2] (a point kept on a curve, :class:`contact.CurveConstraint`).
    table_G : (3 k, 3 k) array or None
        The bodies' residual flexibilities G_P, block diagonal (one body's G_P itself),
        which one kernel reads for all pairs of closed sides
        (:func:`contours._residual_kernels.add_table_blocks`); None without compliances.
    table_place : dict
        Per corrected contour (by id) the first place of its body's points in ``table_G``
        and the body's index.
    max_weights : int
        The most weight blocks a side has (eq. C1).
    """

    def __init__(self, contacts, set_valued, cache_dir=None):
        by_body = {}
        for i, c in enumerate(contacts):
            for contour in c.contours():
                if getattr(contour, "residual_flexibility", False):
                    if not set_valued[i]:
                        raise ModelError(f"contact {c.name!r}: residual flexibility needs a set-valued law "
                                         "(Newton impact or Coulomb contact); a penalty law's spring is the "
                                         "contact's own compliance")
                    if contour.body is None or not hasattr(contour.body, "K_ff"):
                        raise ModelError(f"contour {contour.name!r}: residual flexibility needs a flexible body")
                    group = by_body.setdefault(id(contour.body), (contour.body, {}))[1]
                    group[id(contour)] = contour
        self.compliances = {}
        for body, group in by_body.values():
            contours = list(group.values())
            for contour, rc in zip(contours, residual_compliances(contours, None, cache_dir)):
                self.compliances[id(contour)] = rc
        sides = []
        for c in contacts:
            k = c.kinematics
            s = []
            for sign, side, contour in ((1.0, 1, k.contour1), (-1.0, 2, k.contour2)):
                if id(contour) in self.compliances:
                    s.append((sign, self.compliances[id(contour)], side))
            sides.append(tuple(s))
        self.sides = tuple(sides)
        self.compliant = tuple(bool(s) for s in sides)
        self.skip = tuple(int(isinstance(c.kinematics, PointOnCurveConstraint)) for c in contacts)
        self.table_G, self.table_place = _compliance_table(self.compliances)
        self.max_weights = max((rc.n_weights for rc in self.compliances.values()), default=0)

    def __bool__(self):
        return any(self.compliant)


def _compliance_table(compliances) -> tuple:
    """(table_G, table_place) of :class:`ResidualContacts`: one body's G_P itself, several
    bodies' laid block-diagonally (None without compliances)."""
    groups, base, n = {}, {}, 0
    for rc in compliances.values():
        if id(rc.G_P) not in groups:
            groups[id(rc.G_P)], base[id(rc.G_P)] = rc.G_P, n
            n += rc.G_P.shape[0] // 3
    place = {key: (base[id(rc.G_P)], list(groups).index(id(rc.G_P))) for key, rc in compliances.items()}
    if len(groups) <= 1:
        return next(iter(groups.values()), None), place
    G = np.zeros((3 * n, 3 * n))
    for key, G_P in groups.items():
        a = 3 * base[key]
        G[a:a + G_P.shape[0], a:a + G_P.shape[0]] = G_P
    return G, place


def assemble(model, data, dt) -> int:
    """The compliant rows of this step's contact problem, their compliance and spring
    state (module docstring) into Data's workspaces; the state of a contact that was open
    last step is zeroed first and its rows marked fresh (:func:`contact.compliance.compliant_problem`
    gives them the deflection of the other contacts' forces). Returns r, the number of compliant rows. Allocates no
    numpy array (:mod:`contours._residual_kernels`)."""
    rc = model.residual
    r = 0
    row = model.n_c
    entries = data.comp_entries
    n_e = 0
    for j in range(data.n_closed):
        i = data.closed_idx[j]
        dim = model.dims[i]
        if rc.compliant[i]:
            at = model.lam_at[i]
            fresh = not data.warm[i]
            for x in range(dim):
                if fresh:
                    data.comp_force[at + x] = data.comp_delta[at + x] = data.comp_delta_dot[at + x] = 0.0
                data.comp_rows[r + x] = row + x
                data.comp_fresh[r + x] = fresh
                data.comp_normal[r + x] = r
                data.comp_F[r + x] = data.comp_force[at + x]
                data.comp_d[r + x] = data.comp_delta[at + x]
                data.comp_dd[r + x] = data.comp_delta_dot[at + x]
            k = model.contacts[i].kinematics
            for sign, comp, side in rc.sides[i]:
                point = k.point1 if side == 1 else k.point2
                entries[n_e] = (r, dim, sign, comp, point.eta, point.xi, k, rc.skip[i])
                n_e += 1
            r += dim
        row += dim
    C = data.compliance(r)
    C.fill(0.0)
    _table_blocks(rc, data, entries, n_e, C)
    data.comp_r = r
    return r


def table_blocks_reference(entries, n_e, C, c, work) -> None:
    """The reference of :func:`_table_blocks` (tests): the pair loop over the
    compliances' ``between`` and :func:`contours._residual_kernels.add_contact_block`."""
    for a in range(n_e):
        ra, da, sa, ca, eta_a, xi_a, ka, ta = entries[a]
        for b in range(n_e):
            rb, db, sb, cb, eta_b, xi_b, kb, tb = entries[b]
            if cb.G_P is ca.G_P:
                ca.between(eta_a, xi_a, eta_b, xi_b, cb, c)
                add_contact_block(C, ra, da, rb, db, sa * sb, ka.n, ka.T, ta, kb.n, kb.T, tb, ca.rotation, c, work)


def _table_blocks(rc, data, entries, n_e, C) -> None:
    """C (r, r) of the closed compliant sides in one kernel over all pairs of sides on one
    body (:func:`contours._residual_kernels.add_table_blocks`): each side's weight blocks
    (eq. C1) found once, not once per pair; the sums of :func:`table_blocks_reference`."""
    ints, blocks, index, signs, normals, tangents, rotations = data.comp_table
    for e in range(n_e):
        row, dim, sign, comp, eta, xi, k, skip = entries[e]
        side = ints[e]
        side[0], side[1], side[3] = row, dim, skip
        side[5], side[2] = rc.table_place[id(comp.contour)]
        side[4] = comp.kernel_weights(eta, xi, blocks[e], index[e])
        signs[e] = sign
        normals[e] = k.n
        tangents[e] = k.T
        rotations[e] = comp.rotation
    add_table_blocks(C, rc.table_G, n_e, ints, blocks, index, signs, normals, tangents, rotations, data.comp_c,
                     data.comp_work)


def store(model, data) -> None:
    """The spring state of the compliant rows and their Λ₀ back into the contacts' slots."""
    r = 0
    for j in range(data.n_closed):
        i = data.closed_idx[j]
        if model.residual.compliant[i]:
            at = model.lam_at[i]
            for x in range(model.dims[i]):
                data.comp_force[at + x] = data.comp_F[r]
                data.comp_delta[at + x] = data.comp_d[r]
                data.comp_delta_dot[at + x] = data.comp_dd[r]
                data.comp_impulse0[at + x] = data.comp_lam0[r]
                r += 1


def spring_energy(model, data) -> float:
    """½ Σ Fᵀ δ [J] of the contacts closed at the end of the last step (their springs'
    energy; zero without residual flexibility)."""
    if model.residual is None:
        return 0.0
    return SK.spring_energy(model.contact_table, data.warm, data.comp_force, data.comp_delta)

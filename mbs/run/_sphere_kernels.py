"""numba kernels of the planned broad phase (:mod:`mbs.run.bounding_spheres`): the bounding
spheres of contours at the global state and the pruning of every prunable contact in one
call, allocation-free.

Sphere kinds (``kind`` codes):

- :data:`POINT`: a frame on a point mass, centre r = q[at:at+3] + ū0 [m] (``offset``),
  constant radius (``radius0``) — :class:`mbs.run.bounding_spheres.FrameSphere`;
- :data:`AT_REST`: a flexible body on a frame fixed in space, constant centre (written
  once by the caller), radius ``radius0`` + Σ_k max_j |Φ_jk| |q_f,k| (``radius0`` =
  max_j |ū0_j − c| and what an offset contour adds) with max_j |Φ_jk| in
  ``reach[s, :n_reach[s]]`` and q_f at q[at:] —
  :meth:`mbs.bodies.flexible_body.FlexibleBodyFFR.bounding_sphere`; also a sphere fixed
  in space (a point or sphere contour on the ground: no reach);
- :data:`FREE`: a body on a free frame with a quaternion (a rigid body's frame, or a
  flexible body's bounding sphere), centre R + A c with R = q[at:at+3], A the rotation
  of the quaternion q[at+3:at+7] (:func:`mbs.bodies.rotations.quat_to_matrix`) and c the
  body-frame point ``offset`` (a frame's ū0, the body's :attr:`box_centre`), radius
  ``radius0`` + Σ_k reach[s, k] |q_f,k| with q_f at q[at+7:] (none for a rigid body);
- :data:`CALLED`: any other sphere; the caller writes its centre and radius (the
  kernel leaves them);
- :data:`PLANE`: not a sphere but the half-space behind a plane fixed in space (a plane
  contour on the ground): a point p0 of the plane as its centre (written once by the
  caller), its unit normal n in ``offset``, radius 0. A pair with a plane as its second
  bound is live while the first sphere reaches within the margin of the plane:
  nᵀ(c1 − p0) <= r1 + margin (a centre behind the plane, penetrating, is live).

Plain-numpy reference: the sphere callables of :mod:`mbs.run.bounding_spheres` and the
test d·d > (r1 + r2 + margin)² of each pair (the half-space test for a plane); ``tests/unit/contact/test_bounding_spheres.py`` compares
them.
"""

from __future__ import annotations

from numba import njit

from mbs.bodies._kernels import quat_matrix_into
from mbs.run._stage_kernels import live_contacts

POINT, AT_REST, CALLED, FREE, PLANE = 0, 1, 2, 3, 4
INTS_AT = 3     # ints: n_s, n_p, width, then kind, at, n_reach (n_s each), contact, sphere1, sphere2 (n_p each)


@njit(cache=True)
def sphere_states(q, kind, at, offset, radius0, reach, n_reach, centres, radii, A):
    """Centres (n_s, 3) [m] and radii (n_s,) [m] of the POINT, AT_REST and FREE spheres at
    the global q into ``centres``, ``radii`` (module docstring; ``A`` (3, 3) a work array
    for a free frame's rotation); CALLED rows untouched."""
    for s in range(kind.shape[0]):
        k = kind[s]
        if k == POINT:
            for c in range(3):
                centres[s, c] = q[at[s] + c] + offset[s, c]
            radii[s] = radius0[s]
        elif k == AT_REST:
            r = 0.0
            for j in range(n_reach[s]):
                r += reach[s, j] * abs(q[at[s] + j])
            radii[s] = radius0[s] + r
        elif k == FREE:
            o = at[s]
            quat_matrix_into(q, o + 3, A)
            for c in range(3):
                centres[s, c] = q[o + c] + (A[c, 0] * offset[s, 0] + A[c, 1] * offset[s, 1] + A[c, 2] * offset[s, 2])
            r = 0.0
            for j in range(n_reach[s]):
                r += reach[s, j] * abs(q[o + 7 + j])
            radii[s] = radius0[s] + r


@njit(cache=True)
def prune_pairs(contact, sphere1, sphere2, margin, kind, offset, centres, radii, live, closed):
    """Each prunable contact ``contact[p]`` live when its spheres ``sphere1[p]``,
    ``sphere2[p]`` come within ``margin[p]`` [m]: not |c1 − c2|² > (r1 + r2 + margin)²
    (a PLANE second: not nᵀ(c1 − p0) > r1 + margin, n its ``offset`` row);
    a contact pruned is also open (``closed`` False). Returns the number pruned."""
    pruned = 0
    for p in range(contact.shape[0]):
        a, b, i = sphere1[p], sphere2[p], contact[p]
        d0 = centres[a, 0] - centres[b, 0]
        d1 = centres[a, 1] - centres[b, 1]
        d2 = centres[a, 2] - centres[b, 2]
        reach = radii[a] + radii[b] + margin[p]
        if kind[b] == PLANE:
            on = not offset[b, 0] * d0 + offset[b, 1] * d1 + offset[b, 2] * d2 > reach
        else:
            on = not d0 * d0 + d1 * d1 + d2 * d2 > reach * reach
        live[i] = on
        if not on:
            closed[i] = False
            pruned += 1
    return pruned


@njit(cache=True)
def prune(q, ints, floats, centres, radii, live, closed, live_idx):
    """:func:`sphere_states` then :func:`prune_pairs` in one call, their arrays views of
    ``ints`` (n_s, n_p, width, then kind, at, n_reach, contact, sphere1, sphere2) and
    ``floats`` (offset (n_s, 3), radius0, reach (n_s, width), margin, a (3, 3) work block) — the layout of
    :class:`mbs.run.bounding_spheres.SphereTable`; then the indices of the live contacts into
    ``live_idx`` (:func:`mbs.run._stage_kernels.live_contacts`). Returns (the number pruned,
    the number live)."""
    n, n_p, width = ints[0], ints[1], ints[2]
    o = INTS_AT
    kind, at, n_reach = ints[o:o + n], ints[o + n:o + 2 * n], ints[o + 2 * n:o + 3 * n]
    o += 3 * n
    contact, sphere1, sphere2 = ints[o:o + n_p], ints[o + n_p:o + 2 * n_p], ints[o + 2 * n_p:o + 3 * n_p]
    offset = floats[:3 * n].reshape(n, 3)
    radius0 = floats[3 * n:4 * n]
    reach = floats[4 * n:(4 + width) * n].reshape(n, width)
    margin = floats[(4 + width) * n:(4 + width) * n + n_p]
    A = floats[(4 + width) * n + n_p:(4 + width) * n + n_p + 9].reshape(3, 3)
    sphere_states(q, kind, at, offset, radius0, reach, n_reach, centres, radii, A)
    pruned = prune_pairs(contact, sphere1, sphere2, margin, kind, offset, centres, radii, live, closed)
    return pruned, live_contacts(live, live_idx)

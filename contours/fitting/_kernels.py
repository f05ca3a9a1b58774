"""numba kernel of the trim test (:mod:`.trim`): is a point (η, ξ) of a fitted surface
on the material, i.e. outside every hole polygon in parameter space? Crossing number
(Jordan's theorem): a horizontal ray from the point crosses a polygon's edges an odd
number of times iff the point is inside. Numpy reference:
:func:`.trim.in_material_reference`."""

from __future__ import annotations

from numba import njit


@njit(cache=True)
def in_material(eta, xi, vertices, starts):
    """True when (η, ξ) lies inside no hole polygon. ``vertices`` (M, 2): the polygons'
    corners one after the other, polygon h = vertices[starts[h]:starts[h + 1]] (closed
    implicitly, last corner to first); ``starts`` (H + 1,) int64."""
    for h in range(starts.size - 1):
        a, b = starts[h], starts[h + 1]
        inside = False
        j = b - 1
        for i in range(a, b):
            ei, xi_i = vertices[i, 0], vertices[i, 1]
            ej, xi_j = vertices[j, 0], vertices[j, 1]
            if (xi_i > xi) != (xi_j > xi):
                cross = ei + (xi - xi_i) * (ej - ei) / (xi_j - xi_i)
                if eta < cross:
                    inside = not inside
            j = i
        if inside:
            return False
    return True

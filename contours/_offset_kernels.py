"""numba kernels of the offset contours (band, cylinder) of :mod:`contours.derived`.

A derived point sits at r = R + A (ū(η) + d̄), d̄ = α n̄ + β t̄2, in the body-frame frame
of the neutral curve (t̄ = ū_η/|ū_η|, n̄ the reference normal n̄0 made perpendicular to t̄,
t̄2 = n̄ × t̄). With a = ū_η and G = ∂d̄/∂a = α ∂n̄/∂a + β ∂t̄2/∂a (3, 3):

    r_η = A (ū_η + G ū_ηη),   r_ξ = A (α_ξ n̄ + β_ξ t̄2),   r_ηη = A ū_ηη,
    r_ηξ = A G_ξ ū_ηη (G_ξ = α_ξ ∂n̄/∂a + β_ξ ∂t̄2/∂a),   r_ξξ = A (α_ξξ n̄ + β_ξξ t̄2),
    J_T = [1, −A (ū + d̄)~ T, A Φ_P],   Φ_P = Φ + G Φ_η,
    ṙ = v + A (ω̄ × (ū + d̄) + Φ_P q̇_f).

G is never formed: :func:`offset_derivative` applies it to a vector through
∂t̄/∂a x = (x − t̄ (t̄ᵀ x))/|a|, c = n̄0 − (n̄0ᵀ t̄) t̄, ∂c/∂a = −(t̄ n̄0ᵀ + (n̄0ᵀ t̄) 1) ∂t̄/∂a,
∂n̄/∂a = (1 − n̄ n̄ᵀ) ∂c/∂a / |c|, ∂t̄2/∂a = −t̄~ ∂n̄/∂a + n̄~ ∂t̄/∂a (the matrices of
:func:`contours.derived.offset_frame`, the numpy reference). The offsets (α, β) and their
ξ-derivatives come in as plain floats, so one kernel serves every offset law; the
compiled contact search, which moves ξ itself, gets them from :func:`offsets` (the laws
``BAND`` and ``CYLINDER``). The neutral curve is read span-locally from its
``kernel_data`` (:mod:`.neutral._kernels`).
"""

import numba
import numpy as np

from .neutral._kernels import contract_curve, frame_2s, inertial_rows, local_rows_1s, locate, point_velocity

BAND, CYLINDER = 0, 1   # offset laws of :func:`offsets`


@numba.njit(cache=True)
def offsets(law, size, xi):
    """(α, β, α_ξ, β_ξ, α_ξξ, β_ξξ) [m] at ξ: ``BAND`` (α, β) = (size, ξ) (size the offset
    [m], ξ [m]); ``CYLINDER`` (α, β) = size (cos ξ, sin ξ) (size the radius [m], ξ [rad])."""
    if law == BAND:
        return size, xi, 0.0, 1.0, 0.0, 0.0
    c, s = np.cos(xi), np.sin(xi)
    return size * c, size * s, -size * s, size * c, -size * c, -size * s


@numba.njit(cache=True)
def offset_derivative(t, n, n0, la, lc, al, be, x0, x1, x2):
    """(α ∂n̄/∂a + β ∂t̄2/∂a) x (3 floats) for the frame t̄, n̄ (3,) of the tangent a
    (|a| = ``la``, |c| = ``lc``) and the body-frame reference normal n0 (3,)."""
    tx = t[0] * x0 + t[1] * x1 + t[2] * x2
    y0, y1, y2 = (x0 - t[0] * tx) / la, (x1 - t[1] * tx) / la, (x2 - t[2] * tx) / la  # ∂t̄/∂a x
    n0y = n0[0] * y0 + n0[1] * y1 + n0[2] * y2
    n0t = n0[0] * t[0] + n0[1] * t[1] + n0[2] * t[2]
    c0, c1, c2 = -(t[0] * n0y + n0t * y0), -(t[1] * n0y + n0t * y1), -(t[2] * n0y + n0t * y2)  # ∂c/∂a x
    nc = n[0] * c0 + n[1] * c1 + n[2] * c2
    z0, z1, z2 = (c0 - n[0] * nc) / lc, (c1 - n[1] * nc) / lc, (c2 - n[2] * nc) / lc  # ∂n̄/∂a x
    # ∂t̄2/∂a x = n̄ × y − t̄ × z
    w0 = n[1] * y2 - n[2] * y1 - (t[1] * z2 - t[2] * z1)
    w1 = n[2] * y0 - n[0] * y2 - (t[2] * z0 - t[0] * z2)
    w2 = n[0] * y1 - n[1] * y0 - (t[0] * z1 - t[1] * z0)
    return al * z0 + be * w0, al * z1 + be * w1, al * z2 + be * w2


@numba.njit(cache=True)
def neutral_frame(a, n0, frame):
    """The body-frame frame of the neutral curve from its tangent a = ū_η (3,) and
    reference normal n0 (3,): rows t̄, n̄, t̄2 of ``frame`` (3, 3); returns (|a|, |c|)."""
    la = np.sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2])
    for c in range(3):
        frame[0, c] = a[c] / la
    n0t = n0[0] * frame[0, 0] + n0[1] * frame[0, 1] + n0[2] * frame[0, 2]
    for c in range(3):
        frame[1, c] = n0[c] - n0t * frame[0, c]
    lc = np.sqrt(frame[1, 0] ** 2 + frame[1, 1] ** 2 + frame[1, 2] ** 2)
    for c in range(3):
        frame[1, c] /= lc
    t, n = frame[0], frame[1]
    frame[2, 0] = n[1] * t[2] - n[2] * t[1]
    frame[2, 1] = n[2] * t[0] - n[0] * t[2]
    frame[2, 2] = n[0] * t[1] - n[1] * t[0]
    return la, lc


@numba.njit(cache=True)
def offset_fields(eta, knots, ints, floats, ctrl0, phi, state, span, n0, al, be, al1, be1, al2, be2, B, local,
                  rows, frame, D):
    """Locate η on the neutral curve (wrapped or clipped), fill ``local`` (6, 3) with its
    ū rows (ū, ū_η, ū_ηη in rows 0, 1, 3), ``frame`` (3, 3) with t̄, n̄, t̄2 (rows), ``rows``
    (6, 3) [m] with the body-frame rows of the offset point (ū + d̄, ū_η + G ū_ηη, α_ξ n̄ +
    β_ξ t̄2, ū_ηη, G_ξ ū_ηη, α_ξξ n̄ + β_ξξ t̄2; module docstring) and ``D`` (6, 3) [m] with
    r, r_η, r_ξ, r_ηη, r_ηξ, r_ξξ. (α, β) [m] = (al, be) and their first and second
    ξ-derivatives at the point; n0 the body-frame reference normal. Returns (span, |a|, |c|)."""
    p = ints[0]
    s = locate(knots, p, ints[1], ints[2] != 0, floats[0], floats[1], eta, B)
    local_rows_1s(B, s, p, ctrl0, phi, state, span, np.int64(6), local)
    la, lc = neutral_frame(local[1], n0, frame)
    t, n, t2 = frame[0], frame[1], frame[2]
    uee = local[3]
    g0, g1, g2 = offset_derivative(t, n, n0, la, lc, al, be, uee[0], uee[1], uee[2])
    h0, h1, h2 = offset_derivative(t, n, n0, la, lc, al1, be1, uee[0], uee[1], uee[2])
    rows[1, 0], rows[1, 1], rows[1, 2] = local[1, 0] + g0, local[1, 1] + g1, local[1, 2] + g2
    rows[4, 0], rows[4, 1], rows[4, 2] = h0, h1, h2
    for c in range(3):
        rows[0, c] = local[0, c] + al * n[c] + be * t2[c]
        rows[2, c] = al1 * n[c] + be1 * t2[c]
        rows[3, c] = uee[c]
        rows[5, c] = al2 * n[c] + be2 * t2[c]
    inertial_rows(state, rows, np.int64(6), D)
    return s, la, lc


@numba.njit(cache=True)
def evaluate_offset(eta, knots, ints, floats, ctrl0, phi, state, span, n0, al, be, al1, be1, al2, be2, modal,
                    velocity, B, local, rows, frame, phi_rows, phi_point, D, F, v):
    """An offset-contour point from the neutral curve's state, span-local:
    :func:`offset_fields` into D (6, 3), the surface frame of :func:`frame_2s` (n =
    r_η × r_ξ/|…|) into F; with ``modal`` Φ_P = Φ + G Φ_η (3 n_f,) (row-major (3, n_f))
    into ``phi_point`` (phi_rows (3, 3 n_f) work: Φ, Φ_η) and with ``velocity`` (needs
    ``modal``) ṙ = v + A (ω̄ × (ū + d̄) + Φ_P q̇_f) [m/s] into v (3,)."""
    s, la, lc = offset_fields(eta, knots, ints, floats, ctrl0, phi, state, span, n0, al, be, al1, be1, al2, be2,
                              B, local, rows, frame, D)
    frame_2s(D, 1.0, F)
    if modal:
        n_f = phi.shape[1] // 3
        contract_curve(B, s, ints[0], phi, np.int64(3), phi_rows)
        t, n = frame[0], frame[1]
        for k in range(n_f):
            g0, g1, g2 = offset_derivative(t, n, n0, la, lc, al, be, phi_rows[1, k], phi_rows[1, n_f + k],
                                            phi_rows[1, 2 * n_f + k])
            phi_point[k] = phi_rows[0, k] + g0
            phi_point[n_f + k] = phi_rows[0, n_f + k] + g1
            phi_point[2 * n_f + k] = phi_rows[0, 2 * n_f + k] + g2
    if velocity:
        point_velocity(state, rows[0], phi_point, v)

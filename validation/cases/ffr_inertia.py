"""Consistent vs lumped mass: rigid-body inertia, clamped frequencies and the flip period.

An FFR body's inertia (thesis eq. 2.53, 2.54, 2.65) comes either from the lumped node
masses (row sums for tet4, HRZ for tet10, :func:`preprocess.fe.lumped_masses`) or from
the consistent mass matrix M_s (:func:`preprocess.fe.consistent_mass_matrix`; shape
integrals eq. C1 of :mod:`mbs.bodies.shape_integrals`). Three measurements, each with both
masses (config ``mass``: "lumped" / "consistent"; ``body``: the mesh):

1. **Rigid-body inertia** — mass m, centre of mass c and inertia tensor J about c, taken
   from the shape integrals (m, I1, I_kl, :class:`mbs.bodies.shape_integrals.ShapeIntegrals`)
   of a 0.1 x 0.2 x 0.5 m steel box (tet4 and tet10, a structured 1 x 2 x 5 mesh and an
   unstructured one) and of the stepped beam (:func:`preprocess.stepped_beam`), against
   the exact values of the solid blocks: a block [0, a] x [0, b] x [0, c] of density ρ
   has m = ρabc, c = (a, b, c)/2 and J = m/12 diag(b² + c², a² + c², a² + b²)
   (parallel-axis theorem for the beam's two blocks). Row error: ‖J − J_exact‖_F /
   ‖J_exact‖_F; columns: relative mass error, |c − c_exact| / the body's largest extent,
   relative errors of the principal moments. Consistent mass integrates ρ x xᵀ exactly
   on straight-sided tets (degree 2 ≤ 2·order), so its error is rounding.
2. **Frequencies** — the clamped stepped beam (the setup of ``ffr_frequencies``, tet10)
   at coarse mesh sizes, its first five frequencies from both masses against a finer
   mesh solved with consistent mass (its frequencies are Rayleigh–Ritz upper bounds, so
   the reference's own error is one-sided), modes paired by rank. Row error:
   max_i |f_i / f_ref,i − 1|;
   CPU: :func:`preprocess.build_body` (assembly and modes).
3. **Flip period** — a free steel box 0.1 x 0.2 x 0.3 m (tet10 and tet4, structured
   1 x 2 x 3: coarse, so the lumped inertia is off by several %) spun at 1 rad/s about
   its intermediate principal axis with a 1 % tilt towards the major one (the
   ``tennis_racket`` stability case), as a free FFR body with six elastic modes
   (Ω/ω1 ~ 1e-4: elastically rigid). The period of the flips is measured from the sign
   changes of ω2 and compared with Jacobi's T = 4K(m)/ω_p
   (:func:`validation.stability.body_cases.flip_period`) of the exact block inertia.
   Row error: max |T_measured / T_exact − 1|; column ``own_inertia_error``: the same
   against T of the body's own (FE) inertia, i.e. the integrator's share.
"""

from __future__ import annotations

import numpy as np

from mbs import FlexibleBodyFFR, System
from mbs.bodies.shape_integrals import ShapeIntegrals
from preprocess import Material, box, build_body, fe, stepped_beam
from validation import CaseResult, make_row, timed
from validation.cases.complex_beam import MATERIAL_MM
from validation.stability.body_cases import flip_period, periods_from_flips, zero_crossings

NAME = "ffr_inertia"
DESCRIPTION = ("consistent vs lumped mass: rigid-body inertia of boxes and the stepped beam vs exact, "
               "clamped stepped-beam frequencies vs a fine mesh, flip period vs Jacobi's solution")

MASSES = ("lumped", "consistent")
DENSITY = 7850.0                                   # kg/m³ (steel)
STEEL = Material(DENSITY, 210e9, 0.3)              # kg/m³, Pa, -
BOX = (0.1, 0.2, 0.5)                              # m
BOX_MESHES = (("tet4 structured 1x2x5", 1, None, (1, 2, 5)), ("tet4 unstructured h=0.1", 1, 0.1, None),
              ("tet10 structured 1x2x5", 2, None, (1, 2, 5)), ("tet10 unstructured h=0.1", 2, 0.1, None))
BEAM_MESH_MM = 5.0                                 # stepped beam, inertia part
N_FREQ = 5
RACKET = (0.1, 0.2, 0.3)                           # m, as the tennis_racket stability case
RACKET_MESHES = (("tet10 structured 1x2x3", 2), ("tet4 structured 1x2x3", 1))
SPIN, TILT = 1.0, 0.01                             # rad/s about the intermediate axis; ω3(0)/ω2(0)
FLIPS = 2
OMEGA_DT = 0.02                                    # Ω Δt


# --- exact inertia of solid blocks ----------------------------------------------------------
def block_moments(lo, hi, density):
    """(m [kg], first moment ∫ρx dV (3,) [kg m], second moment ∫ρ x xᵀ dV (3, 3) [kg m²])
    of the solid block lo <= x <= hi (m)."""
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    size, centre = hi - lo, 0.5 * (lo + hi)
    m = density * np.prod(size)
    return m, m * centre, m * np.outer(centre, centre) + np.diag(m * size ** 2 / 12.0)


def inertia_about_com(m, first, second):
    """(m, c = first/m (3,) [m], J = tr(U) 1 − U about c (3, 3) [kg m²], U = second − m c cᵀ)."""
    c = first / m
    U = second - m * np.outer(c, c)
    return m, c, np.trace(U) * np.eye(3) - U


def exact_blocks(blocks, density):
    """(m, c, J about c) of a union of disjoint blocks [(lo, hi), ...] [m]."""
    parts = [block_moments(lo, hi, density) for lo, hi in blocks]
    return inertia_about_com(*(sum(p[i] for p in parts) for i in range(3)))


def stepped_beam_blocks(l=95.0, h1=10.0, h2=34.2, w1=20.0, w2=9.74, base=10.0):
    """The two blocks [m] of :func:`preprocess.stepped_beam` (its docstring, mm there):
    a base block base x h2 x w1 at the origin and the slender part l x h1 x w2, flush at
    y = 0 and centred in z, from x = base on."""
    zc = (w1 - w2) / 2.0
    mm = 1e-3
    return [(np.zeros(3), np.array([base, h2, w1]) * mm),
            (np.array([base, 0.0, zc]) * mm, np.array([base + l, h1, zc + w2]) * mm)]


# --- inertia of an FE body ------------------------------------------------------------------
def fe_inertia(mesh_si, density, mass):
    """(m, c, J about c) of the mesh (SI) from the FFR shape integrals m, I1, I_kl with the
    lumped masses or the consistent M_s (no modes needed: Φ with zero columns)."""
    none = np.zeros((3 * mesh_si.n_nodes, 0))
    if mass == "lumped":
        si = ShapeIntegrals.from_nodes(mesh_si.points, none, fe.lumped_masses(mesh_si, density))
    else:
        si = ShapeIntegrals.from_mass_matrix(mesh_si.points, none, fe.consistent_mass_matrix(mesh_si, density))
    return inertia_about_com(si.mass, si.I1, si.I_kl)


def inertia_row(body, mesh_si, exact, mass):
    """One row of part 1 (module docstring)."""
    (m, c, J), cpu = timed(fe_inertia, mesh_si, DENSITY, mass)
    m0, c0, J0 = exact
    extent = float(np.ptp(mesh_si.points, axis=0).max())
    principal = np.linalg.eigvalsh(J) / np.linalg.eigvalsh(J0) - 1
    return make_row(NAME, {"mass": mass, "body": body}, cpu, np.linalg.norm(J - J0) / np.linalg.norm(J0),
                    "relative", "exact block inertia", nodes=mesh_si.n_nodes, mass_error=m / m0 - 1,
                    com_error=float(np.linalg.norm(c - c0)) / extent,
                    **{f"err_J{i + 1}": float(e) for i, e in enumerate(principal)})


def inertia_rows(quick):
    rows = []
    exact = exact_blocks([(np.zeros(3), np.array(BOX))], DENSITY)
    for label, order, size, divisions in BOX_MESHES:
        mesh = box(*BOX, size, order=order, divisions=divisions)
        rows += [inertia_row(f"box {label}", mesh, exact, mass) for mass in MASSES]
    beam = stepped_beam(BEAM_MESH_MM, order=2).scaled(1e-3)
    exact = exact_blocks(stepped_beam_blocks(), DENSITY)
    rows += [inertia_row(f"stepped beam tet10 h={BEAM_MESH_MM:g} mm", beam, exact, mass) for mass in MASSES]
    return rows


# --- clamped frequencies --------------------------------------------------------------------
def beam_frequencies(mesh_size_mm, mass):
    """(f [Hz] of the first N_FREQ clamped modes, CPU s of build_body, nodes) of the stepped beam."""
    mesh = stepped_beam(mesh_size_mm, order=2)
    data, cpu = timed(build_body, mesh, MATERIAL_MM, N_FREQ, clamp="x0", units="si-mm", mass=mass)
    return data.frequencies()[1], cpu, mesh.n_nodes


def frequency_rows(quick):
    sizes, ref_size = ((10.0,), 3.0) if quick else ((10.0, 5.0, 3.0), 2.0)
    f_ref, _, ref_nodes = beam_frequencies(ref_size, "consistent")
    rows = []
    for size in sizes:
        for mass in MASSES:
            f, cpu, nodes = beam_frequencies(size, mass)
            errors = f / f_ref - 1
            rows.append(make_row(NAME, {"mass": mass, "body": f"stepped beam tet10 h={size:g} mm"}, cpu,
                                 float(np.abs(errors).max()), "relative",
                                 f"consistent tet10 h={ref_size:g} mm ({ref_nodes} nodes)", nodes=nodes,
                                 **{f"err_f{i + 1}": float(e) for i, e in enumerate(errors)}))
    note = ("Reference frequencies [Hz] (consistent mass, tet10, "
            f"h = {ref_size:g} mm, {ref_nodes} nodes): " + ", ".join(f"{v:.1f}" for v in f_ref))
    return rows, note


# --- flip period ----------------------------------------------------------------------------
def racket_body(order, mass):
    """The free racket box (structured 1 x 2 x 3, ``order``) with six free-free modes."""
    mesh = box(*RACKET, None, order=order, divisions=(1, 2, 3))
    return build_body(mesh, STEEL, 6, clamp=None, mass=mass)


def measured_flip_periods(data):
    """(periods [s] from the flips of ω2, T [s] of the body's own inertia, CPU s of the
    simulation) of the body spun about its
    own intermediate principal axis, ω = (0, Ω, TILT Ω) in its principal axes, centre of
    mass at rest; generalized-α ρ∞ = 1 at Ω Δt = OMEGA_DT over FLIPS + ½ half-periods."""
    system = System()
    body = system.add(FlexibleBodyFFR(data, 6, name="racket"))
    si = body.integrals
    m, c, J = inertia_about_com(si.mass, si.I1, si.I_kl)
    moments, axes = np.linalg.eigh(J)
    w0 = np.array([0.0, SPIN, TILT * SPIN])
    T_own = flip_period(moments, w0)[0]
    omega = axes @ w0
    body.set_initial(v=-np.cross(omega, c), omega=omega)
    dt = OMEGA_DT / SPIN
    n = int(np.ceil((FLIPS + 0.75) * T_own / 2 / dt))
    system.simulate(2 * dt, dt, plan=False, rho_inf=1.0)          # load compiled kernels untimed
    res, cpu = timed(system.simulate, n * dt, dt, t_out=np.arange(n + 1) * dt, plan=False, rho_inf=1.0)
    w2 = [axes[:, 1] @ (body.orientation(q[body.q_slice]).T @ body.angular_velocity(q[body.q_slice], u[body.u_slice]))
          for q, u in zip(res.q, res.u)]
    return np.array(periods_from_flips(zero_crossings(res.t, np.array(w2)))), T_own, cpu


def flip_rows(quick):
    exact = exact_blocks([(np.zeros(3), np.array(RACKET))], DENSITY)
    T_exact = flip_period(np.sort(np.linalg.eigvalsh(exact[2])), (0.0, SPIN, TILT * SPIN))[0]
    rows = []
    for label, order in RACKET_MESHES[:1] if quick else RACKET_MESHES:
        for mass in MASSES:
            data = racket_body(order, mass)
            periods, T_own, cpu = measured_flip_periods(data)
            rows.append(make_row(NAME, {"mass": mass, "body": f"racket box {label}"}, cpu,
                                 float(np.abs(periods / T_exact - 1).max()), "relative",
                                 "Jacobi T of the exact inertia", T_measured_s=float(periods.mean()),
                                 T_exact_s=T_exact, own_inertia_error=float(np.abs(periods / T_own - 1).max())))
    return rows


def run(quick: bool) -> CaseResult:
    result = CaseResult(plot_groups=("mass", "error_kind", "reference"))
    result.rows += inertia_rows(quick)
    rows, note = frequency_rows(quick)
    result.rows += rows
    result.rows += flip_rows(quick)
    result.notes.append(note)
    return result

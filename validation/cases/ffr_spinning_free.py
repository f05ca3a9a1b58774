"""Free-free strip spinning about its axis of largest inertia: stiffened flatwise frequency.

Setup: a free-free steel strip (E = 210 GPa, ν = 0.3, ρ = 7800 kg/m³), L = 1 m along x,
b = 60 mm along y, h = 10 mm along z, structured tet10 mesh, its points shifted so the
centre of mass (lumped masses) is the origin. Its second moments are largest about z
(Σ m (x² + y²)), so a spin Ω about z is the stable one. Flatwise bending (displacement
along z, the spin axis) is to first order free of the in-plane effects of the spin:
the Coriolis force 2 Ω × u̇ and the centrifugal softening −Ω × (Ω × u) both vanish for
u ∥ Ω. What remains is the tension of the centrifugal load, so the flatwise frequency
is that of the prestressed structure,

    (K + Ω² K_σ,zz) φ = ω² M φ                                               (F1)

with K_σ,zz = K_s ⊗ I3 the FE geometric stiffness of the stress of the inertia-relief
static displacement under the Omega_zz unit load case (eq. G1–G3 of
:mod:`preprocess.geometric`), M the lumped mass matrix the body's modes are normalized
with. Reference: the eigenvalue of (F1) for the whole free mesh (3N DOFs), by
shift-invert Lanczos near ω1² + Ω² (Φᵀ K_σ,zz Φ)_11 (a shift only), the flatwise mode
picked by its MAC with the unstressed first flatwise mode. (F1) also turns the rigid
rotations about x and y into modes of ω² ≈ Ω² (∫ σ_xx dV / ∫ ρ x² dV = Ω² for the tilt
about y); they are antisymmetric and have no MAC with the flatwise mode. At Ω = 0 the
reference reduces to the body's own first eigenvalue (checked: ``fe_zero_spin_check``).
Beam theory: ω² ≈ ω1² + K Ω² with the Southwell-type coefficient K = ∫ N̂ φ'² dx / ∫ φ² dx,
N̂ = (L²/4 − s²)/2, of the free-free Euler–Bernoulli mode (≈ 3.05; the test compares).

FFR: ``FlexibleBodyFFR(data, n, frame="free")`` with and without ``geometric_stiffening``
(eq. S1 of :mod:`mbs.bodies.geometric_stiffening`: on a free frame the centrifugal cases
K_geo = Ω_z² Φᵀ K_σ,zz Φ), initial spin ω = (0, 0, Ω), q_f = 0 and q̇_f exciting the first
(flatwise) mode alone with a flatwise tip velocity ``TIP_VELOCITY`` (amplitude about
0.1–0.3 mm, 1–3 % of h). Generalized-α with ρ∞ = 1 (the trapezoidal rule, no numerical
damping), Δt = T/``STEPS_PER_PERIOD`` with T = 2π/ω_FE, ``PERIODS`` periods, output every
step, the full FFR equations (plan off). The frequency of q_f,1(t) in the body frame is
measured by :func:`validation.cases.ffr_frequencies.measure_frequency` (Prony fit).

The trapezoidal rule's own period error is ω_d h = 2 arctan(ω h/2) (ffr_frequencies):
at 100 steps per period ω_d/ω − 1 = −3.3e-4, reported per row (``integrator_error``)
along with the error net of it (``model_error`` = ω_FFR/ω_d(ω_FE) − 1). Target: the
stiffened rows within 0.5 %; the unstiffened rows keep ω1 and miss the stiffening.

Rows: config {spin_ratio Ω/ω1, geometric_stiffening, modes, mesh}; error |ω_FFR/ω_FE − 1|.
Quick: mesh 20×2×1, 10 modes. Full: also 6 and 16 modes and a 40×4×2 mesh.
"""

from __future__ import annotations

import math

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as sla

from mbs import FlexibleBodyFFR, System
from preprocess import Material, box, build_body, fe
from preprocess.geometric import LOAD_CASES, inertia_loads, stress_geometric_matrices
from preprocess.residual import StaticFlexibility
from validation import CaseResult, make_row, timed
from validation.cases.ffr_frequencies import measure_frequency

NAME = "ffr_spinning_free"
DESCRIPTION = ("free-free steel strip spinning about its axis of largest inertia: stiffened flatwise "
               "frequency of the FFR body vs the FE eigenvalue of K + K_σ(Ω)")

LENGTH, WIDTH, THICKNESS = 1.0, 0.06, 0.01            # [m] along x, y, z
STEEL = Material(7800.0, 2.1e11, 0.3)                 # SI
SPIN_RATIOS = (0.5, 1.0, 1.5)                         # Ω / ω1
TIP_VELOCITY = 0.1                                    # initial flatwise tip velocity [m/s]
STEPS_PER_PERIOD = 100
PERIODS = 20
QUICK_VARIANTS = (((20, 2, 1), 10),)                  # (mesh divisions, modes)
FULL_VARIANTS = (((20, 2, 1), 6), ((20, 2, 1), 10), ((20, 2, 1), 16), ((40, 4, 2), 10))
SPIN_CASE = LOAD_CASES.index("Omega_zz")
MAC_MIN = 0.9                                         # the flatwise mode's MAC must exceed it
N_EIG = 6                                             # eigenpairs around the shift


def strip_mesh(divisions):
    """The strip's structured tet10 mesh (SI), its lumped-mass centre of mass at the origin."""
    mesh = box(LENGTH, WIDTH, THICKNESS, None, order=2, divisions=divisions)
    masses = fe.lumped_masses(mesh, STEEL.density)
    mesh.points -= masses @ mesh.points / masses.sum()
    return mesh


def strip(divisions, n_modes):
    """(mesh, BodyData) of the free-free strip with ``n_modes`` modes and the geometric stiffness."""
    mesh = strip_mesh(divisions)
    return mesh, build_body(mesh, STEEL, n_modes, geometric_stiffness=True)


def spin_axis(data):
    """Index of the axis of the largest second moment Σ m (|x|² − x_k²) [kg m²] about the origin."""
    r2 = data.masses @ data.u0 ** 2
    return int(np.argmax(r2.sum() - r2))


def flatwise_fraction(data, mode):
    """The share of mode ``mode``'s kinetic energy (lumped M) in z displacements [-]."""
    phi = data.phi[:, mode].reshape(-1, 3)
    e = data.masses @ phi ** 2
    return float(e[2] / e.sum())


class PrestressedStrip:
    """The FE eigenproblem (F1) of the whole free mesh: K, lumped M and K_σ,zz (3N, 3N)."""

    def __init__(self, mesh, data):
        self.data = data
        self.K = data.stiffness.tocsc()
        self.m3 = np.repeat(data.masses, 3)
        load = inertia_loads(data.u0, data.masses)[:, [SPIN_CASE]]
        u_static = StaticFlexibility(data.stiffness, data.masses, data.u0).solve(load)
        K_s = stress_geometric_matrices(mesh, STEEL.young, STEEL.poisson, u_static)[0]
        self.K_sigma = sp.kron(K_s, sp.identity(3), format="csc")
        self.phi1 = data.phi[:, 0]

    def flatwise(self, spin):
        """(ω [rad/s], MAC [-]) of the flatwise mode of (F1) at the spin ``spin`` Ω [rad/s]."""
        guess = self.data.eigenvalues[0] + spin ** 2 * self.data.geometric_stiffness[SPIN_CASE, 0, 0]
        v0 = np.random.default_rng(0).standard_normal(self.K.shape[0])
        vals, vecs = sla.eigsh((self.K + spin ** 2 * self.K_sigma).tocsc(), k=N_EIG,
                               M=sp.diags(self.m3).tocsc(), sigma=guess, v0=v0)
        mphi = self.m3 * self.phi1
        mac = (vecs.T @ mphi) ** 2 / (np.einsum("ij,i,ij->j", vecs, self.m3, vecs) * (self.phi1 @ mphi))
        j = int(np.argmax(mac))
        if mac[j] < MAC_MIN:
            raise RuntimeError(f"no flatwise mode near ω² = {guess:.4g} at Ω = {spin:.4g} rad/s "
                               f"(best MAC {mac[j]:.3f})")
        return math.sqrt(vals[j]), float(mac[j])


def simulate(data, n_modes, spin, stiffening, dt, t_end):
    """Run the free strip spinning at ``spin`` [rad/s] about z, first mode excited with
    ``TIP_VELOCITY``, step ``dt`` to ``t_end`` [s]; returns (q_f,1 (n,), ω̄_z at the end
    [rad/s], CPU s). Without stiffening above 0.2 ω1 the run warns (SpinMonitor), as it
    should: those rows show what the warning is about."""
    system = System()
    body = system.add(FlexibleBodyFFR(data, n_modes, frame="free", geometric_stiffening=stiffening))
    qdot = np.zeros(n_modes)
    qdot[0] = TIP_VELOCITY / np.abs(data.phi[2::3, 0]).max()
    body.set_initial(omega=(0.0, 0.0, spin), qdot_f=qdot)
    res, cpu = timed(system.simulate, t_end, dt, integrator="generalized-alpha", rho_inf=1.0, plan=False)
    q, u = res.q[:, body.q_slice], res.u[:, body.u_slice]
    spin_end = body.frame_state(q[-1], u[-1])[3][2]
    return body.modal_coordinates(q)[:, 0], spin_end, cpu


def run(quick: bool) -> CaseResult:
    result = CaseResult(plot_groups=("geometric_stiffening", "mesh", "modes"))
    checks = []
    for divisions, n_modes in QUICK_VARIANTS if quick else FULL_VARIANTS:
        mesh, data = strip(divisions, n_modes)
        axis, flat = spin_axis(data), flatwise_fraction(data, 0)
        if axis != 2 or flat < MAC_MIN:
            raise RuntimeError(f"strip: largest inertia about axis {axis}, first mode {flat:.3f} flatwise; "
                               "the case needs z and a flatwise first mode")
        omega1 = math.sqrt(data.eigenvalues[0])
        fe_model = PrestressedStrip(mesh, data)
        fe_zero = abs(fe_model.flatwise(0.0)[0] / omega1 - 1)
        label = "x".join(map(str, divisions))
        checks.append((label, n_modes, data.n_nodes, omega1, fe_zero))
        for stiffening in (True, False):     # load the compiled kernels untimed
            simulate(data, n_modes, 0.0, stiffening, 1e-5, 2e-5)
        for ratio in SPIN_RATIOS:
            spin = ratio * omega1
            omega_fe, mac = fe_model.flatwise(spin)
            dt = 2 * np.pi / omega_fe / STEPS_PER_PERIOD
            t_end = PERIODS * STEPS_PER_PERIOD * dt
            integrator_error = 2 * math.atan(omega_fe * dt / 2) / (omega_fe * dt) - 1
            for stiffening in (True, False):
                q1, spin_end, cpu = simulate(data, n_modes, spin, stiffening, dt, t_end)
                omega_ffr, _, residual = measure_frequency(q1, dt)
                config = {"spin_ratio": ratio, "geometric_stiffening": stiffening, "modes": n_modes,
                          "mesh": label}
                result.rows.append(make_row(
                    NAME, config, cpu, abs(omega_ffr / omega_fe - 1), "relative",
                    "FE eigenvalue of K + K_σ(Ω) of the same mesh", spin_rad_s=spin,
                    omega_unstressed=omega1, omega_fe=omega_fe, omega_ffr=omega_ffr,
                    integrator_error=integrator_error,
                    model_error=omega_ffr / (omega_fe * (1 + integrator_error)) - 1,
                    fit_residual=residual, mac=mac, spin_drift=float(spin_end / spin - 1),
                    fe_zero_spin_check=fe_zero, dt_s=dt))
    result.notes += [_setup_note(checks), _frequency_table(result.rows)]
    return result


def _setup_note(checks):
    lines = [f"Free-free steel strip {LENGTH} × {WIDTH} × {THICKNESS} m (x, y, z), tet10, spinning "
             f"about z (largest inertia); first mode flatwise (z), excited alone with a flatwise tip "
             f"velocity of {TIP_VELOCITY} m/s. Generalized-α ρ∞ = 1 (trapezoidal), "
             f"{STEPS_PER_PERIOD} steps per period of the FE frequency, {PERIODS} periods; frequency of "
             f"q_f,1(t) by Prony fit. Reference: flatwise eigenvalue of (K + Ω² K_σ,zz, M) of the "
             "whole free mesh. At Ω = 0 it equals the body's first eigenfrequency ω1 to:", ""]
    lines += [f"- mesh {label}, {n_modes} modes, {nodes} nodes: ω1 = {omega1:.3f} rad/s, "
              f"|ω_FE(0)/ω1 − 1| = {err:.1e}" for label, n_modes, nodes, omega1, err in checks]
    return "\n".join(lines)


def _frequency_table(rows):
    lines = ["| mesh | modes | Ω/ω1 | Ω [rad/s] | ω_FE [rad/s] | ω_FFR stiffened | error | ω_FFR linear | error |",
             "|---|---|---|---|---|---|---|---|---|"]
    pairs = {}
    for row in rows:
        c = row["config"]
        pairs.setdefault((c["mesh"], c["modes"], c["spin_ratio"]), {})[c["geometric_stiffening"]] = row
    for (mesh, modes, ratio), pair in pairs.items():
        s, n = pair[True], pair[False]
        lines.append(f"| {mesh} | {modes} | {ratio} | {s['spin_rad_s']:.2f} | {s['omega_fe']:.3f} | "
                     f"{s['omega_ffr']:.3f} | {s['error']:.2e} | {n['omega_ffr']:.3f} | {n['error']:.2e} |")
    return "\n".join(lines)

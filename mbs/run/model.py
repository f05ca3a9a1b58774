"""Model and Data of a run (DESIGN, "Model / data split"; as Pinocchio's Model/Data and
MuJoCo's mjModel/mjData).

:func:`compile_model` turns a System, after planning, into a frozen :class:`Model`:
what is fixed for the run — the bodies integrated and those the plan solves apart
(left out: identity mass block, zero force, zero increment), their equations
(:class:`~mbs.run.equations.Equations`) and body stage, whether the iteration matrix
M̂ = M + θΔt D + θ²Δt² K is constant, the contours to update and the contacts owning
each, and the contact table (kinds, dimensions, closing tolerances, margins, the
bounding spheres of prunable pairs, the rows of each contact's impulses, the compiled
detection of the pairs that have one, :mod:`mbs.run.fused_detection`). The System is never
mutated.

:class:`Data` holds everything the stages change as preallocated arrays: t, q, u, the
midpoint state (t_m, q_m), the increment du, h, M, the tangents K, D, M̂ and its
Cholesky factors (one per step size of a constant M̂), u_free, the contact flags (live,
closed), penalty normal forces, the bounding spheres of a planned run, the closed set,
the buffers of W (nu, m), M̂⁻¹W, the Delassus matrix G (m, m), ξ_free, γ⁻, the
gap-closing term, Λ and γ⁺ for the largest possible closed set, the warm starts (Λ of
the last step per contact and for the joints), counters and the record of the last
step, and the contours' and contacts' run state (``contact_f``, ``contact_i``: their state
vectors, contact points, kinematics, the searches' warm starts and counters), of which
the contour, contact-kinematics and search objects hold views (:mod:`mbs.run.contact_state`:
made when the Data is, the fused detections' tables made again on them).

A checkpoint (:mod:`mbs.results.checkpoint`) holds every array and scalar of Data
(:meth:`Data.collect`, :meth:`Data.restore`) but its caches, rebuilt on demand from the
Model: the contact sets' law encodings and the views of the contact problem's buffers.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from contact.kinematics import PointOnCurveConstraint, buffer_layout
from contact.solver import WORK_ROWS

from mbs.bodies.body import place_bodies
from mbs.results.codec import StateMismatch, put, take
from mbs.run import _stage_kernels as SK
from mbs.run.body_stage import BodyStage
from mbs.run.bounding_spheres import SphereTable
from mbs.run.contact_state import ContactState
from mbs.run.equations import Equations
from mbs.run.fused_detection import fused_detection
from mbs.run.residual_contact import ResidualContacts

N_FACTORS = 8          # Cholesky factors of a constant M̂ kept for different step sizes (+1)
CACHES = ("contact_sets", "problem_views", "lapack_views", "solver_views", "compliance_views", "factor_dt",
          "factor_last", "comp_entries", "comp_table")
# ^ Data rebuilt on demand (the last step's factor of a constant M̂ is looked up again in
#   ``factors``; the compliant contacts' entries are made each step): not in a checkpoint
CARRIED = ("t", "q", "u", "closed", "lam_prev", "warm", "lam_joints", "warm_joints", "comp_force", "comp_delta",
           "comp_delta_dot", "stats", "contact_f", "contact_i")
# ^ the Data a Moreau step reads of the steps before it (the rest it writes before reading):
#   the state, the closed flags (a planned run keeps closed contacts live), the warm
#   starts, the compliant contacts' springs, the counters and the contours' and contacts'
#   run state (mbs.run.contact_state); what a step taken back puts back
#   (mbs.integrators.moreau.AdaptiveMoreauTimeStepping)


@dataclass(frozen=True)
class Model:
    """The frozen description of a run (module docstring).

    Attributes
    ----------
    system : System
    plan : Plan or None
        The scene plan it was compiled under (:mod:`mbs.run.plan`).
    equations : Equations
        M, h, tangents, constraints over the active bodies (allocating; implicit and
        explicit integrators).
    body_stage : BodyStage
        The same terms written into Data's arrays (Moreau's body stage).
    nq, nu, n_c : int
    idle : tuple of bodies
        Bodies the plan solves apart.
    active_u : (n_act,) int array or None
        Rows of u of the active bodies (None: all).
    theta : float
        θ of the Moreau–Jean θ-method.
    solver : ProxSolver or None
    constant_iteration : bool
        M, K, D constant (M̂ factored once per step size).
    prune : bool
        A planned run: contacts are searched only while their bounding spheres meet.
    contacts : tuple
        The System's contacts (set-valued, single-valued and curve constraints).
    set_valued, unilateral : tuple of bool
    dims : tuple of int
        Rows of Λ of each set-valued contact (0 for single-valued).
    lam_at : tuple of int
        First entry of each contact's warm start in ``Data.lam_prev``.
    penalty : tuple of int
        Single-valued unilateral contacts with law derivatives (their stiffness is
        checked against the step).
    spheres : SphereTable or None
        The bounding spheres of the prunable contacts of a planned run
        (:class:`mbs.run.bounding_spheres.SphereTable`), None without a plan.
    fused : tuple
        Per contact its fused detection (:func:`mbs.run.fused_detection.fused_detection`:
        contour update and detection in one compiled call) or None (the Python path).
    contours : tuple of (contour, owners, q_slice, u_slice)
        Every contour of a contact once, the indices of the contacts owning it and its
        body's slices (None on the ground).
    owner_at, owners : int arrays
        The owners of contour k without a fused detection, as flat arrays:
        owners[owner_at[k]:owner_at[k + 1]] (:func:`mbs.run._stage_kernels.contours_in_use`;
        a contour whose owners all have one is updated by them, in the detection stage).
    single_valued : tuple of int
        The contacts with a single-valued law (their forces join h).
    m_max : int
        Rows of the largest contact problem: n_c + Σ dims.
    blocks : (k, 2) int array or None
        Rows [a, b) of each active body: M̂ is block diagonal with these blocks when no
        force element has tangents (factored and solved block by block,
        :mod:`mbs.run.linalg_kernels`); None: M̂ is factored whole (LAPACK).
    idle_rows : int array
        Rows of u of the bodies the plan solves apart (zero in every solve).
    residual : ResidualContacts or None
        The contacts on contours with residual flexibility and their compliances
        (:mod:`mbs.run.residual_contact`); None when there is none.
    contact_state : ContactState
        Where the contours' and contacts' run state lies in Data's ``contact_f`` and
        ``contact_i`` (:mod:`mbs.run.contact_state`).
    contact_table : (n, TABLE_COLUMNS) int array
        Per contact where its kinematics lies in ``contact_f``, its rows of Λ and what
        else the kernels over the contacts need of it (the columns of
        :mod:`mbs.run._stage_kernels`).
    layout : tuple of (body, q_slice, u_slice)
        Each body's rows of q and u (:meth:`mbs.system.System.layout`), given to the
        bodies again when a Data is made (a body may belong to several Systems).
    """

    system: object
    plan: object
    equations: Equations
    body_stage: BodyStage
    nq: int
    nu: int
    n_c: int
    idle: tuple
    active_u: np.ndarray | None
    theta: float
    solver: object
    constant_iteration: bool
    prune: bool
    contacts: tuple
    set_valued: tuple
    unilateral: tuple
    dims: tuple
    lam_at: tuple
    penalty: tuple
    spheres: SphereTable | None
    fused: tuple
    contours: tuple
    owner_at: np.ndarray
    owners: np.ndarray
    single_valued: tuple
    m_max: int
    blocks: np.ndarray | None
    idle_rows: np.ndarray
    residual: ResidualContacts | None
    contact_state: ContactState
    contact_table: np.ndarray
    layout: tuple

    @property
    def n_act(self) -> int:
        """Velocities of the active bodies."""
        return self.nu if self.active_u is None else self.active_u.size


def compile_model(system, plan=None, theta=0.5, solver=None) -> Model:
    """The :class:`Model` of ``system`` for a run under ``plan`` (:class:`mbs.run.plan.Plan`,
    or None: every body integrated, every contour updated each step); ``theta`` and
    ``solver`` the Moreau options (module docstring). The residual flexibility of
    corrected contours is cached in ``system.cache_dir`` (None: computed each time)."""
    layout = system.layout()
    idle = tuple(bp.body for bp in plan.modal_bodies) if plan is not None else ()
    equations = Equations(system, idle, plan.forces if plan is not None else ())
    active_u = None
    if idle:
        rows = np.arange(system.nu)
        active_u = np.setdiff1d(rows, np.concatenate([rows[b.u_slice] for b in idle]))
    contacts = tuple(system.contacts)
    set_valued = tuple(bool(c.set_valued) for c in contacts)
    dims = tuple(int(c.dim) if sv else 0 for c, sv in zip(contacts, set_valued))
    lam_at = tuple(int(a) for a in np.concatenate(([0], np.cumsum(dims)))[:-1]) if contacts else ()
    penalty = tuple(i for i, c in enumerate(contacts)
                    if not c.set_valued and c.unilateral and hasattr(c.law, "derivatives"))
    fused = tuple(fused_detection(c) for c in contacts)
    seen, table = {}, []
    for i, c in enumerate(contacts):
        for contour in c.contours():
            if id(contour) not in seen:
                seen[id(contour)] = len(table)
                body = contour.body
                table.append([contour, [], None if body is None else body.q_slice,
                              None if body is None else body.u_slice])
            owners = table[seen[id(contour)]][1]
            if i not in owners and fused[i] is None:
                owners.append(i)
    contours = tuple((k, tuple(owners), qs, us) for k, owners, qs, us in table)
    owner_at = np.cumsum([0] + [len(owners) for _, owners, _, _ in table]).astype(np.int64)
    owners = np.array([i for _, owners, _, _ in table for i in owners], dtype=np.int64)
    body_stage = BodyStage.of_equations(equations)
    blocks = None
    if body_stage.block_tangents:
        blocks = np.array([[b.u_slice.start, b.u_slice.stop] for b in body_stage.active], dtype=np.int64)
        blocks = blocks.reshape(-1, 2)
    idle_rows = np.array([i for b in equations.idle for i in range(b.u_slice.start, b.u_slice.stop)],
                         dtype=np.int64)
    residual = ResidualContacts(contacts, set_valued, getattr(system, "cache_dir", None))
    contact_state = ContactState([k for k, *_ in contours] + list(contacts))
    return Model(system=system, plan=plan, equations=equations, body_stage=body_stage,
                 nq=system.nq, nu=system.nu, n_c=system.n_c, idle=equations.idle, active_u=active_u,
                 theta=float(theta), solver=solver, constant_iteration=equations.constant_iteration_matrix,
                 prune=plan is not None, contacts=contacts, set_valued=set_valued,
                 unilateral=tuple(bool(c.unilateral) for c in contacts), dims=dims, lam_at=lam_at,
                 penalty=penalty, spheres=SphereTable(contacts) if plan is not None else None, fused=fused,
                 contours=contours, owner_at=owner_at, owners=owners,
                 single_valued=tuple(i for i, sv in enumerate(set_valued) if not sv), m_max=system.n_c + sum(dims),
                 blocks=blocks, idle_rows=idle_rows, residual=residual if residual else None,
                 contact_state=contact_state,
                 contact_table=_contact_table(contacts, dims, lam_at, residual if residual else None, contact_state),
                 layout=layout)


def _contact_table(contacts, dims, lam_at, residual, contact_state) -> np.ndarray:
    """Model.contact_table: a row per contact (the columns of :mod:`mbs.run._stage_kernels`)."""
    at = {id(obj): offset for obj, name, pool, offset, shape in contact_state.slots if name == "buffer" and pool == 0}
    table = np.zeros((len(contacts), SK.TABLE_COLUMNS), dtype=np.int64)
    for i, (c, dim, lam) in enumerate(zip(contacts, dims, lam_at)):
        k = c.kinematics
        nu1, nu2 = k.contour1.nu, k.contour2.nu
        s1, s2 = k.u_slices()
        w_N1, w_N2, w_T1, w_T2 = buffer_layout(nu1, nu2)[3:7]
        table[i] = (at[id(k)], w_N1, w_N2, w_T1, w_T2, nu1, nu2, -1 if s1 is None else s1.start,
                    -1 if s2 is None else s2.start, dim, lam, c.unilateral, isinstance(k, PointOnCurveConstraint),
                    residual is not None and residual.compliant[i])
    return table


LAST_STEP = (0, 0.0, 0, 0.0, 0.0, 0, 0.0, 0.0)     # Data.last of a step not yet taken


class CarriedCopy:
    """What a step reads of the steps before it (:data:`CARRIED` of ``data``), copied by
    :meth:`save` into buffers made once and put back by :meth:`restore`: a step taken back
    leaves no trace (:class:`mbs.integrators.moreau.AdaptiveMoreauTimeStepping`)."""

    def __init__(self, data):
        self.data = data
        self._arrays = [(name, getattr(data, name).copy()) for name in CARRIED
                        if isinstance(getattr(data, name), np.ndarray)]
        self._others = [name for name in CARRIED if not isinstance(getattr(data, name), np.ndarray)]
        self._values = []

    def save(self) -> None:
        data = self.data
        for name, kept in self._arrays:
            np.copyto(kept, getattr(data, name))
        self._values = [dict(v) if isinstance(v, dict) else v for v in (getattr(data, n) for n in self._others)]

    def restore(self) -> None:
        data = self.data
        for name, kept in self._arrays:
            np.copyto(getattr(data, name), kept)
        for name, value in zip(self._others, self._values):
            setattr(data, name, dict(value) if isinstance(value, dict) else value)


class Data:
    """The state and workspaces of a run of ``model`` (module docstring). Arrays of the
    current contact problem are views of the ``*_buf`` buffers sized for ``m_max``
    rows (:meth:`problem`)."""

    def __init__(self, model: Model):
        nq, nu, m, n = model.nq, model.nu, model.m_max, len(model.contacts)
        n_act = model.n_act
        place_bodies(model.layout)          # the bodies' rows in this Model's System
        self.t = self.t_m = 0.0
        self.q, self.u = np.zeros(nq), np.zeros(nu)
        self.q_m = np.zeros(nq)
        self.du = np.zeros(nu)
        self.h = np.zeros(nu)
        self.M = np.zeros((nu, nu))
        for b in model.idle:
            np.fill_diagonal(self.M[b.u_slice, b.u_slice], 1.0)
        self.K, self.D = np.zeros((nu, nu)), np.zeros((nu, nu))
        self.factors = []                   # [(step size, Cholesky factor of M̂)]: (nu, nu) blockwise with
                                            # model.blocks, else (n_act, n_act) Fortran order
        self.factor = None                  # the factor of this step
        self.factor_dt = np.nan             # a constant M̂: the last step size [s] and its entry of
        self.factor_last = None             # ``factors``
        self.u_free = np.zeros(nu)
        self.rhs = np.zeros(nu)             # M̂⁻¹ b on all rows
        self.rhs_act = np.zeros(n_act)      # ... on the active rows
        self.w_N = np.zeros(nu)             # a penalty contact's W_N
        # contacts
        self.live = np.ones(n, dtype=bool)
        self.live_idx = np.arange(n, dtype=np.intp)            # the live contacts, n_live of them (all
        self.n_live = n                                        # unless a planned run prunes)
        self.contour_idx = np.zeros(len(model.contours), dtype=np.intp)   # contours of live contacts
        self.closed = np.zeros(n, dtype=bool)
        self.located = np.zeros(n, dtype=bool)      # located this step (g_N <= closing_tol)
        self.force_N = np.zeros(n)
        self.closed_idx = np.zeros(n, dtype=np.intp)
        self.n_closed = 0
        self.m = 0
        self.problem_views = {}             # (nu, m) -> views of the buffers below (Data.problem)
        self.W_buf = np.zeros(nu * m)
        self.MW_buf = np.zeros(nu * m)
        self.MW_lapack_buf = np.zeros(nu * m)     # M̂⁻¹W in Fortran order for LAPACK (Data.lapack_matrix)
        self.lapack_views = {}
        self.G_buf = np.zeros(m * m)
        self.lam_buf, self.gamma_plus_buf = np.zeros(m), np.zeros(m)
        self.xi_free_buf, self.gamma_pre_buf = np.zeros(m), np.zeros(m)
        self.closing_buf, self.offset_buf = np.zeros(m), np.zeros(m)
        self.work_u = np.zeros(nu)          # M̂⁻¹ W Λ, then (1 − 2θ)Δt u_k
        self.u_prev = np.zeros(nu)          # u_k while u_{k+1} is formed
        self.solver_work_buf = np.zeros(WORK_ROWS * m)     # the solver's scratch (WORK_ROWS, m),
        self.newton_matrix_buf = np.zeros(m * m)    # the Newton phases with friction: J (m, m),
        self.newton_pivots_buf = np.zeros(2 * m, dtype=np.int64)    # pivots (2, m),
        self.newton_local = np.zeros((5, 3))        # an entry's z, P, ∂P/∂z
        self.solver_views = {}              # m -> views of the four above (Data.solver_scratch)
        # compliant contacts (mbs.run.residual_contact, contact.compliance): spring state per
        # contact row (end force [N], deflection [m], its rate [m/s]), the last step's
        # Λ₀ = (1 − θ)Δt F_k per contact row [N s] (its impulse is Λ₀ + lam_prev), and this step's
        # compliant rows, their normal rows, compliance (r, r) [m/N], state and Λ₀ [N s]
        n_rows = sum(model.dims)
        self.comp_force, self.comp_delta, self.comp_delta_dot = np.zeros((3, n_rows))
        self.comp_impulse0 = np.zeros(n_rows)
        self.comp_rows, self.comp_normal = np.zeros(m, dtype=np.int64), np.zeros(m, dtype=np.int64)
        self.comp_fresh = np.zeros(m, dtype=np.bool_)      # the row's contact was open last step
        self.comp_C_buf = np.zeros(m * m)                  # C (r, r): Data.compliance
        self.compliance_views = {}                         # r -> C
        self.comp_F, self.comp_d, self.comp_dd, self.comp_lam0 = np.zeros((4, m))
        self.comp_c, self.comp_work = np.zeros((3, 3)), np.zeros((2, 3, 3))     # c(a, b), its frame work
        self.comp_r = 0
        self.comp_entries = [None] * (2 * n)
        k = model.residual.max_weights if model.residual is not None else 0
        self.comp_table = (np.zeros((2 * n, 6), dtype=np.int64), np.zeros((2 * n, k, 3, 3)),
                           np.zeros((2 * n, k), dtype=np.int64), np.zeros(2 * n), np.zeros((2 * n, 3)),
                           np.zeros((2 * n, 3, 2)), np.zeros((2 * n, 3, 3)))   # per side: the kernel's tables
        n_s = 0 if model.spheres is None else len(model.spheres.spheres)
        self.sphere_centres = np.zeros((n_s, 3))    # bounding spheres of the prunable contacts [m]
        self.sphere_radii = np.zeros(n_s)
        self.spheres_started = False                # the constant centres written
        self.lam_prev = np.zeros(sum(model.dims))
        self.warm = np.zeros(n, dtype=bool)         # the contact has Λ of the last step
        self.lam_joints = np.zeros(model.n_c)
        self.warm_joints = False                    # the last step solved a contact problem (then
                                                    # the joints have Λ of it); False: no warm[i]
        self.contact_sets = {}              # ContactSet per closed set (indices)
        self.solution = None                # (iterations, residual, converged) of the last solve
        self.h_last = 0.0
        self.stats = {"closed_contacts": 0, "solver_iterations": 0, "max_penetration": 0.0, "pruned_contacts": 0}
        self.steps = self.iterations = 0    # the integrator's accepted steps and Newton iterations
        self.integrator = {}                # its own state between steps by name (generalized-α's u̇,
                                            # ā, λ; the adaptive step's next size), set at its start
        self.last = list(LAST_STEP)         # this accepted step: most closed contacts, penetration,
                                            # solver iterations, residual; impulse work; with a
                                            # trace (mbs.run.step_work) most contacts transmitting a
                                            # force, load work, damping loss
        # the contours' and contacts' run state (mbs.run.contact_state): their arrays become
        # views of these two vectors, the fused detections' tables follow
        self.contact_f, self.contact_i = model.contact_state.pools()
        model.contact_state.bind(self.contact_f, self.contact_i, model.fused)

    def problem(self, nu, m):
        """Views (W (nu, m), M̂⁻¹W (nu, m), G (m, m), Λ, γ⁺, ξ_free, γ⁻, closing, offset
        (m,)) of the contact problem with m rows, made once per (nu, m) and kept in
        ``problem_views``; all C-contiguous, so that every m gives the kernels one array
        layout and each kernel is compiled once."""
        views = self.problem_views.get((nu, m))
        if views is None:
            views = self.problem_views[(nu, m)] = self._problem(nu, m)
        return views

    def _problem(self, nu, m):
        return (self.W_buf[:nu * m].reshape(nu, m), self.MW_buf[:nu * m].reshape(nu, m),
                self.G_buf[:m * m].reshape(m, m), self.lam_buf[:m], self.gamma_plus_buf[:m],
                self.xi_free_buf[:m], self.gamma_pre_buf[:m], self.closing_buf[:m], self.offset_buf[:m])

    def lapack_matrix(self, nu, m):
        """A (nu, m) Fortran-order scratch for LAPACK's in-place solve of M̂⁻¹W
        (:func:`mbs.run.stages.solve_matrix`), made once per (nu, m)."""
        X = self.lapack_views.get((nu, m))
        if X is None:
            X = self.lapack_views[(nu, m)] = self.MW_lapack_buf[:nu * m].reshape(m, nu).T
        return X

    def solver_scratch(self, m):
        """(work (WORK_ROWS, m), (J (m, m), pivots (2, m), local (5, 3))): the contact
        solver's scratch of an m-row problem (:meth:`contact.solver.ProxSolver.solve_into`),
        C-contiguous views of the buffers made once per m and kept in ``solver_views``. Every
        m gives the kernels arrays of one layout, so each kernel is compiled once (a column
        slice of a (WORK_ROWS, m_max) array would be C-contiguous only at m = m_max)."""
        views = self.solver_views.get(m)
        if views is None:
            views = self.solver_views[m] = (self.solver_work_buf[:WORK_ROWS * m].reshape(WORK_ROWS, m),
                                            (self.newton_matrix_buf[:m * m].reshape(m, m),
                                             self.newton_pivots_buf[:2 * m].reshape(2, m), self.newton_local))
        return views

    def compliance(self, r):
        """The compliance C (r, r) [m/N] of this step's r compliant rows
        (:mod:`mbs.run.residual_contact`): a C-contiguous view made once per r."""
        C = self.compliance_views.get(r)
        if C is None:
            C = self.compliance_views[r] = self.comp_C_buf[:r * r].reshape(r, r)
        return C

    def collect(self, prefix, arrays: dict, kinds: dict) -> None:
        """Every array and scalar of the run under ``prefix/…`` (:func:`mbs.results.codec.put`):
        the factors of a constant M̂ as ``factors/<j>/step`` [s] and ``factors/<j>/factor``
        (in their memory order), ``stats``, ``integrator`` and ``last`` entry by entry; the caches
        (:data:`CACHES`) left out."""
        for name, value in vars(self).items():
            if name in CACHES:
                continue
            if name == "factors":
                for j, (step, factor) in enumerate(value):
                    put(f"{prefix}/factors/{j}/step", step, arrays, kinds)
                    put(f"{prefix}/factors/{j}/factor", factor, arrays, kinds)
            elif name in ("stats", "integrator", "last"):
                for key, entry in (enumerate(value) if name == "last" else value.items()):
                    put(f"{prefix}/{name}/{key}", entry, arrays, kinds)
            else:
                put(f"{prefix}/{name}", value, arrays, kinds)

    def restore(self, prefix, arrays, kinds) -> None:
        """The state :meth:`collect` saved, into this Data of the same Model
        (:class:`~mbs.results.codec.StateMismatch` if it does not fit)."""
        for name, value in vars(self).items():
            if name in CACHES:
                continue
            if name == "factors":
                self.factors = []
                while f"{prefix}/factors/{len(self.factors)}/step" in kinds:
                    at = f"{prefix}/factors/{len(self.factors)}"
                    step, factor = take(f"{at}/step", 0.0, arrays, kinds), take(f"{at}/factor", None, arrays, kinds)
                    if factor.ndim != 2 or factor.shape[0] != factor.shape[1] or factor.shape[0] not in (
                            self.rhs.size, self.rhs_act.size):
                        raise StateMismatch(f"{at}/factor has shape {factor.shape}, not this run's")
                    self.factors.append((step, factor))
            elif name in ("stats", "integrator"):
                at = f"{prefix}/{name}/"            # the saved keys in their order
                setattr(self, name, {k[len(at):]: take(k, value.get(k[len(at):]), arrays, kinds)
                                     for k in kinds if k.startswith(at)})
            elif name == "last":
                value[:] = [take(f"{prefix}/last/{i}", v, arrays, kinds) for i, v in enumerate(value)]
            else:
                setattr(self, name, take(f"{prefix}/{name}", value, arrays, kinds))
        self.factor_dt, self.factor_last = np.nan, None

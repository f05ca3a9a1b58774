"""Exudyn (JKU Linz, ``pip install exudyn``) as a peer FFR code; optional.

:func:`free_flight` simulates one free-floating flexible body with Exudyn's
``ObjectFFRFreducedOrder`` (floating frame of reference with a modal basis, the
CMS formulation of Zwölfer and Gerstmayr) under face loads fixed in the body
frame, integrated by Exudyn's implicit generalized-α solver with a fixed step.
It is the peer of our FFR body in the report's free-flight scene (report Sec.
5.7.3, "complex forcing": the 1 x 1 x 5 m beam with step loads on its end faces,
probe node A at the mesh origin).

Identical model data
--------------------
Exudyn gets OUR matrices and OUR modes, not its own: an ``exudyn.FEM.FEMinterface``
is filled directly with the node positions ``u0``, the lumped mass matrix
``diag(m_0, m_0, m_0, m_1, ...)``, the stiffness ``K`` and ``modeBasis = phi``
(eigenvalues ``diag(phiᵀ K phi)``); nothing is recomputed by Exudyn. Its
``ObjectFFRFreducedOrderInterface`` then forms the reduced matrices ``phiᵀ M phi``,
``phiᵀ K phi`` and the constant inertia integrals from these.

Exudyn's conventions, as found
------------------------------
Exudyn 1.13.6, ``exudyn/FEM.py``, checked at run time against Exudyn's own mesh-node
output:

* Reference frame: the rigid-body node of the object holds the frame origin ``R``
  and Euler parameters (orientation ``A``); the mesh node positions are
  ``r_i = R + A (x_ref,i + Psi_i q)`` with ``x_ref`` = the ``Position`` nodes of the
  FEMinterface, i.e. exactly our ``u0``. The frame origin is therefore the point
  (0, 0, 0) of the ``u0`` coordinates, NOT the centre of mass (Exudyn stores the
  centre of mass ``chiU`` separately and uses it only in the inertia terms); with
  ``positionRef = 0`` and the identity reference rotation the body frame starts on
  the inertial frame, as ours does. So Exudyn's and our frames agree without any
  conversion: ``position = R + A (u0_p + Phi_p q_f)`` and ``elastic = Phi_p q_f``.
  Because the free-free modes are mass-orthogonal to the rigid-body modes, both
  codes' elastic coordinates mean the same thing (mean-axis-like frame).
* Loads: each face load is a ``LoadForceVector`` on a ``MarkerSuperElementPosition``
  (mesh nodes with the caller's weights), so node i receives ``w_i F``. Exudyn
  refuses ``bodyFixed=True`` on this marker type; the body-fixed force is therefore
  a load user function returning ``A(q) d magnitude(t)`` with ``A`` read from the
  rigid-body node in the CURRENT (Newton iterate) configuration. The load's
  dependence on ``A`` is left out of the Newton Jacobian (Exudyn's default,
  ``computeLoadsJacobian = 0``); Newton converges regardless, the step result is
  the converged one.
* Time of load evaluation: generalized-α in Exudyn solves the equations of motion
  at the END of each step, so ``magnitude`` is called with ``t = t_{n+1}`` (and at
  t = 0 for the initial accelerations), usually twice or more per step (once per
  Newton residual). The times passed are exactly ``k * h`` (bitwise, as numpy
  computes them; checked for h = 1e-3, 3e-4, 7e-4, 1e-4). A step load that
  switches at t_s thus acts from the step ending at the first grid time at which
  ``magnitude`` returns the new value: with ``t < t_s`` in the caller's function
  and t_s on the grid, the step ending at t_s already carries the new value.
* Numerical damping: ``rho_inf`` is Exudyn's ``generalizedAlpha.spectralRadius``
  (Arnold–Brüls generalized-α, index-3 constraint for the Euler-parameter norm).

Outputs and timing
------------------
Sensors stored in memory (no files) record the frame origin ``R``, the rotation
matrix ``A`` and the modal coordinates ``q_f`` at EVERY step (t = 0, h, 2h, ...);
the probe outputs are computed at those steps and interpolated linearly to
``output_times`` (exact when the output times are multiples of h). ``cpu_s`` is
the process CPU time of ``exudyn.SolveDynamic`` only (which includes Exudyn's
solver initialization and the initial accelerations, a negligible part);
``setup_s`` the process CPU time of building the system (FEMinterface, reduced
matrices, markers, loads, sensors, ``Assemble``). Every call to a load user
function is a call into Python, part of ``cpu_s``.

No console output, no files: the solution file, the solver-information file and
the sensor files are disabled; Exudyn runs with ``verboseMode = 0``.
"""

from __future__ import annotations

import time

import numpy as np
import scipy.sparse as sp

__all__ = ["available", "free_flight"]


def available() -> bool:
    """True when ``import exudyn`` (and its FEM module) works on this machine."""
    try:
        import exudyn  # noqa: F401
        import exudyn.FEM  # noqa: F401
    except Exception:  # ImportError, or a broken binary module
        return False
    return True


def _check_inputs(u0, masses, stiffness, phi, face_loads, t_end, h, probe_node, output_times):
    u0 = np.ascontiguousarray(u0, dtype=float)
    if u0.ndim != 2 or u0.shape[1] != 3 or len(u0) == 0:
        raise ValueError(f"u0 must have shape (N, 3), not {u0.shape}")
    n = len(u0)
    masses = np.ascontiguousarray(masses, dtype=float)
    if masses.shape != (n,) or not np.all(masses > 0):
        raise ValueError(f"masses must be (N,) = ({n},) and positive")
    K = sp.csr_matrix(stiffness, dtype=float)
    if K.shape != (3 * n, 3 * n):
        raise ValueError(f"stiffness must be (3N, 3N) = {(3 * n, 3 * n)}, not {K.shape}")
    phi = np.ascontiguousarray(phi, dtype=float)
    if phi.ndim != 2 or phi.shape[0] != 3 * n or phi.shape[1] < 1:
        raise ValueError(f"phi must be (3N, n_f) with 3N = {3 * n}, not {phi.shape}")
    if not (t_end > 0 and h > 0):
        raise ValueError(f"need t_end > 0 and h > 0, got {t_end}, {h}")
    n_steps = int(round(t_end / h))
    if n_steps < 1 or abs(n_steps * h - t_end) > 1e-9 * t_end:
        raise ValueError(f"t_end = {t_end} s is not a whole number of steps h = {h} s")
    if not 0 <= int(probe_node) < n:
        raise ValueError(f"probe_node {probe_node} is not a node index in [0, {n})")
    output_times = np.atleast_1d(np.asarray(output_times, dtype=float))
    if output_times.ndim != 1 or len(output_times) == 0:
        raise ValueError("output_times must be a non-empty 1-D array")
    if np.any(np.diff(output_times) < 0) or output_times[0] < 0 or \
            output_times[-1] > t_end * (1 + 1e-12):
        raise ValueError("output_times must be sorted and lie within [0, t_end]")
    loads = []
    for k, (weights, direction, magnitude) in enumerate(face_loads):
        weights = np.asarray(weights, dtype=float)
        direction = np.asarray(direction, dtype=float)
        if weights.shape != (n,):
            raise ValueError(f"face load {k}: weights must have shape ({n},), not {weights.shape}")
        if abs(weights.sum() - 1.0) > 1e-9:
            raise ValueError(f"face load {k}: weights sum to {weights.sum()}, not 1")
        if direction.shape != (3,):
            raise ValueError(f"face load {k}: direction must have shape (3,)")
        if not callable(magnitude):
            raise ValueError(f"face load {k}: magnitude must be a callable t -> N")
        loads.append((weights, direction, magnitude))
    return u0, masses, K, phi, loads, n_steps, int(probe_node), output_times


def free_flight(u0, masses, stiffness, phi, face_loads, t_end, h, probe_node, output_times,
                rho_inf=0.9):
    """Simulate a free-floating flexible body with Exudyn's ObjectFFRFreducedOrder
    (generalized-α, fixed step) under body-fixed face loads; return the probe node's motion.

    The body starts at rest with its body frame on the inertial frame; no gravity, no
    damping other than the integrator's. Equations: Exudyn's CMS form of the FFR
    equations of motion (Zwölfer and Gerstmayr's nodal-based FFRF with modal
    reduction: frame translation, Euler parameters, modal coordinates; inertia terms
    from the lumped masses and ``u0``, stiffness ``phiᵀ K phi``). Conventions (frame
    origin, load timing) in the module docstring.

    Parameters
    ----------
    u0 : (N, 3) undeformed node positions [m] in the body frame. The body frame's origin
        is the point (0, 0, 0) of these coordinates, its axes the coordinate axes.
    masses : (N,) lumped node masses [kg].
    stiffness : scipy sparse (3N, 3N) stiffness [N/m], node-major DOFs x0, y0, z0, x1, ...
    phi : (3N, n_f) mass-normalized free-free elastic mode shapes [kg^-1/2] (rigid modes
        removed), used as Exudyn's mode basis unchanged.
    face_loads : list of ``(weights, direction_body, magnitude)``: ``weights`` (N,) node
        weights summing to 1, ``direction_body`` (3,) the force direction in the body
        frame (rotates with the frame; not normalized here, the force is
        ``direction_body * magnitude(t)``), ``magnitude(t)`` a callable giving N.
    t_end : end time [s]; must be a whole number of steps.
    h : fixed step size [s].
    probe_node : index of the node whose motion is returned.
    output_times : (n_out,) sorted times in [0, t_end] [s]; the per-step results are
        interpolated linearly to them (exact on multiples of h).
    rho_inf : spectral radius at infinity of generalized-α (Exudyn's spectralRadius).

    Returns
    -------
    dict with ``t`` (n_out,) [s]; ``position`` (n_out, 3) global probe-node position
    ``R + A (u0_p + Phi_p q_f)`` [m]; ``elastic`` (n_out, 3) elastic displacement of the
    probe node in the body frame ``Phi_p q_f`` [m]; ``cpu_s`` process CPU time of the
    time integration [s]; ``setup_s`` process CPU time of the model set-up [s];
    ``steps`` number of steps. Extra diagnostic keys: ``frame_origin`` (n_out, 3) R [m],
    ``rotation`` (n_out, 3, 3) A (interpolated entrywise, for diagnostics only),
    ``q_f`` (n_out, n_f), ``exudyn_position`` (n_out, 3) Exudyn's own mesh-node position.

    Raises ImportError when exudyn is not installed, ValueError on malformed input,
    RuntimeError when Exudyn's solver fails or its node output contradicts the frame
    convention above.
    """
    import exudyn as exu
    import exudyn.itemInterface as eii
    from exudyn.FEM import FEMinterface, ObjectFFRFreducedOrderInterface

    u0, masses, K, phi, loads, n_steps, probe, output_times = _check_inputs(
        u0, masses, stiffness, phi, face_loads, t_end, h, probe_node, output_times)
    n_f = phi.shape[1]

    c0 = time.process_time()
    fem = FEMinterface()
    fem.nodes = {"Position": u0}
    fem.massMatrix = sp.diags(np.repeat(masses, 3)).tocsr()
    fem.stiffnessMatrix = K
    fem.modeBasis = {"matrix": phi, "type": "NormalModes"}
    fem.eigenValues = np.einsum("ij,ij->j", phi, K @ phi)

    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    cms = ObjectFFRFreducedOrderInterface(fem)
    items = cms.AddObjectFFRFreducedOrder(mbs, positionRef=[0.0, 0.0, 0.0],
                                          initialVelocity=[0.0, 0.0, 0.0],
                                          rotationMatrixRef=np.eye(3),
                                          initialAngularVelocity=[0.0, 0.0, 0.0])
    body, n_rigid, n_modal = items["oFFRFreducedOrder"], items["nRigidBody"], items["nGenericODE2"]
    rotation_type = exu.OutputVariableType.RotationMatrix

    for weights, direction, magnitude in loads:
        nodes = np.flatnonzero(weights)
        marker = mbs.AddMarker(eii.MarkerSuperElementPosition(
            bodyNumber=body, meshNodeNumbers=[int(i) for i in nodes],
            weightingFactors=weights[nodes], visualization={"show": False,
                                                             "showMarkerNodes": False}))

        def body_fixed_force(mbs_, t, load_vector, d=direction, f=magnitude):
            A = np.asarray(mbs_.GetNodeOutput(n_rigid, rotation_type)).reshape(3, 3)
            return A @ (d * float(f(t)))

        mbs.AddLoad(eii.LoadForceVector(markerNumber=marker, loadVector=[0.0, 0.0, 0.0],
                                        loadVectorUserFunction=body_fixed_force))

    ovt = exu.OutputVariableType
    memory_only = dict(writeToFile=False, fileName="", storeInternal=True)
    s_R = mbs.AddSensor(eii.SensorNode(nodeNumber=n_rigid, outputVariableType=ovt.Position,
                                       **memory_only))
    s_A = mbs.AddSensor(eii.SensorNode(nodeNumber=n_rigid, outputVariableType=rotation_type,
                                       **memory_only))
    s_q = mbs.AddSensor(eii.SensorNode(nodeNumber=n_modal, outputVariableType=ovt.Coordinates,
                                       **memory_only))
    s_p = mbs.AddSensor(eii.SensorSuperElement(bodyNumber=body, meshNodeNumber=probe,
                                               outputVariableType=ovt.Position, **memory_only))
    mbs.Assemble()

    settings = exu.SimulationSettings()
    ti = settings.timeIntegration
    ti.startTime = 0.0
    ti.endTime = float(t_end)
    ti.numberOfSteps = n_steps
    ti.adaptiveStep = False
    ti.automaticStepSize = False
    ti.verboseMode = 0
    ti.verboseModeFile = 0
    ti.generalizedAlpha.spectralRadius = float(rho_inf)
    ti.generalizedAlpha.useNewmark = False
    ti.generalizedAlpha.useIndex2Constraints = False
    settings.solution.file.write = False
    settings.solution.file.writeInitialValues = True  # sensors record t = 0 only with this flag
    settings.solution.sensors.active = True
    settings.solution.sensors.writePeriod = 0.5 * h  # every step (at most one record per step)
    settings.solution.restart.write = False
    settings.show.computationTime = False
    settings.show.statistics = False
    settings.show.globalTimers = False
    setup_s = time.process_time() - c0

    c0 = time.process_time()
    ok = exu.SolveDynamic(mbs, settings, solverType=exu.DynamicSolverType.GeneralizedAlpha,
                          showHints=False, showCausingItems=False)
    cpu_s = time.process_time() - c0
    if not ok:
        raise RuntimeError("Exudyn's generalized-α solver did not finish (Newton failure)")

    R = np.asarray(mbs.GetSensorStoredData(s_R))
    t = R[:, 0]
    R = R[:, 1:4]
    A = np.asarray(mbs.GetSensorStoredData(s_A))[:, 1:10].reshape(-1, 3, 3)
    q = np.asarray(mbs.GetSensorStoredData(s_q))[:, 1:1 + n_f]
    p_exu = np.asarray(mbs.GetSensorStoredData(s_p))[:, 1:4]
    if len(t) != n_steps + 1 or abs(t[-1] - t_end) > 1e-9 * t_end:
        raise RuntimeError(f"Exudyn recorded {len(t)} sensor rows up to t = {t[-1]}, "
                           f"expected {n_steps + 1} up to {t_end}")

    elastic = q @ phi[3 * probe:3 * probe + 3].T                          # Phi_p q_f, (n_t, 3)
    position = R + np.einsum("tij,tj->ti", A, u0[probe] + elastic)       # R + A (u0_p + Phi_p q_f)
    scale = max(float(np.abs(u0).max()), 1.0)
    mismatch = float(np.abs(position - p_exu).max())
    if mismatch > 1e-9 * scale:
        raise RuntimeError(f"Exudyn's mesh-node position differs from R + A (u0 + Phi q) by "
                           f"{mismatch:.3e} m: its frame convention is not the one assumed")

    def at(values):
        flat = values.reshape(len(t), -1)
        out = np.column_stack([np.interp(output_times, t, column) for column in flat.T])
        return out.reshape((len(output_times),) + values.shape[1:])

    return dict(t=output_times.copy(), position=at(position), elastic=at(elastic),
                cpu_s=cpu_s, setup_s=setup_s, steps=n_steps,
                frame_origin=at(R), rotation=at(A), q_f=at(q), exudyn_position=at(p_exu))

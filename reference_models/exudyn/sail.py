"""Exudyn reference model of the heliogyro blade deployment (scene `sail-deploy`, seed 004).

Inertial frame, planar (the motion stays in the plane z = r: no force has a z component), one
blade with half the hub inertia (symmetric deployment; channels report both blades). Shared
scene definition and release law: reference_models/sail_common.py.

- Hub: NodeRigidBody2D + ObjectRigidBody2D (inertia J_hub/2), translation fixed by two
  CoordinateConstraints: one rotational DOF. Marker Q at (L_c, 0) on the hub.
- Nodes: NodePoint2D + MassPoint2D (reference position Q0, so the coordinates are
  displacements from it).
- Thread: SpringDamper (c, d, rest l0) between neighbours, switched on (`activeConnector`) when
  the inner node is released.
- Boundary segment node→Q: SpringDamper with a Python `springForceUserFunction`
  f = c (L − r ω (t − t_b)) + d (L' − r ω) (the growing rest length at the solver's own stage
  time, the damper on the true stretch rate); active only while the node is the boundary.
- Stored nodes, two ways (the same physics; the integrator family decides):
  * explicit integrators ("velocity_verlet", default, and "rk44"): the stored thread is part of
    the hub inertia (J_hub/2 + Σ_stored m_j L_c², as in the custom conservative variant); a
    stored node is a parked mass point with no active connector. At its release time the hub
    inertia drops by m_j L_c² (the `inertia` parameter is re-read at every SolveDynamic call) and
    the node appears at Q with the hub-point velocity plus r ω along the rotated X1 axis: angular
    momentum is continuous and Ω does not jump. Explicit solvers cannot hold nodes by joints
    (shared notes), and the hub's two ground CoordinateConstraints are eliminated by the explicit
    solver, which is exact here because the hub's COM is its reference point (hub position stays
    at 0.0; checked). Velocity Verlet is symplectic and conserves the angular momentum of these
    central spring forces to round-off (measured 2.9e-11 over the full deployment, k = 1e5;
    1.5e-11 over 30 s at k = 1e7); Exudyn 1.13 prints "VelocityVerlet: still under development",
    so it is checked against MuJoCo (hub_rate 2.2e-7, tip 2.4e-8 rad over 30 s at k = 1e7).
    `dt="auto"` takes 0.8 × (2 for Verlet, 2.785 for RK4) / (2 sqrt(c/m_min)).
  * implicit integrators ("generalized_alpha", "trapezoidal"): stored nodes are held at Q by
    RevoluteJoint2D constraints, switched off through `activeConnector` at the release time; the
    node then gets the release velocity as above (put `release_offset` = 1e-9 m beyond Q so the
    new boundary SpringDamper never has length exactly 0). Generalized-α does not conserve
    angular momentum: the drift is the integrator's, not Newton's (5 s, n = 20: 2.3e-7 at
    h = 7.1e-4 with Newton tolerance 1e-6 or full Newton at 1e-10; 1.7e-8 at h = 1e-4;
    full deployment 1.6e-5), so it misses the scene's 1e-8 and is kept as the constraint-based
    cross-check, not the default.
- Time stepping: SolveDynamic is called segment by segment between breakpoints (output times
  and release times), each continuing from the previous end state (copied to the Initial
  configuration), so releases and outputs land exactly on steps. Implicit only: after each
  release a window `fine_window` is integrated with `fine_dt` and the looser
  `fine_newton_rel_tol` (the new boundary segment is nearly zero-length: its transverse
  stiffness T/ℓ is huge and Newton with the coarse step fails there); a segment whose Newton
  iteration fails is restarted from its saved start state with 4x, 16x, 64x smaller steps before
  the run is reported diverged. (Verified: a pre-step user function is called with the END time
  of the coming step while the coordinates are still at its start; this leaf does not use one.)
- An explicit step above the stability limit blows up; the run stops `diverged` at the first
  non-finite state or Exudyn error, and the reason names the stable-step estimate.
"""
from __future__ import annotations

import time as _time

import exudyn as exu
import numpy as np
from exudyn.itemInterface import (CoordinateConstraint, MarkerBodyPosition,
                                  MarkerNodeCoordinate, MarkerNodePosition, MassPoint2D,
                                  NodePointGround, NodePoint2D, NodeRigidBody2D,
                                  ObjectRigidBody2D, RevoluteJoint2D, SpringDamper)

from ..sail_common import (channels, formula18, merge_settings, payout, scene,
                           stable_dt_explicit, t_full)

DEFAULT_SETTINGS = {"integrator": "velocity_verlet", "dt": "auto", "rho_inf": 0.8,
                    "newton_rel_tol": 1e-6, "newton_abs_tol": 1e-8, "modified_newton": True,
                    "verbose": 0, "fine_dt": 1e-5, "fine_window": 0.05, "release_offset": 1e-9,
                    "fine_newton_rel_tol": 1e-6}
INTEGRATORS = ("velocity_verlet", "rk44", "generalized_alpha", "trapezoidal")
# explicit: Exudyn solver and stability interval on the imaginary axis
_EXPLICIT = {"velocity_verlet": (exu.DynamicSolverType.VelocityVerlet, 2.0),
             "rk44": (exu.DynamicSolverType.RK44, 2.785)}
_IMPLICIT = {"generalized_alpha": exu.DynamicSolverType.GeneralizedAlpha,
             "trapezoidal": exu.DynamicSolverType.TrapezoidalIndex2}
AUTO_DT = {"generalized_alpha": 0.05 / 70, "trapezoidal": 0.05 / 70}   # explicit: stability


def simulate(params, t_out, settings=None):
    s, t_out = merge_settings(settings, DEFAULT_SETTINGS, INTEGRATORS, t_out)
    p, n, l0, m, t_rel = scene(params)
    Lc, r, c, d = p["L_c"], p["r"], p["stiffness"], p["damping"]
    rw = r * p["omega_spool"]
    Om0 = p["Omega0"]
    explicit = s["integrator"] in _EXPLICIT
    h_stable = stable_dt_explicit(p, _EXPLICIT[s["integrator"]][1]) if explicit else None
    if s["dt"] in (None, "auto"):
        h = h_stable if explicit else AUTO_DT[s["integrator"]]
    else:
        h = float(s["dt"])

    def hub_inertia(b):
        """Half the hub plus, for the explicit model, the thread still stored (nodes > b)."""
        return 0.5 * p["J_hub"] + (float(m[b + 1:].sum()) * Lc**2 if explicit else 0.0)

    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    ground = mbs.AddNode(NodePointGround(referenceCoordinates=[0, 0, 0]))
    mg = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=ground, coordinate=0))
    nh = mbs.AddNode(NodeRigidBody2D(referenceCoordinates=[0, 0, 0],
                                     initialVelocities=[0, 0, Om0]))
    hub = mbs.AddObject(ObjectRigidBody2D(mass=1.0, inertia=hub_inertia(-1), nodeNumber=nh))
    for k in range(2):
        mk = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=nh, coordinate=k))
        mbs.AddObject(CoordinateConstraint(markerNumbers=[mg, mk]))
    mQ = mbs.AddMarker(MarkerBodyPosition(bodyNumber=hub, localPosition=[Lc, 0, 0]))
    nodes, mn = [], []
    v_stored = [0, 0] if explicit else [0, Om0 * Lc]     # parked, or moving with Q
    for j in range(n):
        nj = mbs.AddNode(NodePoint2D(referenceCoordinates=[Lc, 0], initialVelocities=v_stored))
        mbs.AddObject(MassPoint2D(mass=float(m[j]), nodeNumber=nj))
        nodes.append(nj)
        mn.append(mbs.AddMarker(MarkerNodePosition(nodeNumber=nj)))
    springs = [mbs.AddObject(SpringDamper(markerNumbers=[mn[j], mn[j + 1]], referenceLength=l0,
                                          stiffness=c, damping=d, activeConnector=False))
               for j in range(n - 1)]
    work = {"t": 0.0, "W": 0.0}        # spool work on one blade, summed at every new time
    state = {"b": -1}

    def q_force(mbs_, t, itemNumber, deltaL, deltaL_t, stiffness, damping, force):
        paid, rate, q_on = payout(p, t)
        if not q_on:                   # last node released at full payout
            return 0.0
        f = c * (deltaL - (paid - l0 * state["b"])) + d * (deltaL_t - rate)
        if t > work["t"]:              # rectangle rule at the solver's own (stage) times
            work["W"] -= f * rate * (t - work["t"])
            work["t"] = t
        return f

    qspr = [mbs.AddObject(SpringDamper(markerNumbers=[mn[j], mQ], referenceLength=0.0,
                                       stiffness=c, damping=d, activeConnector=False,
                                       springForceUserFunction=q_force))
            for j in range(n)]
    holds = ([] if explicit else
             [mbs.AddObject(RevoluteJoint2D(markerNumbers=[mQ, mn[j]])) for j in range(n)])
    mbs.Assemble()

    ode2_node = [mbs.GetNodeODE2Index(nj) for nj in nodes]
    hub_idx = mbs.GetNodeODE2Index(nh)
    N = len(t_out)
    psi_o, Om_o = np.full(N, np.nan), np.full(N, np.nan)
    X_o, V_o = np.full((N, n, 3), np.nan), np.full((N, n, 3), np.nan)
    b_o = np.full(N, -1)
    W_o = np.full(N, np.nan)

    def release(j, t):
        cfg = exu.ConfigurationType.Current
        q = mbs.systemData.GetODE2Coordinates(configuration=cfg)
        v = mbs.systemData.GetODE2Coordinates_t(configuration=cfg)
        psi, Om = q[hub_idx + 2], v[hub_idx + 2]
        cp, sp = np.cos(psi), np.sin(psi)
        i0 = ode2_node[j]
        dlt = s["release_offset"]         # keeps the new boundary segment off zero length
        q[i0:i0 + 2] = [(Lc + dlt) * cp - Lc, (Lc + dlt) * sp]
        v[i0:i0 + 2] = [-Om * Lc * sp + rw * cp, Om * Lc * cp + rw * sp]
        mbs.systemData.SetODE2Coordinates(q, configuration=cfg)
        mbs.systemData.SetODE2Coordinates_t(v, configuration=cfg)
        if explicit:
            mbs.SetObjectParameter(hub, "inertia", hub_inertia(j))
        else:
            mbs.SetObjectParameter(holds[j], "activeConnector", False)
        mbs.SetObjectParameter(qspr[j], "activeConnector", True)
        if j > 0:
            mbs.SetObjectParameter(qspr[j - 1], "activeConnector", False)
            mbs.SetObjectParameter(springs[j - 1], "activeConnector", True)
        state["b"] = j

    def record(io):
        cfg = exu.ConfigurationType.Current
        q = mbs.systemData.GetODE2Coordinates(configuration=cfg)
        v = mbs.systemData.GetODE2Coordinates_t(configuration=cfg)
        psi_o[io], Om_o[io] = q[hub_idx + 2], v[hub_idx + 2]
        for j in range(n):
            i0 = ode2_node[j]
            X_o[io, j] = (Lc + q[i0], q[i0 + 1], r)
            V_o[io, j] = (v[i0], v[i0 + 1], 0.0)
        b_o[io] = state["b"]
        W_o[io] = 2.0 * work["W"]         # two blades

    ss = exu.SimulationSettings()
    ss.timeIntegration.verboseMode = int(s.get("verbose", 0))
    ss.timeIntegration.adaptiveStep = False
    ss.timeIntegration.automaticStepSize = False
    ss.timeIntegration.newton.relativeTolerance = s["newton_rel_tol"]
    ss.timeIntegration.newton.absoluteTolerance = s["newton_abs_tol"]
    ss.timeIntegration.newton.useModifiedNewton = bool(s["modified_newton"])
    ss.timeIntegration.generalizedAlpha.spectralRadius = s["rho_inf"]
    ss.linearSolver.solverType = exu.LinearSolverType.EigenSparse
    ss.solution.file.write = False
    ss.solution.sensors.writePeriod = 1e9
    stype = _EXPLICIT[s["integrator"]][0] if explicit else _IMPLICIT[s["integrator"]]
    Cur, Ini = exu.ConfigurationType.Current, exu.ConfigurationType.Initial
    sd = mbs.systemData

    def solve_once(t0, t1, hs, tol):
        k = max(1, int(np.ceil((t1 - t0) / hs - 1e-9)))
        ss.timeIntegration.newton.relativeTolerance = tol
        ss.timeIntegration.newton.absoluteTolerance = tol * s["newton_abs_tol"] / s["newton_rel_tol"]
        sd.SetODE2Coordinates(sd.GetODE2Coordinates(configuration=Cur), configuration=Ini)
        sd.SetODE2Coordinates_t(sd.GetODE2Coordinates_t(configuration=Cur), configuration=Ini)
        sd.SetAECoordinates(sd.GetAECoordinates(configuration=Cur), configuration=Ini)
        ss.timeIntegration.startTime = t0
        ss.timeIntegration.endTime = t1
        ss.timeIntegration.numberOfSteps = k
        mbs.SolveDynamic(ss, solverType=stype, storeSolver=False)
        if explicit and not np.all(np.isfinite(sd.GetODE2Coordinates_t(configuration=Cur))):
            raise FloatingPointError("non-finite state")
        return k

    def solve(t0, t1, hs, tol):
        """Continue the solution from t0 to t1 with about step hs (state: Current). Implicit: if
        Newton fails (nearly zero-length boundary segment, stiff springs), restore the state and
        retry with steps 4x, 16x, 64x smaller and the looser `fine_newton_rel_tol`."""
        if explicit:
            return solve_once(t0, t1, hs, tol)
        saved = (sd.GetODE2Coordinates(configuration=Cur), sd.GetODE2Coordinates_t(configuration=Cur),
                 sd.GetAECoordinates(configuration=Cur), dict(work))
        last = None
        for div, tl in ((1, tol), (4, max(tol, s["fine_newton_rel_tol"])),
                        (16, max(tol, s["fine_newton_rel_tol"])),
                        (64, max(tol, s["fine_newton_rel_tol"]))):
            try:
                k = solve_once(t0, t1, hs / div, tl)
                retries[0] += div > 1
                return k
            except Exception as exc:     # exu.SolverError
                last = exc
                sd.SetODE2Coordinates(saved[0], configuration=Cur)
                sd.SetODE2Coordinates_t(saved[1], configuration=Cur)
                sd.SetAECoordinates(saved[2], configuration=Cur)
                work.update(saved[3])
        raise last

    retries = [0]

    # breakpoints: outputs and releases; implicit: after each release a window of `fine_window`
    # s is integrated with `fine_dt` (the new boundary segment is nearly zero-length and its
    # direction is ill-defined for Newton with the coarse step)
    bps = sorted(set(np.round(t_out, 12)) | {float(np.round(x, 12)) for x in
                                               [*t_rel[1:], t_full(p)] if x < t_out[-1]})
    out_index = {float(np.round(x, 12)): i for i, x in enumerate(t_out)}
    rel_index = {float(np.round(x, 12)): j for j, x in enumerate(t_rel) if j > 0}
    fine_window = 0.0 if explicit else s["fine_window"]
    status, reason, t_fail = "ok", None, None
    steps = 0
    wall0 = _time.perf_counter()
    t_last_rel = 0.0
    t = 0.0
    release(0, 0.0)
    try:
        for te in bps:
            if te > t:
                tf = min(te, t_last_rel + fine_window)
                if tf > t:
                    steps += solve(t, tf, s["fine_dt"], s["fine_newton_rel_tol"])
                    t = tf
                if te > t:
                    steps += solve(t, te, h, s["newton_rel_tol"])
                    t = te
            if te in rel_index:
                release(rel_index[te], te)
                t_last_rel = te
            if te in out_index:
                record(out_index[te])
    except Exception as exc:             # exu.SolverError (Newton failure), blow-up
        status, reason = "diverged", f"Exudyn solver failed: {str(exc).splitlines()[0][:200]}"
        if explicit and h > h_stable:
            reason += f" (step {h:.3g} s above the explicit stability limit ≈ {h_stable:.3g} s)"
        t_fail = float(t)
    wall = _time.perf_counter() - wall0
    if status == "ok" and not np.all(np.isfinite(Om_o)):
        status, reason = "diverged", "non-finite state"
        t_fail = float(t_out[~np.isfinite(Om_o)][0])
    ch, extra = channels(p, t_out, psi_o, Om_o, X_o, V_o, b_o, W_o)
    extra["hub_rate_formula18"] = formula18(p, t_out)
    extra["boundary_node"] = b_o.astype(float)
    return {"channels": ch, "status": status, "t_fail": t_fail, "reason": reason,
            "stats": {"steps": int(steps), "rhs_evals": -1, "segment_retries": retries[0],
                      "wall_s": wall},
            "settings": {**s, "dt": float(h)}, "extra": extra}

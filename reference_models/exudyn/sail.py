"""Exudyn reference model of the heliogyro blade deployment (scene `sail-deploy`, seed 004).

Inertial frame, planar (the motion stays in the plane z = r: no force has a z component), one
blade with half the hub inertia (symmetric deployment; channels report both blades). Shared
scene physics (thread, payout, release law, breakpoints, channels): compare/physics/sail.py.

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
  * explicit integrators ("velocity_verlet", default, and "rk4" = Exudyn's RK44): the stored thread
    is part of the hub inertia (J_hub/2 + Σ_stored m_j L_c², as in the custom conservative variant);
    a stored node is a parked mass point with no active connector. At its release time the hub
    inertia drops by m_j L_c² (the `inertia` parameter is re-read at every SolveDynamic call) and
    the node appears at Q with the hub-point velocity plus r ω along the rotated X1 axis: angular
    momentum is continuous and Ω does not jump. Explicit solvers cannot hold nodes by joints (shared
    notes), and the hub's two ground CoordinateConstraints are eliminated by the explicit solver,
    which is exact here because the hub's COM is its reference point (hub position stays at 0.0;
    checked). Velocity Verlet is symplectic and conserves the angular momentum of these central
    spring forces to round-off (measured 2.9e-11 over the full deployment, k = 1e5; 1.5e-11 over 30
    s at k = 1e7); Exudyn 1.13 prints "VelocityVerlet: still under development", so it is checked
    against MuJoCo (hub_rate 2.2e-7, tip 2.4e-8 rad over 30 s at k = 1e7). `dt="auto"` takes 0.8 ×
    (2 for Verlet, 2.785 for RK4) / (2 sqrt(c/m_min)).
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
  `fine_newton_tol` (the new boundary segment is nearly zero-length: its transverse
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
from exudyn.itemInterface import (
    CoordinateConstraint,
    MarkerBodyPosition,
    MarkerNodeCoordinate,
    MarkerNodePosition,
    MassPoint2D,
    NodePoint2D,
    NodePointGround,
    NodeRigidBody2D,
    ObjectRigidBody2D,
    RevoluteJoint2D,
    SpringDamper,
)

from compare.contract import LeafResult, check_once, merge_settings, require_positive
from compare.physics import sail as phys

from ..sail_common import check_grid, stable_dt_explicit

DEFAULT_SETTINGS = {"integrator": "velocity_verlet", "dt": "auto", "spectral_radius": 0.8,
                    "newton_tol": 1e-6, "newton_abs_tol": 1e-8, "modified_newton": True,
                    "verbose": 0, "fine_dt": 1e-5, "fine_window": 0.05, "release_offset": 1e-9,
                    "fine_newton_tol": 1e-6}
INTEGRATORS = ("velocity_verlet", "rk4", "generalized_alpha", "trapezoidal")
# explicit: Exudyn solver and stability interval on the imaginary axis
_EXPLICIT = {"velocity_verlet": (exu.DynamicSolverType.VelocityVerlet, 2.0),
             "rk4": (exu.DynamicSolverType.RK44, 2.785)}
_IMPLICIT = {"generalized_alpha": exu.DynamicSolverType.GeneralizedAlpha,
             "trapezoidal": exu.DynamicSolverType.TrapezoidalIndex2}
AUTO_DT = {"generalized_alpha": 0.05 / 70, "trapezoidal": 0.05 / 70}   # explicit: stability
# The error estimate's coarser members (compare/leafinfo.py `COARSER_DT`): the explicit auto
# step is 0.8 of the stability bound (sail_common.stable_dt_explicit, whose λ bounds the chain's
# highest frequency from above), so 1.2× the step stays at 0.96 of it; halving costs 2× the run.
COARSER_DT = {"velocity_verlet": (1.1, 1.2), "rk4": (1.1, 1.2)}


class _Sail:
    """build (the Exudyn system of one blade and half the hub) / release / step / observe."""

    def __init__(self, p: dict, s: dict, n_out: int):
        self.p, self.s = p, s
        self.n, self.l0, self.m, self.t_rel = phys.thread(p)
        n, l0 = self.n, self.l0
        Lc, c, d = p["L_c"], p["stiffness"], p["damping"]
        self.explicit = s["integrator"] in _EXPLICIT
        self.rw = p["r"] * p["omega_spool"]
        self.payout_args = (p["L"], self.rw, p["last_node"] == "released")
        self.cd = (c, d)
        self.b = -1
        self.work = {"t": 0.0, "W": 0.0}        # spool work on one blade, summed at every time
        self.retries = 0
        SC = exu.SystemContainer()
        self.SC = SC
        self.mbs = mbs = SC.AddSystem()
        ground = mbs.AddNode(NodePointGround(referenceCoordinates=[0, 0, 0]))
        mg = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=ground, coordinate=0))
        nh = mbs.AddNode(NodeRigidBody2D(referenceCoordinates=[0, 0, 0],
                                         initialVelocities=[0, 0, p["Omega0"]]))
        self.hub = mbs.AddObject(ObjectRigidBody2D(mass=1.0, inertia=self.hub_inertia(-1),
                                                   nodeNumber=nh))
        for k in range(2):
            mk = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=nh, coordinate=k))
            mbs.AddObject(CoordinateConstraint(markerNumbers=[mg, mk]))
        mQ = mbs.AddMarker(MarkerBodyPosition(bodyNumber=self.hub, localPosition=[Lc, 0, 0]))
        nodes, mn = [], []
        v_stored = [0, 0] if self.explicit else [0, p["Omega0"] * Lc]   # parked, or with Q
        for j in range(n):
            nj = mbs.AddNode(NodePoint2D(referenceCoordinates=[Lc, 0],
                                         initialVelocities=v_stored))
            mbs.AddObject(MassPoint2D(mass=float(self.m[j]), nodeNumber=nj))
            nodes.append(nj)
            mn.append(mbs.AddMarker(MarkerNodePosition(nodeNumber=nj)))
        self.springs = [mbs.AddObject(SpringDamper(markerNumbers=[mn[j], mn[j + 1]],
                                                   referenceLength=l0, stiffness=c, damping=d,
                                                   activeConnector=False))
                        for j in range(n - 1)]
        self.qspr = [mbs.AddObject(SpringDamper(markerNumbers=[mn[j], mQ], referenceLength=0.0,
                                                stiffness=c, damping=d, activeConnector=False,
                                                springForceUserFunction=self.q_force))
                     for j in range(n)]
        self.holds = ([] if self.explicit else
                      [mbs.AddObject(RevoluteJoint2D(markerNumbers=[mQ, mn[j]]))
                       for j in range(n)])
        mbs.Assemble()
        self.ode2_node = [mbs.GetNodeODE2Index(nj) for nj in nodes]
        self.hub_idx = mbs.GetNodeODE2Index(nh)
        self.out = {"psi": np.full(n_out, np.nan), "omega": np.full(n_out, np.nan),
                    "X": np.full((n_out, n, 3), np.nan), "V": np.full((n_out, n, 3), np.nan),
                    "b": np.full(n_out, -1), "W": np.full(n_out, np.nan)}
        self.ss = self._solver_settings()
        self.stype = (_EXPLICIT[s["integrator"]][0] if self.explicit
                      else _IMPLICIT[s["integrator"]])

    def hub_inertia(self, b: int) -> float:
        """Half the hub plus, for the explicit model, the thread still stored (nodes > b)."""
        extra = float(self.m[b + 1:].sum()) * self.p["L_c"]**2 if self.explicit else 0.0
        return 0.5 * self.p["J_hub"] + extra

    def q_force(self, mbs_, t, itemNumber, deltaL, deltaL_t, stiffness, damping, force):
        """The boundary node's Q-spring: growing rest length, damper on the true stretch rate."""
        # the shared payout law, called as plain Python (no jit dispatch in a user function)
        paid, rate, q_on = phys.payout.py_func(t, *self.payout_args)
        if not q_on:                   # last node released at full payout
            return 0.0
        c, d = self.cd
        f = c * (deltaL - (paid - self.l0 * self.b)) + d * (deltaL_t - rate)
        if t > self.work["t"]:         # rectangle rule at the solver's own (stage) times
            self.work["W"] -= f * rate * (t - self.work["t"])
            self.work["t"] = t
        return f

    def _solver_settings(self):
        s = self.s
        ss = exu.SimulationSettings()
        ss.timeIntegration.verboseMode = int(s["verbose"])
        ss.timeIntegration.adaptiveStep = False
        ss.timeIntegration.automaticStepSize = False
        ss.timeIntegration.newton.relativeTolerance = s["newton_tol"]
        ss.timeIntegration.newton.absoluteTolerance = s["newton_abs_tol"]
        ss.timeIntegration.newton.useModifiedNewton = bool(s["modified_newton"])
        ss.timeIntegration.generalizedAlpha.spectralRadius = s["spectral_radius"]
        ss.linearSolver.solverType = exu.LinearSolverType.EigenSparse
        ss.solution.file.write = False
        ss.solution.sensors.writePeriod = 1e9
        return ss

    # ---- release / observe ------------------------------------------------------------------
    def release(self, j: int) -> None:
        """Node j leaves Q by the shared release law (put `release_offset` beyond Q)."""
        mbs, cfg, Lc = self.mbs, exu.ConfigurationType.Current, self.p["L_c"]
        q = mbs.systemData.GetODE2Coordinates(configuration=cfg)
        v = mbs.systemData.GetODE2Coordinates_t(configuration=cfg)
        psi, Om = q[self.hub_idx + 2], v[self.hub_idx + 2]
        _, _, _, v0, v1, _ = phys.release_state(psi, Om, Lc, self.p["r"], self.rw)
        i0 = self.ode2_node[j]
        dlt = self.s["release_offset"]     # keeps the new boundary segment off zero length
        q[i0:i0 + 2] = [(Lc + dlt) * np.cos(psi) - Lc, (Lc + dlt) * np.sin(psi)]
        v[i0:i0 + 2] = [v0, v1]
        mbs.systemData.SetODE2Coordinates(q, configuration=cfg)
        mbs.systemData.SetODE2Coordinates_t(v, configuration=cfg)
        if self.explicit:
            mbs.SetObjectParameter(self.hub, "inertia", self.hub_inertia(j))
        else:
            mbs.SetObjectParameter(self.holds[j], "activeConnector", False)
        mbs.SetObjectParameter(self.qspr[j], "activeConnector", True)
        if j > 0:
            mbs.SetObjectParameter(self.qspr[j - 1], "activeConnector", False)
            mbs.SetObjectParameter(self.springs[j - 1], "activeConnector", True)
        self.b = j

    def observe(self, io: int) -> None:
        cfg, o, Lc, r = exu.ConfigurationType.Current, self.out, self.p["L_c"], self.p["r"]
        q = self.mbs.systemData.GetODE2Coordinates(configuration=cfg)
        v = self.mbs.systemData.GetODE2Coordinates_t(configuration=cfg)
        o["psi"][io], o["omega"][io] = q[self.hub_idx + 2], v[self.hub_idx + 2]
        for j in range(self.n):
            i0 = self.ode2_node[j]
            o["X"][io, j] = (Lc + q[i0], q[i0 + 1], r)
            o["V"][io, j] = (v[i0], v[i0 + 1], 0.0)
        o["b"][io] = self.b
        o["W"][io] = 2.0 * self.work["W"]         # two blades

    # ---- step -------------------------------------------------------------------------------
    def _solve_once(self, t0: float, t1: float, hs: float, tol: float) -> int:
        s, ss, sd = self.s, self.ss, self.mbs.systemData
        Cur, Ini = exu.ConfigurationType.Current, exu.ConfigurationType.Initial
        k = max(1, int(np.ceil((t1 - t0) / hs - 1e-9)))
        ss.timeIntegration.newton.relativeTolerance = tol
        ss.timeIntegration.newton.absoluteTolerance = tol * s["newton_abs_tol"] / s["newton_tol"]
        sd.SetODE2Coordinates(sd.GetODE2Coordinates(configuration=Cur), configuration=Ini)
        sd.SetODE2Coordinates_t(sd.GetODE2Coordinates_t(configuration=Cur), configuration=Ini)
        sd.SetAECoordinates(sd.GetAECoordinates(configuration=Cur), configuration=Ini)
        ss.timeIntegration.startTime = t0
        ss.timeIntegration.endTime = t1
        ss.timeIntegration.numberOfSteps = k
        self.mbs.SolveDynamic(ss, solverType=self.stype, storeSolver=False)
        if self.explicit and not np.all(np.isfinite(sd.GetODE2Coordinates_t(configuration=Cur))):
            raise FloatingPointError("non-finite state")
        return k

    def step(self, t0: float, t1: float, hs: float, tol: float) -> int:
        """Continue from t0 to t1 with about step hs. Implicit: if Newton fails (nearly
        zero-length boundary segment, stiff springs), restore the state and retry with steps 4x,
        16x, 64x smaller and the looser `fine_newton_tol`. Returns the number of steps."""
        if self.explicit:
            return self._solve_once(t0, t1, hs, tol)
        sd, Cur = self.mbs.systemData, exu.ConfigurationType.Current
        saved = (sd.GetODE2Coordinates(configuration=Cur),
                 sd.GetODE2Coordinates_t(configuration=Cur),
                 sd.GetAECoordinates(configuration=Cur), dict(self.work))
        fine = max(tol, self.s["fine_newton_tol"])
        last = None
        for div, tl in ((1, tol), (4, fine), (16, fine), (64, fine)):
            try:
                k = self._solve_once(t0, t1, hs / div, tl)
                self.retries += div > 1
                return k
            except Exception as exc:     # exu.SolverError
                last = exc
                sd.SetODE2Coordinates(saved[0], configuration=Cur)
                sd.SetODE2Coordinates_t(saved[1], configuration=Cur)
                sd.SetAECoordinates(saved[2], configuration=Cur)
                self.work.update(saved[3])
        raise last


def _run(model: _Sail, p: dict, t_out: np.ndarray, h: float) -> tuple:
    """Breakpoints: outputs and releases; implicit: after each release a window of
    `fine_window` s is integrated with `fine_dt` (the new boundary segment is nearly
    zero-length and its direction ill-defined for Newton with the coarse step). Returns
    (status, reason, t_fail, steps)."""
    s = model.s
    fine_window = 0.0 if model.explicit else s["fine_window"]
    steps = 0
    t_last_rel = 0.0
    t = 0.0
    model.release(0)
    try:
        for te, io, jr, _ in zip(*phys.breakpoints(p, t_out), strict=True):
            if te > t:
                tf = min(te, t_last_rel + fine_window)
                if tf > t:
                    steps += model.step(t, tf, s["fine_dt"], s["fine_newton_tol"])
                    t = tf
                if te > t:
                    steps += model.step(t, te, h, s["newton_tol"])
                    t = te
            if jr > 0:
                model.release(jr)
                t_last_rel = te
            if io >= 0:
                model.observe(io)
    except Exception as exc:             # exu.SolverError (Newton failure), blow-up
        return "diverged", f"Exudyn solver failed: {str(exc).splitlines()[0][:200]}", float(t), \
            steps
    return "ok", None, None, steps


@check_once
def check_settings(settings: dict | None, t_out: np.ndarray | None = None) -> dict:
    """The settings merged and checked before anything runs (ValueError with one line)."""
    s = merge_settings(settings, DEFAULT_SETTINGS, INTEGRATORS)
    if not 0.0 <= float(s["spectral_radius"]) <= 1.0:
        raise ValueError(f"spectral_radius must be in [0, 1], got {s['spectral_radius']!r}")
    require_positive(s, ("newton_tol", "newton_abs_tol", "fine_dt", "fine_newton_tol"))
    require_positive(s, ("dt",), auto_ok=True)
    return s


def simulate(params: dict, t_out: np.ndarray, settings: dict | None = None) -> LeafResult:
    s, t_out = check_settings(settings), check_grid(t_out)
    explicit = s["integrator"] in _EXPLICIT
    h_stable = stable_dt_explicit(params, _EXPLICIT[s["integrator"]][1]) if explicit else None
    h = (h_stable if explicit else AUTO_DT[s["integrator"]]) if s["dt"] in (None, "auto") \
        else float(s["dt"])
    model = _Sail(params, s, len(t_out))
    wall0 = _time.perf_counter()
    status, reason, t_fail, steps = _run(model, params, t_out, h)
    wall = _time.perf_counter() - wall0
    if status != "ok" and explicit and h > h_stable:
        reason += f" (step {h:.3g} s above the explicit stability limit ≈ {h_stable:.3g} s)"
    o = model.out
    if status == "ok" and not np.all(np.isfinite(o["omega"])):
        status, reason = "diverged", "non-finite state"
        t_fail = float(t_out[~np.isfinite(o["omega"])][0])
    ch, extra = phys.channels(params, t_out, o["psi"], o["omega"], o["X"], o["V"], o["b"],
                              spool_work=o["W"])
    extra["hub_rate_formula18"] = phys.formula18(params, t_out)
    extra["boundary_node"] = o["b"].astype(float)
    return LeafResult(channels=ch, status=status, t_fail=t_fail, reason=reason,
            stats={"steps": int(steps), "rhs_evals": -1, "retries": model.retries,
                      "integrate_s": wall},
            settings={**s, "dt": float(h)}, extra=extra)

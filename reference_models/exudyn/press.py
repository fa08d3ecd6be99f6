"""Exudyn model of the crank–rod–rocker–slider press (`press`) and its lock/release cycle
(`press-cycle`).

Model: three `NodeRigidBody2D`/`ObjectRigidBody2D` links (node = centre of mass, so the lumped
"paper" masses sit at A, B, C), a `NodePoint2D`/`MassPoint2D` slider, four `RevoluteJoint2D`
(O, A, B, C) and a `CoordinateConstraint` y_slider = 0 — an index-3 DAE with 11 coordinates and
9 constraints, solved with Exudyn's generalized-α (position-level constraints, no drift).
The Kloss motor torque is a `LoadCoordinate` on the crank's rotation coordinate whose user function
reads the crank speed of the current Newton iterate. Slider spring/damper:
`CoordinateSpringDamper` on the slider's x displacement.

The run is split into segments (each output interval, plus lock_after / release_after) solved by
`SolveDynamic` with `updateInitialValues=True`; a pre-step user function records every step's
state so the motor work, the damper loss and the press work are integrated step by step with the
Hermite-corrected trapezoid (4th order) and so the lock event is found between two steps; the
lock instant is then located by bisection with one-step re-solves from the saved state.

The lock is a `CoordinateConstraint` on the rocker's rotation coordinate, switched on at the
event with the plastic impact applied explicitly: q̇⁺ = q̇⁻ − M⁻¹Gᵀ(GM⁻¹Gᵀ)⁻¹Gq̇⁻ with the
mass matrix M of the Exudyn bodies and the Jacobian G of all active constraints (lock included)
on Exudyn's coordinates — the momentum of the remaining coordinate is kept, the loss is T⁻ − T⁺.
"""
from __future__ import annotations

import math

import exudyn as exu
import numpy as np
from exudyn import itemInterface as ii

from compare.contract import LeafResult, check_once
from compare.physics import press as phys

from .. import press_common as pc

DEFAULT_SETTINGS = {"integrator": "generalized_alpha", "dt": 2e-5, "spectral_radius": 0.8,
                    "newton_tol": 1e-10, "newton_abs_tol": 1e-12}
INTEGRATORS = ("generalized_alpha", "trapezoidal")
# the error estimate's Newton jitter (compare/solvers.py `_unseen_error`): the tight run again
# with Newton's relative tolerance (the one that binds) scaled by the first of these that
# completes — index-3 accelerations carry the positions' Newton error over β·dt², so
# crank_accel scatters by up to 1.3e-16 s² × its scale / dt²; 1000× tighter reaches the
# rounding floor, and through a lock only a looser tolerance may converge
JITTER_PROBE = {"newton_tol": (1e-3, 1e-2, 1e-1, 10.0)}

class _Diverged(Exception):
    def __init__(self, t, reason):
        super().__init__(reason)
        self.t, self.reason = t, reason


@check_once
def check_settings(settings: dict | None, t_out: np.ndarray | None = None) -> dict:
    """The settings merged and checked before anything runs (ValueError with one line)."""
    s = pc.fixed_step_settings(settings, DEFAULT_SETTINGS, INTEGRATORS)
    rho = float(s["spectral_radius"])
    if not 0.0 <= rho <= 1.0:
        raise ValueError(f"spectral_radius must be in [0, 1], got {rho!r}")
    s["spectral_radius"] = rho
    return s


class _Press:
    """The Exudyn system plus the bookkeeping the scene needs."""

    def __init__(self, p: dict, st: dict, settings: dict, cycle: bool):
        self.exu = exu
        self.p, self.st, self.cycle, self.settings = p, st, cycle, settings
        self.n_bisections = 0
        self.u = float(p["gear_ratio"])
        self.k, self.c = float(p["slider_stiffness"]), float(p["slider_damping"])
        self.F = float(p["press_force"]) if cycle else 0.0
        self.g = float(p["gravity"])
        self.locked = False
        lay = phys.link_layout(p)
        self.lay = lay
        SC = exu.SystemContainer()
        mbs = SC.AddSystem()
        self.SC, self.mbs = SC, mbs
        ground = mbs.AddObject(ii.ObjectGround())
        ng = mbs.AddNode(ii.NodePointGround())
        mg = mbs.AddMarker(ii.MarkerNodeCoordinate(nodeNumber=ng, coordinate=0))

        # link: (first point, direction angle, rate, velocity of first point, length)
        links = {
            "crank": (np.zeros(2), st["phi"], st["phid"], np.zeros(2), float(p["l1"])),
            "rod": (st["A"], st["theta2"], st["theta2d"], st["vA"], float(p["l2"])),
            "rocker": (st["C"], st["psi"], st["psid"], st["vC"], float(p["l3"])),
        }
        self.nodes, self.bodies, self.local = {}, {}, {}
        for name, (P0, ang, rate, v0, L) in links.items():
            cx, m, J = lay[name]
            e = np.array([math.cos(ang), math.sin(ang)])
            en = np.array([-math.sin(ang), math.cos(ang)])
            com = P0 + cx * e
            vcom = v0 + rate * cx * en
            n = mbs.AddNode(ii.NodeRigidBody2D(referenceCoordinates=[com[0], com[1], ang],
                                               initialCoordinates=[0, 0, 0],
                                               initialVelocities=[vcom[0], vcom[1], rate]))
            b = mbs.AddObject(ii.ObjectRigidBody2D(nodeNumber=n, mass=m, inertia=J))
            mm = mbs.AddMarker(ii.MarkerBodyMass(bodyNumber=b))
            mbs.AddLoad(ii.LoadMassProportional(markerNumber=mm, loadVector=[0, -self.g, 0]))
            self.nodes[name], self.bodies[name] = n, b
            # local positions of the link's first and second joint points (from the COM)
            self.local[name] = (np.array([-cx, 0.0]), np.array([L - cx, 0.0]))
        ns = mbs.AddNode(ii.NodePoint2D(referenceCoordinates=[st["C"][0], 0.0],
                                        initialCoordinates=[0, 0],
                                        initialVelocities=[st["vC"][0], 0.0]))
        mbs.AddObject(ii.MassPoint2D(nodeNumber=ns, mass=float(p["m4"])))
        self.nodes["slider"] = ns

        def bm(name, which):
            return mbs.AddMarker(ii.MarkerBodyPosition(
                bodyNumber=self.bodies[name], localPosition=[*self.local[name][which], 0.0]))
        mO = mbs.AddMarker(ii.MarkerBodyPosition(bodyNumber=ground, localPosition=[0, 0, 0]))
        mS = mbs.AddMarker(ii.MarkerNodePosition(nodeNumber=ns))
        # joints: O (ground–crank), A (crank end – rod start), B (rod end – rocker end),
        # C (rocker start – slider)
        for m0, m1 in ((mO, bm("crank", 0)), (bm("crank", 1), bm("rod", 0)),
                       (bm("rod", 1), bm("rocker", 1)), (bm("rocker", 0), mS)):
            mbs.AddObject(ii.RevoluteJoint2D(markerNumbers=[m0, m1]))
        msx = mbs.AddMarker(ii.MarkerNodeCoordinate(nodeNumber=ns, coordinate=0))
        msy = mbs.AddMarker(ii.MarkerNodeCoordinate(nodeNumber=ns, coordinate=1))
        mbs.AddObject(ii.CoordinateConstraint(markerNumbers=[mg, msy]))
        mbs.AddObject(ii.CoordinateSpringDamper(markerNumbers=[mg, msx], stiffness=self.k,
                                                damping=self.c, offset=0.0))
        # motor
        mcr = mbs.AddMarker(ii.MarkerNodeCoordinate(nodeNumber=self.nodes["crank"], coordinate=2))
        ncr = self.nodes["crank"]
        Ct = exu.OutputVariableType.Coordinates_t
        u = self.u

        def motor(mbs_, t, load):
            return phys.motor_torque(mbs_.GetNodeOutput(ncr, Ct)[2], u)
        mbs.AddLoad(ii.LoadCoordinate(markerNumber=mcr, load=0.0, loadUserFunction=motor))
        self.lock = None
        if cycle:
            F = self.F

            vreg = float(p["press_force_vreg"])

            def press(mbs_, t, load):
                if not self.locked:
                    return 0.0
                return phys.press_load(mbs_.GetNodeOutput(ns, Ct)[0], F, vreg)
            mbs.AddLoad(ii.LoadCoordinate(markerNumber=msx, load=0.0, loadUserFunction=press))
            mro = mbs.AddMarker(ii.MarkerNodeCoordinate(nodeNumber=self.nodes["rocker"],
                                                        coordinate=2))
            self.lock = mbs.AddObject(ii.CoordinateConstraint(markerNumbers=[mg, mro], offset=0.0,
                                                              activeConnector=False))
        mbs.Assemble()
        self.idx = {k: mbs.GetNodeODE2Index(n) for k, n in self.nodes.items()}
        self.ref = np.array(mbs.systemData.GetODE2Coordinates(
            configuration=exu.ConfigurationType.Reference))

        ss = exu.SimulationSettings()
        ss.solution.file.write = False
        ss.timeIntegration.verboseMode = 0
        ss.show.statistics = False
        ss.show.computationTime = False
        ss.timeIntegration.adaptiveStep = False
        ss.timeIntegration.newton.relativeTolerance = float(settings["newton_tol"])
        ss.timeIntegration.newton.absoluteTolerance = float(settings["newton_abs_tol"])
        ss.timeIntegration.newton.useModifiedNewton = False
        ss.linearSolver.solverType = exu.LinearSolverType.EXUdense
        if settings["integrator"] == "generalized_alpha":
            ss.timeIntegration.generalizedAlpha.spectralRadius = settings["spectral_radius"]
            ss.timeIntegration.generalizedAlpha.useIndex2Constraints = False
            ss.timeIntegration.generalizedAlpha.useNewmark = False
        else:
            ss.timeIntegration.generalizedAlpha.useIndex2Constraints = True
            ss.timeIntegration.generalizedAlpha.useNewmark = True
            ss.timeIntegration.generalizedAlpha.spectralRadius = 1.0
        self.ss = ss
        self.solver_type = exu.DynamicSolverType.GeneralizedAlpha
        self.steps = 0
        self.rec = []          # per step: (t, q, v, a) of the start-of-step states
        self.h = None
        self.t0 = None
        mbs.SetPreStepUserFunction(self._prestep)

    # ---- state ----------------------------------------------------------------------------
    def state(self):
        sd, C = self.mbs.systemData, self.exu.ConfigurationType.Current
        return (np.array(sd.GetODE2Coordinates(configuration=C)),
                np.array(sd.GetODE2Coordinates_t(configuration=C)),
                np.array(sd.GetODE2Coordinates_tt(configuration=C)))

    def set_initial(self, q, v):
        sd, I = self.mbs.systemData, self.exu.ConfigurationType.Initial
        sd.SetODE2Coordinates(list(q), configuration=I)
        sd.SetODE2Coordinates_t(list(v), configuration=I)

    def _prestep(self, mbs, t):
        # called with t = end of the coming step, state = start of that step
        self.rec.append((t - self.h, *self.state()))
        return True

    # ---- observation ------------------------------------------------------------------------
    def observe(self, q, v, a):
        """The kinematic output the scene's channels are built from, and T, V of the bodies."""
        i = self.idx
        x = self.ref + q
        T = 0.0
        Vg = 0.0
        for name in ("crank", "rod", "rocker"):
            j = i[name]
            _, m, J = self.lay[name]
            T += 0.5 * m * (v[j] ** 2 + v[j + 1] ** 2) + 0.5 * J * v[j + 2] ** 2
            Vg += m * self.g * x[j + 1]
        js = i["slider"]
        T += 0.5 * float(self.p["m4"]) * (v[js] ** 2 + v[js + 1] ** 2)
        Vg += float(self.p["m4"]) * self.g * x[js + 1]
        Vs = 0.5 * self.k * q[js] ** 2
        jc, jr = i["crank"] + 2, i["rocker"] + 2
        return {"crank_angle": x[jc], "crank_rate": v[jc], "crank_accel": a[jc],
                "rocker_angle": x[jr], "slider_x": x[js], "T": T, "V": Vg + Vs}

    def rates(self, v, a, locked):
        """(integrand, derivative) of motor work, damper loss, press work at one state."""
        jc, js = self.idx["crank"] + 2, self.idx["slider"]
        w, wd = v[jc], a[jc]
        tau = phys.motor_torque(w, self.u)
        eps = 1e-6 * max(1.0, abs(w))
        dtau = (phys.motor_torque(w + eps, self.u) - phys.motor_torque(w - eps, self.u)) / (2 * eps)
        vs, as_ = v[js], a[js]
        out = [tau * w, (dtau * w + tau) * wd, self.c * vs * vs, 2 * self.c * vs * as_, 0.0, 0.0]
        if locked:
            out[4], out[5] = phys.press_power(vs, as_, self.F, float(self.p["press_force_vreg"]))
        return np.array(out)

    # ---- solving ----------------------------------------------------------------------------
    def solve(self, t0, t1, nsteps, record=True):
        """Solve [t0, t1] in nsteps from the Initial configuration; returns the records."""
        ss = self.ss
        ss.timeIntegration.startTime = t0
        ss.timeIntegration.endTime = t1
        ss.timeIntegration.numberOfSteps = int(nsteps)
        self.h = (t1 - t0) / nsteps
        self.rec = []
        try:
            ok = self.mbs.SolveDynamic(ss, solverType=self.solver_type, updateInitialValues=True)
        except Exception as exc:  # exudyn.SolverError, RuntimeError
            why = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
            raise _Diverged(t0, f"exudyn solver failed in [{t0:.6g}, {t1:.6g}]: {why}") from None
        if not ok:
            raise _Diverged(t0, f"exudyn SolveDynamic returned False in [{t0:.6g}, {t1:.6g}]")
        self.steps += int(nsteps)
        q, v, a = self.state()
        if not (np.all(np.isfinite(q)) and np.all(np.isfinite(v)) and np.all(np.isfinite(a))):
            raise _Diverged(t1, "non-finite state")
        rec = self.rec + [(t1, q, v, a)]
        return rec

    def impact_matrices(self, q):
        """Mass matrix and Jacobian of every active constraint (the four revolute joints, y_slider
        = 0 and the lock) on Exudyn's ODE2 coordinates at the configuration q.  Node = centre of
        mass, so M is diag(m, m, J) per link and (m4, m4) for the slider."""
        i = self.idx
        x = self.ref + q
        n2 = len(q)
        M = np.zeros((n2, n2))
        for name in ("crank", "rod", "rocker"):
            _, m, J = self.lay[name]
            j = i[name]
            M[j, j] = M[j + 1, j + 1] = m
            M[j + 2, j + 2] = J
        js = i["slider"]
        M[js, js] = M[js + 1, js + 1] = float(self.p["m4"])

        def point_jac(name, which):
            j = i[name]
            th = x[j + 2]
            r = self.local[name][which]
            Rr = np.array([math.cos(th) * r[0] - math.sin(th) * r[1],
                           math.sin(th) * r[0] + math.cos(th) * r[1]])
            G = np.zeros((2, n2))
            G[:, j:j + 2] = np.eye(2)
            G[:, j + 2] = [-Rr[1], Rr[0]]
            return G
        Gs = np.zeros((2, n2))
        Gs[:, js:js + 2] = np.eye(2)
        rows = [point_jac("crank", 0),
                point_jac("crank", 1) - point_jac("rod", 0),
                point_jac("rod", 1) - point_jac("rocker", 1),
                point_jac("rocker", 0) - Gs,
                Gs[1:2]]
        lock = np.zeros((1, n2))
        lock[0, i["rocker"] + 2] = 1.0
        rows.append(lock)
        return M, np.vstack(rows)


def _hermite(rec_rates, t):
    """∫ of several integrands over consecutive records, Hermite-corrected trapezoid."""
    f = rec_rates[:, 0::2]
    fd = rec_rates[:, 1::2]
    h = np.diff(t)[:, None]
    return np.sum(0.5 * h * (f[1:] + f[:-1]) + h * h / 12.0 * (fd[:-1] - fd[1:]), axis=0)


def _integrate_records(model, rec, locked) -> np.ndarray:
    """Motor work, damper loss and press work over a run of step records."""
    return _hermite(np.array([model.rates(r[2], r[3], locked) for r in rec]),
                    np.array([r[0] for r in rec]))


def _rocker_angle(model, q) -> float:
    jr = model.idx["rocker"] + 2
    return model.ref[jr] + q[jr]


def _find_lock(model, rec, h, psi_lock, work) -> float | None:
    """The first step in `rec` across ψ = lock angle: its work is booked up to the crossing,
    located by bisection with one-step re-solves from the step's start. Returns the lock time
    (the state is then at the crossing) or None."""
    g = np.array([_rocker_angle(model, r[1]) - psi_lock for r in rec])
    hit = np.nonzero(np.sign(g[1:]) * np.sign(g[:-1]) <= 0)[0]
    if not len(hit):
        return None
    j = int(hit[0])
    work += _integrate_records(model, rec[:j + 1], model.locked)
    ta, qa, va = rec[j][0], rec[j][1], rec[j][2]
    def advance(dt):
        model.set_initial(qa, va)
        r2 = model.solve(ta, ta + dt, 1)
        return _rocker_angle(model, r2[-1][1]) - psi_lock, r2
    hi, nb, last = pc.bisect_event(advance, g[j], h)
    if last is None or abs(last[-1][0] - (ta + hi)) > 1e-15:
        model.set_initial(qa, va)
        last = model.solve(ta, ta + hi, 1)
    work += _integrate_records(model, last, False)
    model.n_bisections = nb
    return ta + hi


def _apply_lock(model) -> tuple:
    """Plastic lock: activate the rocker constraint, project the velocities with Exudyn's own M
    and G. Returns (kinetic energy lost, crank-rate jump)."""
    q, v, a = model.state()
    jr = model.idx["rocker"] + 2
    model.mbs.SetObjectParameter(model.lock, "offset", float(q[jr]))
    model.mbs.SetObjectParameter(model.lock, "activeConnector", True)
    model.set_initial(q, v)
    M, G = model.impact_matrices(q)
    Minv_Gt = np.linalg.solve(M, G.T)
    lam = np.linalg.lstsq(G @ Minv_Gt, G @ v, rcond=None)[0]
    v_new = v - Minv_Gt @ lam
    loss = model.observe(q, v, a)["T"] - model.observe(q, v_new, a)["T"]
    model.locked = True
    model.set_initial(q, v_new)
    jc = model.idx["crank"] + 2
    return loss, v_new[jc] - v[jc]


COLUMNS = ("crank_angle", "crank_rate", "crank_accel", "rocker_angle", "slider_x", "T", "V",
           "W_motor", "W_damper", "W_press", "lock_loss")


def _run(model, p: dict, t_out: np.ndarray, rows: dict, extra: dict) -> tuple:
    """Segment by segment between the breakpoints; the lock as an event between two steps.
    Fills `rows` at the outputs; returns (status, t_fail, reason)."""
    dt = model.settings["dt"]
    work = np.zeros(3)          # motor work, damper loss, press work
    lock_loss = 0.0

    def store(k, obs):
        for name in COLUMNS[:7]:
            rows[name][k] = obs[name]
        rows["W_motor"][k], rows["W_damper"][k], rows["W_press"][k] = work
        rows["lock_loss"][k] = lock_loss

    bounds, out_index, events = phys.breakpoints(p, t_out)
    la, ra, psi_lock = events if model.cycle else (None, None, None)
    store(0, model.observe(*model.state()))
    t = 0.0
    bi = 1
    released = False
    t_lock = None
    try:
        while bi < len(bounds):
            t1 = bounds[bi]
            nst = max(1, int(math.ceil((t1 - t) / dt - 1e-9)))
            rec = model.solve(t, t1, nst)
            if t == 0.0:   # GA computed the consistent initial accelerations: store t = 0 again
                store(0, model.observe(*rec[0][1:]))
            if model.cycle and t_lock is None and la - 1e-15 <= t < ra - 1e-15:
                t_lock = _find_lock(model, rec, (t1 - t) / nst, psi_lock, work)
                if t_lock is not None:
                    lock_loss, jump = _apply_lock(model)
                    extra.update({"t_lock": np.array([t_lock]),
                                  "lock_energy_loss": np.array([lock_loss]),
                                  "lock_bisections": np.array([model.n_bisections]),
                                  "crank_rate_jump": np.array([jump])})
                    t = t_lock
                    continue          # bounds[bi] is still the target: on from t_lock
            work += _integrate_records(model, rec, model.locked)
            t = t1
            if model.cycle and model.locked and not released and abs(t - ra) < 1e-12:
                model.mbs.SetObjectParameter(model.lock, "activeConnector", False)
                model.locked = False
                released = True
            k = out_index.get(float(t1))
            if k is not None:
                obs = model.observe(*model.state())
                store(k, obs)
                if not all(np.isfinite(obs[c]) for c in ("crank_angle", "slider_x")):
                    raise _Diverged(t1, "non-finite output")
            bi += 1
    except _Diverged as d:
        return "diverged", float(d.t), d.reason, work
    finally:
        model.mbs.SetPreStepUserFunction(0)
    return "ok", None, None, work


def simulate(params: dict, t_out: np.ndarray, settings: dict | None = None) -> LeafResult:
    """Run `press` (idle) or, when the parameters carry the lock, `press-cycle`."""
    s = check_settings(settings)
    cycle, t_out, st = pc.prepare(params, t_out, s)
    prev = exu.config.printToConsole
    exu.config.printToConsole = False      # the failure banner would otherwise go to stdout
    rows = {k: np.full(len(t_out), np.nan) for k in COLUMNS}
    extra = {}
    try:
        model = _Press(params, st, s, cycle)
        status, t_fail, reason, work = _run(model, params, t_out, rows, extra)
    finally:
        exu.config.printToConsole = prev
    ch = phys.channels(params, *(rows[k] for k in COLUMNS))
    if t_fail is not None:
        bad = t_out > t_fail - 1e-15
        for name in ch:
            ch[name][bad] = np.nan
    if cycle:
        extra.setdefault("t_lock", np.array([np.nan]))
        extra.setdefault("lock_energy_loss", np.array([np.nan]))
        extra["motor_work"] = np.array([work[0]])
        extra["press_work"] = np.array([work[2]])
    return LeafResult(channels=ch, status=status, t_fail=t_fail, reason=reason,
            stats={"steps": model.steps, "rhs_evals": -1}, settings=dict(s),
            extra=extra)

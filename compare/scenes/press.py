"""Crank–rocker press with slider, idle and variable structure (seed 003; spec scene-press.md)."""
import math

import numpy as np

from ..errors import BadInput
from ..physics import press as phys
from .base import Calibration, Extreme, Finding, MapSpec, TimeScene
from .params import Param, positive

SOURCE = "seed 003 (clutchless crank press; Lagrange partial systems, linear-acceleration method)"

_MECHANISM = (
    positive("l1", 0.015, "m", "crank length O–A"),
    positive("l2", 0.040, "m", "connecting-rod length A–B"),
    positive("l3", 0.030, "m", "rocker length B–C"),
    positive("m1", 4.6, "kg", "crank mass (lumped at A)"),
    positive("m2", 20.0, "kg", "rod mass (lumped at B)"),
    positive("m3", 18.0, "kg", "rocker mass (lumped at C)"),
    positive("m4", 100.0, "kg", "slider mass"),
    positive("J1", 0.034, "kg·m²", "crank moment of inertia"),
    positive("J2", 0.036, "kg·m²", "rod moment of inertia"),
    positive("J3", 0.0441, "kg·m²", "rocker moment of inertia"),
    Param("phi0", -64.1, "deg", "initial crank angle", lo=-360, hi=360),
    Param("psi0", -46.34, "deg", "initial rocker angle (direction C→B)", lo=-360, hi=360),
    Param("omega0", 43.5, "rad/s", "initial crank rate", lo=-1e4, hi=1e4),
    Param("rocker_rate0", 0.0, "rad/s", "initial rocker rate", lo=-1e4, hi=1e4),
    Param("gravity", 9.81, "m/s²", "gravity along −y", lo=0.0, hi=1e3),
    positive("slider_stiffness", 1e6, "N/m", "slider spring about its initial position",
             hi=1e12),
    Param("slider_damping", 0.0, "N·s/m", "slider damper", lo=0.0, hi=1e9),
    Param("gear_ratio", 1.0, "", "motor-to-crank reduction u (u = 0 disconnects the motor)",
          lo=0.0, hi=1e3),
    # An explicit choice, continuous in u: the crank carries u²·rotor_inertia. The paper (u = 1)
    # applies the motor characteristic to the crank without the rotor, hence default 0; the
    # 4A80B4U3's own rotor is 0.0033 kg·m². Continuous, so that no golden is sized across a
    # jump (joining only at u ≠ 1 would make u = 1 + 1e-12 add 9.7 % of J1).
    Param("rotor_inertia", 0.0, "kg·m²", "motor rotor inertia reflected to the crank as "
          "u²·rotor_inertia (0: the paper's model; the 4A80B4U3 rotor is 0.0033)",
          lo=0.0, hi=1e3),
    Param("mass_model", "paper", "", "paper: masses lumped at the joints (eq. 21); midpoint: "
          "link masses at mid-points", kind="choice", choices=("paper", "midpoint")),
    Param("assembly", 1, "", "loop-closure root: 1 x_B > x_A, 2 the other", kind="choice",
          choices=(1, 2)),
)

CHANNELS = phys.CHANNELS     # each built once, by compare.physics.press.channels
# the acceptance numbers, as absolute bounds
# Every solver's numerical error is in its error estimate — lagrange-partial's 0.1° central
# differences (its KNOBS), MuJoCo's constraint time constant tied to its step (its KNOBS: RK4
# sampling the stiff constraint at dt/tc = 1/4 left crank_accel 0.146 off the rigid model at
# every step) — so the allowances are 1e-9 of scale (the estimates' own inaccuracy) and one
# model difference: MuJoCo's soft loop closure (`mujoco_soft_closure`).
MUJOCO_IMPEDANCE = 0.9999   # MuJoCo's solimp d (its press leaf; tests check they agree)
SOFT_CLOSURE_SAFETY = 3.0


def _weight_at_rest(params) -> float:
    """MuJoCo's diagonal estimate of a connect row: the mean translational inverse inertia of
    the two bodies it joins — the rocker's centre of mass in the tree at rest (qpos0: the
    chain straight along x) and the slider — at their centres of mass."""
    chain = phys.chain_jacobians(params, [0.0, 0.0, 0.0])
    M = sum(m * Jc.T @ Jc + J * np.outer(np.arange(3) < len(lens), np.arange(3) < len(lens))
            for m, J, Jc, lens in chain)
    Jr = chain[-1][2]
    return float(np.trace(Jr @ np.linalg.solve(M, Jr.T)) / 3 + 1 / (3 * float(params["m4"])))


def mujoco_soft_closure(params):
    """MuJoCo's loop is closed by a soft constraint of impedance d: at the start, where the
    loop's violation is 0, its constraint force solves (A + R) f = −a₀, R = (1 − d)/d × the
    engine's diagonal estimate of A, against the rigid A f = −a₀ — crank_accel moves by
    `phys.soft_closure_offset` (∝ 1 − d, measured exactly so by a helper at d = 0.9999 … 0.99).
    MuJoCo's estimate (body weights at qpos0) is not reproduced exactly: the offset with diag A
    and with the weights at rest came to 0.43–1.26 and 0.52–0.83 of the measured one over 11
    sets; the allowance is SOFT_CLOSURE_SAFETY × the larger (1.6–3.8 × measured), in rad/s²
    on top of the 1e-9 of scale every pair has."""
    M, _, G, _ = phys.open_tree_at_start(params)
    A = G @ np.linalg.solve(M, G.T)
    largest = max(abs(phys.soft_closure_offset(params, MUJOCO_IMPEDANCE, d))
                  for d in (np.diag(A), np.full(2, _weight_at_rest(params))))
    return ("rel+abs", 1e-9, SOFT_CLOSURE_SAFETY * largest)


TOLERANCES = {**{c: 1e-9 for c in ("crank_angle", "crank_rate", "crank_accel", "rocker_angle",
                                   "slider_x")},
              "by_solver": {"mujoco": {"crank_accel": mujoco_soft_closure}}}


def _check(p):
    """The loop must close at the start (the shared loop closure): B = C + l3(cos ψ, sin ψ) with
    C on the x axis needs |y_B − y_A| ≤ l2 for the rod to reach from A (rejected here, before
    anything runs)."""
    xA, yA, xB, yB, xC, ok = phys.loop_closure(math.radians(p["phi0"]), math.radians(p["psi0"]),
                                               p["l1"], p["l2"], p["l3"], 1.0)
    if not ok:
        gap = abs(yB - yA)
        raise BadInput(f"l2: the rod ({p['l2']:g} m) cannot close the loop at phi0 = "
                       f"{p['phi0']:g} deg, psi0 = {p['psi0']:g} deg (needs ≥ {gap:.4g} m)")


PRESS_LEAVES = {"lagrange-partial": "custom_models.press.partial",
                "lagrange-exact": "custom_models.press.exact",
                "exudyn": "reference_models.exudyn.press",
                "mujoco": "reference_models.mujoco.press"}


def draw_press(rec, params, traj, color, offset):
    """Crank O→A, rod A→B, rocker B→C as one line strip with the joints as points, the slider
    at C on its guide (the x axis), from the crank and rocker angles through the shared loop
    closure. While the rocker is locked onto the slider the linkage turns dark (press-cycle)."""
    import rerun as rr
    phi, psi = traj.channels["crank_angle"], traj.channels["rocker_angle"]
    rows = np.nonzero(np.isfinite(phi) & np.isfinite(psi))[0]
    l1, l2, l3 = params["l1"], params["l2"], params["l3"]
    sigma = phys.assembly_sign(params)
    pts = np.full((len(rows), 4, 3), np.nan)
    for k, i in enumerate(rows):
        xA, yA, xB, yB, xC, _ = phys.loop_closure(float(phi[i]), float(psi[i]), l1, l2, l3,
                                                  sigma)
        pts[k] = [[0, 0, 0], [xA, yA, 0], [xB, yB, 0], [xC, 0, 0]]
    pts += offset
    t = traj.t[rows]
    t_lock = _extra_scalar(traj, "t_lock")
    locked = np.zeros(len(rows), bool)
    if t_lock is not None and phys.is_cycle(params):
        locked = (t >= t_lock) & (t < params["release_after"])
    dark = tuple(int(c * 0.35) for c in color)
    colors = [dark if x else tuple(color) for x in locked]
    ent = f"world/{traj.solver}"
    xc = pts[:, 3, 0]
    rec.log(f"{ent}/guide", rr.LineStrips3D([[[np.nanmin(xc) - l1, 0, 0],
                                              [np.nanmax(xc) + l1, 0, 0]]], radii=2e-4,
                                            colors=[(128, 128, 128)]), static=True)
    idx = [rr.TimeColumn("sim_time", duration=t)]
    rec.send_columns(f"{ent}/links", indexes=idx,
                     columns=rr.LineStrips3D.columns(strips=list(pts), colors=colors,
                                                     radii=[5e-4] * len(rows))
                     .partition([1] * len(rows)))
    rec.send_columns(f"{ent}/joints", indexes=idx,
                     columns=rr.Points3D.columns(positions=pts.reshape(-1, 3),
                                                 colors=np.repeat(colors, 4, axis=0),
                                                 radii=[1e-3] * (4 * len(rows)))
                     .partition([4] * len(rows)))
    box = [[4e-3, 2e-3, 2e-3]] * len(rows)
    rec.send_columns(f"{ent}/slider", indexes=idx,
                     columns=rr.Boxes3D.columns(centers=pts[:, 3], half_sizes=box,
                                                colors=colors).partition([1] * len(rows)))


# The spec's extremes (scene-press.md). The linear-acceleration cases use the quiet press of
# tests/physics/test_press_custom.py (slider 1e9 N/m, motor disconnected), whose fastest period
# T_min = 3.0786 ms comes from the linearised modes: the Newmark β = 1/6 limit is
# h = (√3/π)·T_min = 0.5513·T_min.
_QUIET = {"slider_stiffness": 1e9, "gravity": 0.0, "gear_ratio": 0.0, "omega0": 0.0,
          "rocker_rate0": 0.01}
_T_MIN = 3.0786032e-3
_CUSTOM = ("lagrange-exact", "lagrange-partial")


def _linacc(ratio):
    h = ratio * _T_MIN
    return {**_QUIET, "output_dt": h, "t_end": 300 * h}


# The step (and, for lagrange-partial, the finite-difference step of its partial systems) at
# which each solver's energy balance closes to the 1e-6 bound with ≥ 2× margin — the largest
# step that does, as a user would pick it; the default steps leave a drift that falls with the
# step (each run's own estimate says so: discretisation error, not a wrong model). Drift of the
# energy scale measured default → here (dt is snapped to divide the 1.25 ms output step):
# slider 1e9 N/m (press and press-cycle alike): lagrange-partial 4.0e-5 → 4.0e-7 at 1e-6 s and
#   0.01° (as dt²; with the paper's 0.1° virtual step the drift stops near 3e-6 — 4.4e-6 at
#   2e-6 s, 3.4e-6 at 1e-6 s — the O(Δ²) model error of the partial systems; 2e-6 s with 0.01°
#   leaves 1.6e-6); Exudyn 1.2e-4 → 4.7e-7 at 1.25e-6 s (falls as dt²);
#   MuJoCo 3.4e-3 / 5.5e-3 (press-cycle) → 2.6e-7 / 3.4e-7 at 2.5e-6 s (as dt^2.6: the soft
#   loop constraint's time constant follows the step; 3.1e-6 s leaves 5.9e-7 in press-cycle).
_RESOLVE_SLIDER = {"dt": {"lagrange-partial": 1e-6, "exudyn": 1.25e-6, "mujoco": 2.5e-6},
                   "dphi_deg": {"lagrange-partial": 0.01}, "dpsi_deg": {"lagrange-partial": 0.01}}
# toggle: Exudyn 2.6e-5 → 2.9e-7 at 6.25e-6 s without numerical damping (spectral radius 1;
# 5.9e-7 at 1e-5 s; at 0.8 generalized-α bleeds energy steadily, still 4.5e-7 at 2.5e-6 s, a
# 400 000-step run); MuJoCo 7.9e-6 → 2.2e-7 at 2.78e-5 s (5.1e-7 at 3.1e-5 s)
_RESOLVE_TOGGLE = {"dt": {"exudyn": 6.25e-6, "mujoco": 2.78e-5}, "spectral_radius": {"exudyn": 1.0}}
# motor stall: lagrange-partial 2.5e-6 → 4.0e-7 at 4e-6 s and 0.01° (2.5e-6 at any step with
# 0.1°: the stall's drift is the partial systems' model error, as above); MuJoCo 1.0e-4 → 3.3e-7
# at 2e-5 s (5.1e-7 at 2.5e-5 s)
_RESOLVE_STALL = {"dt": {"lagrange-partial": 4e-6, "mujoco": 2e-5},
                  "dphi_deg": {"lagrange-partial": 0.01}, "dpsi_deg": {"lagrange-partial": 0.01}}

# 100 crank revolutions (6 s, 113 revolutions): the engines' drifts fall with the step, but
# 1e-6 needs runs of minutes (each check is that run plus its estimate's 2·dt and dt/2 runs).
_LONG_RUN = {
    "exudyn": "its energy drift falls as dt² (2.7e-4 of the energy scale at its default "
              "2e-5 s, 6.8e-5 at 1e-5 s; without numerical damping it fails to converge at "
              "0.9 s, spectral radius 0.95 / 0.98 drift more, 5.1e-4 / 5.2e-4): 1e-6 with "
              "margin needs dt ≈ 1.7e-6 s, 3.5 million steps of a per-step Python callback, "
              "several minutes per run",
    "mujoco": "its energy drift falls as dt^2.9 (2.2e-3 of the energy scale at its default "
              "1e-4 s, 3.1e-4 at 5e-5 s, 4.1e-5 at 2.5e-5 s, 7.9e-7 at 6.25e-6 s in a 6-min run "
              "on a loaded machine — the soft loop constraint's time constant follows the "
              "step): 1e-6 with margin needs dt ≈ 5e-6 s, 1.2 million steps, several minutes "
              "per run"}

PRESS_EXTREMES = (
    Extreme("toggle: rod vertical", {"t_end": 1.0}, _RESOLVE_TOGGLE, slow=("exudyn",),
            why="left idle the rod reaches the vertical, where the (φ, ψ) chart is singular: "
                "the minimal-coordinate solvers must stop with that reason; full-coordinate "
                "engines may pass (at the step that resolves the 1-s run, Exudyn without "
                "numerical damping; its 160 000 steps only with --all)"),
    Extreme("slider 1e9 N/m", {"slider_stiffness": 1e9}, _RESOLVE_SLIDER, bound=1e-6,
            why="very stiff slider (T_min 3 ms; every solver but lagrange-exact at the step "
                "that resolves it, lagrange-partial with 0.01° partial systems)"),
    Extreme("linear acceleration 0.54·T_min", _linacc(0.54),
            {"integrator": "linacc", "dt": 0.54 * _T_MIN}, bound=1e-6, solvers=_CUSTOM,
            why="just below the limit 0.5513·T_min: stable (the leaf's growth check stays "
                "quiet) but coarse — Newmark β = 1/6 weighs the potential by 1 − (ωh)²/12, so "
                "the energy balance is off by ~100 % of this quiet press's tiny energy and the "
                "adapter reports it 'too coarse'; above the limit the leaf reports "
                "'unstable'"),
    Extreme("linear acceleration 0.56·T_min", _linacc(0.56),
            {"integrator": "linacc", "dt": 0.56 * _T_MIN}, expect="status", solvers=_CUSTOM,
            why="just above the limit: must end unstable, never ok"),
    Extreme("100 crank revolutions", {"slider_stiffness": 1e8, "slider_damping": 1e5,
                                      "t_end": 6.0, "output_dt": 0.01}, bound=1e-6, slow=True,
            known_failures=_LONG_RUN,
            why="long-run drift (stiff damped slider, 113 revolutions): lagrange-exact closes "
                "the balance (2.6e-7); lagrange-partial's linear-acceleration step ends 'too "
                "coarse'; the engines' drifts fall with the step but the step that meets the "
                "bound makes each run minutes long (declared known failures)"),
)


# `xval calibrate`: the linkage within ±10 % of the paper's (a crank twice as long reaches the
# rod's vertical within 0.02 s), the rest by the default rule; where the rod still comes
# within `singular_tol` of the vertical the custom solvers' (φ, ψ) chart is singular and they
# stop (the extreme "toggle: rod vertical"), which the engines' redundant coordinates pass
# (press-cycle, `xval calibrate press-cycle --seed 2468` set 19: the engines' rod 0.6° from
# the vertical at 2.5 ms; seed 1234 set 4: 4.4° at 6.25 ms, lagrange-partial's 0.1° stencil
# reaching the double root from 6.3°)
_VERTICAL = ("the rod reaches the vertical, where the (φ, ψ) chart is singular (lagrange-partial: "
             "comes within its stencil's reach of it)", "singular:")
OUTSIDE = {"lagrange-partial": _VERTICAL, "lagrange-exact": _VERTICAL}
CALIBRATION = Calibration(
    region={"l1": (0.0135, 0.0165), "l2": (0.036, 0.044), "l3": (0.027, 0.033),
            "phi0": (-70.0, -58.0), "psi0": (-51.0, -42.0)},
    fixed={"t_end": 0.02}, outside=OUTSIDE,
    # Exudyn's own finer runs grow noisier in crank_accel (tests/verdicts/test_coverage.py)
    truth={"exudyn": "lagrange-exact"}, campaign=2)


PRESS = TimeScene(
    name="press", title="Crank–rocker press with slider, idle run (2 DOF)", source=SOURCE,
    leaves=PRESS_LEAVES,
    params=_MECHANISM + (positive("t_end", 0.05, "s", "horizon (paper: 0.05 s)", hi=1e3),
                         positive("output_dt", 0.00125, "s", "output grid (paper: 40 steps)")),
    channels=CHANNELS, tolerances=TOLERANCES, key_channel="crank_rate", check=_check,
    reference_solvers=("lagrange-exact", "mujoco"),
    draw_3d=draw_press, view_channels=("crank_rate", "rocker_angle", "slider_x"),
    extremes=PRESS_EXTREMES,
    campaign_cases=({"name": "press"},), calibration=CALIBRATION,
    notes="Energy balance = kinetic + spring + gravity − motor work + damper loss.")

PRESS_CYCLE = TimeScene(
    name="press-cycle",
    title="Press cycle: idle → rocker locks onto the slider → loaded stroke → release",
    source=SOURCE, leaves=PRESS_LEAVES,
    params=_MECHANISM + (
        Param("lock_after", 0.01, "s", "earliest lock time", lo=0.0, hi=1e3,
              physical=False),     # a threshold: the lock then waits for lock_angle
        Param("lock_angle", -48.0, "deg", "rocker angle at which it locks onto the slider",
              lo=-360, hi=360),
        Param("press_force", 2000.0, "N", "working load F resisting the slider while locked "
              "(−F·tanh(v/press_force_vreg))", lo=0.0, hi=1e8),
        positive("press_force_vreg", 0.01, "m/s", "velocity scale of the load's sign change"),
        Param("release_after", 0.045, "s", "the lock opens at this time", lo=0.0, hi=1e3),
        positive("t_end", 0.06, "s", "horizon", hi=1e3),
        positive("output_dt", 0.00125, "s", "output grid")),
    channels=CHANNELS, tolerances=TOLERANCES,
    key_channel="crank_rate", check=_check, findings=lambda p, trs: cycle_findings(p, trs),
    draw_3d=draw_press, view_channels=("crank_rate", "rocker_angle", "slider_x"),
    extremes=(
        Extreme("motor stall: load 50 kN", {"press_force": 5e4}, _RESOLVE_STALL, bound=1e-6,
                why="the working load overpowers the motor (25× the default): the crank "
                    "stalls and is thrown back (lagrange-partial and MuJoCo at the step that "
                    "resolves it, lagrange-partial with 0.01° partial systems)"),
        Extreme("slider 1e9 N/m", {"slider_stiffness": 1e9}, _RESOLVE_SLIDER, bound=1e-6,
                why="stiff slider through lock and release (as press's: every solver but "
                    "lagrange-exact at the step that resolves it)"),
    ),
    campaign_cases=({"name": "press-cycle"},),
    # as press's: Exudyn's own dt/16 and dt/32 runs differ by 0.07 in crank_accel, 3× the
    # run's distance to either (the index-3 accelerations carry Newton's tolerance / dt²)
    calibration=Calibration(truth={"exudyn": "lagrange-exact"}, outside=OUTSIDE, campaign=2),
    map_observables={"lock_time": (lambda p, tr: lock_time(p, tr), "s",
                                   "the instant the rocker locks onto the slider")},
    # lock instant over the slider's stiffness; where the rocker stops locking (between 1e6
    # and 1e7 N/m at the defaults) bracketed by the custom solvers, checked by the engines
    maps=(MapSpec("lock-vs-slider-stiffness", x="slider_stiffness=1e5:1e7", resolution=1e-2,
                  coarse=(9, 1), observable="lock_time"),),
    notes="The lock is a plastic impact located as a state event; energy_balance includes the "
          "press work and the energy lost at the lock.")


def _extra_scalar(tr, *names):
    for n in names:
        if n in tr.extra:
            v = float(np.ravel(tr.extra[n])[0])
            return v if np.isfinite(v) else None
    return None


def lock_time(params, tr):
    """The lock instant of one run [s], None when the rocker never locks."""
    return _extra_scalar(tr, "t_lock")


def cycle_findings(params, trajectories):
    """Lock instant and energy lost at the plastic lock, per solver, with their spread."""
    ok = [tr for tr in trajectories if tr.status == "ok"]
    t_lock = {tr.solver: lock_time(params, tr) for tr in ok}
    loss = {tr.solver: _extra_scalar(tr, "lock_energy_loss") for tr in ok}
    out = []
    found = {s: v for s, v in t_lock.items() if v is not None}
    if not found:
        return [Finding("t_lock", None, "s", "no lock happened inside [lock_after, "
                        "release_after) in any solver")]
    spread = max(found.values()) - min(found.values())
    out.append(Finding("t_lock", min(found.values()), "s", "lock at t = " + ", ".join(
        f"{s} {v:.10f} s" for s, v in found.items()) + f" (spread {spread:.1e} s)", at=found))
    lf = {s: v for s, v in loss.items() if v is not None}
    if lf:
        out.append(Finding("lock_energy_loss", min(lf.values()), "J",
                           "energy lost at the plastic lock: " + ", ".join(
                               f"{s} {v:.8f} J" for s, v in lf.items())
                           + f" (spread {max(lf.values()) - min(lf.values()):.1e} J)"))
    return out

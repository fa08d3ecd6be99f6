"""Thread unrolling from spools on a spinning hub: solar-sail blade deployment (seed 004;
spec scene-sail.md)."""
import functools

import numpy as np
from scipy.integrate import solve_ivp

from ..errors import BadInput
from ..physics import sail as phys
from .base import AllowanceCase, Calibration, Extreme, Finding, FormulaCheck, MapSpec, TimeScene
from .params import Param, positive

SOURCE = "seed 004 (constant-dimension spring–mass thread unwinding from a spool)"


def check(values):
    """The threads unroll under the spin's centrifugal tension: a hub at rest has none (the
    release law, formula 18 and the allowances all scale with Ω₀)."""
    if values["Omega0"] == 0:
        raise BadInput("Omega0: 0 rad/s leaves the threads without centrifugal tension "
                       "(a deployment needs a spinning hub; give a non-zero initial spin)")


def sail_findings(params, trajectories):
    """Hub rate against the rebuilt formula 18, angular-momentum drift, tip-angle statistics."""
    ok = [tr for tr in trajectories if tr.status == "ok"]
    out = []
    for tr in ok:
        f18 = tr.extra.get("hub_rate_formula18")
        w = tr.channels["hub_rate"]
        parts = []
        if f18 is not None and len(f18) == len(w):
            dev = np.max(np.abs(w - f18) / np.abs(f18))
            parts.append(f"max |Ω − Ω₁₈|/Ω₁₈ = {dev:.2e} (rebuilt formula 18 with L_c and tip "
                         f"masses; the remainder is the lumping of n = {params['n']} nodes)")
        am = tr.invariants.get("angular_momentum")
        if am is not None:
            parts.append(f"angular-momentum drift {am:.1e}")
        tip = tr.channels["tip_angle"]
        late = tr.t >= min(20.0, tr.t[-1] / 2)
        parts.append(f"tip angle mean {np.mean(tip[late]):.4f} rad, std {np.std(tip[late]):.4f} "
                     f"rad over t ≥ {tr.t[late][0]:.3g} s")
        out.append(Finding(f"sail_{tr.solver}", am, "", f"{tr.solver}: " + "; ".join(parts)))
    t_full = params["L"] / (params["r"] * params["omega_spool"])
    if ok and t_full <= ok[0].t[-1]:
        out.append(Finding("end_of_deployment", t_full, "s", f"the whole blade is out at "
                           f"t = L/(r·ω) = {t_full:.6g} s: the spool stops (last node "
                           f"{params['last_node']})", at={tr.solver: t_full for tr in ok}))
    return out


MAX_FRAMES = 600     # a long deployment is drawn at ≤ 600 instants (stated recording size)


def peak_tip_angle(params, tr):
    """Largest |tip angle| over the run [rad]: how far the blade lags the hub's spin."""
    return float(np.nanmax(np.abs(tr.channels["tip_angle"])))


def deployment_time(params, tr):
    """When the deployed (stretched) length first comes within 1e-4 of the blade length [s]
    (None: not within the run); the payout law makes it L/(r·ω) in every solver. Not L
    itself: the loaded thread's stretch (~1e-6 of L, measured at ω = 7 rad/s) moves the
    arc length about L by more than a tighter threshold."""
    i = np.nonzero(tr.channels["deployed_length"] >= params["L"] * (1 - 1e-4))[0]
    return float(tr.t[i[0]]) if len(i) else None


def draw_sail(rec, params, traj, color, offset):
    """Hub disk, both spools and both blades' threads (the second blade is the first turned by
    π: the blades are symmetric), from the shared kinematic output `thread_shape` (released
    nodes tip → boundary, then the departure point Q). Long runs are decimated to MAX_FRAMES
    instants."""
    import rerun as rr
    shape, psi = traj.extra.get("thread_shape"), traj.extra.get("hub_angle")
    if shape is None or psi is None:
        return
    ent = f"world/{traj.solver}"
    rows = np.nonzero(np.isfinite(psi))[0]
    rows = rows[:: max(1, int(np.ceil(len(rows) / MAX_FRAMES)))]
    Lc, r = params["L_c"], params["r"]
    rec.log(f"{ent}/hub", rr.Cylinders3D(lengths=[0.2 * r], radii=[0.8 * Lc],
                                         centers=[offset], colors=[color]), static=True)
    strips, spools, times = [], [], traj.t[rows]
    for i in rows:
        pts = shape[i][np.isfinite(shape[i]).all(axis=1)]
        turn = np.array([[-1.0, -1.0, 1.0]])                    # R_z(π)
        strips += [pts + offset, pts * turn + offset]
        q = np.array([Lc * np.cos(psi[i]), Lc * np.sin(psi[i]), r])
        spools += [q + offset, q * turn[0] + offset]
    rec.send_columns(f"{ent}/thread", indexes=[rr.TimeColumn("sim_time", duration=times)],
                     columns=rr.LineStrips3D.columns(strips=strips,
                                                     colors=[color] * len(strips))
                     .partition([2] * len(rows)))
    rec.send_columns(f"{ent}/spools", indexes=[rr.TimeColumn("sim_time", duration=times)],
                     columns=rr.Points3D.columns(positions=np.array(spools),
                                                 colors=[color] * len(spools))
                     .partition([2] * len(rows)))


def _angular_momentum_held(params, tr):
    """Conservation law: no external moment acts on hub + threads."""
    drift = tr.invariants.get("angular_momentum", np.inf)
    return drift <= 1e-8, drift, f"angular momentum drift {drift:.1e} (bound 1e-8)"


# The spec's extremes (scene-sail.md). The paper's own model (`thread-spool`) is left out: its
# release law does not conserve angular momentum by design (3e-3 over the deployment), which
# the regular comparisons report.
_CONSERVATIVE = ("thread-spool-conservative", "exudyn", "mujoco")
SAIL_EXTREMES = (
    Extreme("stiffness 1e9, explicit engines", {"stiffness": 1e9, "t_end": 0.2,
                                               "output_dt": 0.01},
            check=_angular_momentum_held, solvers=_CONSERVATIVE,
            why="the explicit engines must pick a ~1e-7 s step (or say they cannot)"),
    Extreme("damping 1e-6", {"damping": 1e-6, "t_end": 2}, check=_angular_momentum_held,
            solvers=_CONSERVATIVE, why="almost undamped thread"),
    Extreme("damping 10", {"damping": 10.0, "t_end": 2}, check=_angular_momentum_held,
            solvers=_CONSERVATIVE, why="overdamped springs (stiff damping term)"),
    Extreme("n 5", {"n": 5, "t_end": 2}, check=_angular_momentum_held, solvers=_CONSERVATIVE,
            why="coarse thread"),
    Extreme("n 200", {"n": 200, "t_end": 1}, check=_angular_momentum_held,
            solvers=_CONSERVATIVE, slow=True, why="fine thread (a 1e6 rad/s chain mode)"),
    Extreme("spool 10× faster", {"omega_spool": 35.0, "t_end": 2}, check=_angular_momentum_held,
            solvers=_CONSERVATIVE, why="fast deployment"),
    Extreme("light hub: spin reversal", {"J_hub": 4e-5, "n": 5, "omega_spool": 7.0,
                                         "t_end": 30}, check=_angular_momentum_held,
            solvers=_CONSERVATIVE, slow=True, why="yo-yo despin: the spin reverses"),
    Extreme("end of deployment, last node released",
            {"last_node": "released", "t_end": 150}, check=_angular_momentum_held,
            solvers=("thread-spool-conservative",), why="the blade flies free at 142.86 s"),
)


# Exudyn puts each released node `release_offset` = 1e-9 m radially beyond Q (its leaf's
# DEFAULT_SETTINGS; tests/verdicts/test_allowance_models.py checks the two agree) so that the new
# boundary spring never has length 0. The node then carries m_j(L_c + δ)·ΩL_c about the axis where
# the hub gave up m_j L_c²Ω: each release adds m_j δ L_c Ω to the angular momentum (both blades:
# twice), relative to H = J_eff Ω with J_eff = J_hub + 2L_c²Σm_j (Ω ≤ |Ω₀| after t = 0, so Ω cancels
# to an upper bound). Measured at 6 parameter sets to 1 % (docs/scenes/sail-deploy.md).
EXUDYN_RELEASE_OFFSET = 1e-9
RELEASE_OFFSET_SAFETY = 1.25


def release_offset_momentum(params):
    """Relative angular-momentum change Exudyn's release offset adds by t_end: 2δL_c Σ_{t_j <
    t_end} m_j / J_eff."""
    _, _, m, t_rel = phys.thread(params)
    released = m[t_rel < params["t_end"] - 1e-12].sum()
    J_eff = params["J_hub"] + 2 * params["L_c"] ** 2 * m.sum()
    return 2 * EXUDYN_RELEASE_OFFSET * params["L_c"] * released / J_eff


def exudyn_momentum_allowance(params):
    """The release offset's momentum × RELEASE_OFFSET_SAFETY (1.25: the formula met the
    deviation to 1–3 % at six sets; the Verlet round-off, ≤ 1e-14 of H over 2 s, is not in it;
    a wider factor costs the verdicts power — Exudyn's thread damping is seen through this
    channel only)."""
    return RELEASE_OFFSET_SAFETY * release_offset_momentum(params)


# The offset's effect on the tip angle is of second order: the released node starts with its
# Q-spring stretched by δ (rest length 0), and the stiff segment's vibration, energy ½kδ² a
# blade, leaves a slow swing of the lag behind. Exudyn's tip angle against its own run at δ/10
# (set 11 of seed 11: 1e-11, 1e-10, 1e-9, 4e-9, 1.6e-8 m give 2e-12, 9.7e-12, 1.4e-9, 2.3e-8,
# 3.7e-7 rad against MuJoCo) goes as δ² and, varying one parameter at a time there, as
# k¹·L_c¹·J_hub⁻¹·|Ω₀|⁻¹·(rω)⁻¹ (exponents 1.01, 1.03, −0.99, −1.02, −1.10), not with the node
# mass (0.04) nor Exudyn's step (0.01; a physical effect of the offset, not a numerical one):
#   Δθ ≈ k δ² L_c / (J_hub |Ω₀| r ω)  (two blades' ½kδ² over J_hub Ω, over the payout rate
#   r ω / L_c),
# measured 0.12–1.07 × the Exudyn–MuJoCo tip deviation over the 20 calibration sets of seed 11
# and the defaults at t_end 0.5 s (docs/scenes/sail-deploy.md); wide at a fast spin or a long
# L_c (Ω₀ 12: 0.11, L_c 0.2: 0.20). A scaling law fitted at one release, not derived: each
# later release is counted as one more such kick at Ω₀.
OFFSET_TIP_SAFETY = 1.5


def release_offset_tip(params):
    """The tip-angle deviation [rad] Exudyn's release offset δ leaves by t_end:
    (releases by t_end) × k δ² L_c / (J_hub |Ω₀| r ω)."""
    _, _, _, t_rel = phys.thread(params)
    kicks = int(np.sum(t_rel < params["t_end"] - 1e-12))
    return (kicks * params["stiffness"] * EXUDYN_RELEASE_OFFSET ** 2 * params["L_c"]
            / (params["J_hub"] * abs(params["Omega0"]) * params["r"] * params["omega_spool"]))


def exudyn_tip_allowance(params):
    """Exudyn against MuJoCo (one model, the offset the difference): the offset's tip-angle
    deviation × OFFSET_TIP_SAFETY."""
    return ("abs", OFFSET_TIP_SAFETY * release_offset_tip(params))



# The paper's model (`thread-spool`) against a conservative one. It leaves the stored thread
# out of the hub inertia, so each change dΩ of the spin misses the 2 L_c² M_stored dΩ that the
# stored thread carries: ΔH(t) = 2 L_c² ∫ M_stored dΩ (phys.stored_thread_momentum); each later
# release turns the node's r·ω along the trailing thread, 2 m_j L_c r ω sinθ more. The spin
# then differs by ΔH/I(t), and the tip's lag, tan θ = 2 r ω/(Ω L_c) (phys.root_lag), by
# sinθ cosθ ΔΩ/Ω. Evaluated on the lumped formula 18's Ω(t); measured at 6 sets
# (docs/scenes/sail-deploy.md): spin and momentum to ≤ 10 %, the tip to a factor 2 (the change
# of the despin rate's Euler force on the lag is not in it).
PAPER_SAFETY = 2.0
PAPER_TIP_SAFETY = 2.5


def paper_release_deviation(params):
    """Closed-form deviation of the paper's model from a conservative one by t_end:
    (hub rate / |Ω₀|, angular momentum / H₀, tip angle [rad])."""
    return _paper_release_deviation(tuple(params[k] for k in _PAPER_KEYS))


_PAPER_KEYS = ("J_hub", "rho_L", "L", "L_c", "r", "Omega0", "omega_spool", "tip_mass", "n",
               "t_end")


@functools.lru_cache(maxsize=256)          # three allowances of one run share it
def _paper_release_deviation(values):
    params = dict(zip(_PAPER_KEYS, values))
    t, omega, dH, H0 = _paper_momentum(params)
    Lc, rw = params["L_c"], params["r"] * params["omega_spool"]
    d_omega = dH * omega / H0                       # ΔH / I(t), I = H0/Ω
    lag = np.arctan2(2 * rw, np.abs(omega) * Lc)
    tip = np.sin(lag) * np.cos(lag) * np.abs(d_omega / omega)
    return (float(np.max(np.abs(d_omega))) / abs(params["Omega0"]),
            float(np.max(np.abs(dH))) / abs(H0), float(np.max(tip)))


def _paper_momentum(params):
    """(t: the release grid to t_end, the lumped formula 18's Ω on it, ΔH(t) of the paper's
    model against a conservative one, H₀)."""
    t = phys.release_grid(params, params["t_end"])
    omega = phys.formula18_discrete(params, t)
    n, _, m, t_rel = phys.thread(params)
    Lc, rw, sign = params["L_c"], params["r"] * params["omega_spool"], np.sign(params["Omega0"])
    dH = phys.stored_thread_momentum(params, t, omega)
    for j in range(1, n):                   # the velocity turn of each later release
        if t_rel[j] < params["t_end"] - 1e-12:
            lag = phys.root_lag(params, np.interp(t_rel[j], t, omega))
            dH[t >= t_rel[j]] -= sign * 2 * m[j] * Lc * rw * np.sin(lag)
    H0 = (params["J_hub"] + 2 * Lc**2 * m.sum()) * params["Omega0"]
    return t, omega, dH, H0


def paper_hub_shift(params, t_out):
    """Ω of the paper's model minus a conservative one's on `t_out` [rad/s], signed: ΔH/I(t)
    (measured: the difference to 1–5 %, docs/scenes/sail-deploy.md)."""
    t, omega, dH, H0 = _paper_momentum(params)
    return np.interp(t_out, t, dH * omega / H0)


def paper_hub_allowance(params):
    return PAPER_SAFETY * paper_release_deviation(params)[0]


def paper_momentum_allowance(params):
    return PAPER_SAFETY * paper_release_deviation(params)[1]


# The tip's swing. Until the second release (t_rel[1], ≥ 1.3 s over the calibration region) the
# released thread is the tip node on one taut segment of length ℓ = rωt hinged at Q, paid out
# along itself: its lag θ (the tip angle) obeys, in the hub frame,
#   ℓθ̈ + 2ℓ̇θ̇ = −Ω²L_c sinθ + 2Ωℓ̇ + Ω̇(ℓ + L_c cosθ)
# (centrifugal restoring moment, Coriolis push of the payout, the despin's Euler force), from
# θ ≈ Ωt at release. Its equilibrium is the quasi-steady lag above; it swings about it with
# ω_n = Ω√(L_c/ℓ), so at short horizons the tip is still overshooting (1.05–1.4 × the steady
# lag at 0.5 s) and the steady formula's ∂θ/∂Ω misses the deviation by 0.1–4.7 ×. The paper's
# spin Ω + ΔΩ (ΔΩ = ΔH/I as above) moves θ by δθ, the equation's variation, integrated along:
# measured 0.67–1.29 × the deviation at 26 sets (the 20 calibration sets and PAPER_SETS;
# docs/scenes/sail-deploy.md), its θ within 0.55 % of thread-spool-conservative's peak tip angle.
PAPER_SWING_SAFETY = 2.0


def paper_tip_swing(params):
    """max |δθ| [rad] of the tip's swing (the equation above) under the paper's spin change,
    up to t_end or the second release, whichever comes first."""
    return _paper_tip_swing(tuple(params[k] for k in _PAPER_KEYS))


def _swing_end(params):
    n, _, _, t_rel = phys.thread(params)
    return min(params["t_end"], t_rel[1]) if n > 1 else params["t_end"]


@functools.lru_cache(maxsize=256)
def _paper_tip_swing(values):
    params = dict(zip(_PAPER_KEYS, values))
    t_stop = _swing_end(params)
    return float(np.max(np.abs(tip_swing(params, np.linspace(0.0, t_stop, 2001))[1])))


def tip_swing(params, t_out):
    """(θ, δθ) [rad] on `t_out` (within the swing: ≤ the second release): the tip's lag by the
    equation above on formula 18's spin, and its variation under the paper's ΔΩ."""
    t_stop = float(np.max(t_out))
    t, omega, dH, H0 = _paper_momentum({**params, "t_end": t_stop})
    sign, Lc = np.sign(params["Omega0"]), params["L_c"]
    rw = params["r"] * params["omega_spool"]
    W, dW = sign * omega, sign * dH * omega / H0          # |Ω| and its change
    Wd, dWd = np.gradient(W, t), np.gradient(dW, t)

    def rhs(s, y):
        th, thd, dth, dthd = y
        w, wd, dw, dwd = (np.interp(s, t, f) for f in (W, Wd, dW, dWd))
        ell = rw * s
        acc = -w * w * Lc * np.sin(th) + 2 * w * rw + wd * (ell + Lc * np.cos(th)) - 2 * rw * thd
        dacc = (-(w * w * np.cos(th) + wd * np.sin(th)) * Lc * dth
                - 2 * w * dw * Lc * np.sin(th) + 2 * dw * rw
                + dwd * (ell + Lc * np.cos(th)) - 2 * rw * dthd)
        return [thd, acc / ell, dthd, dacc / ell]

    t0 = 1e-6 * t_stop                                    # θ ≈ Ωt at release (ℓ → 0)
    sol = solve_ivp(rhs, (t0, t_stop), [W[0] * t0, W[0], 0.0, 0.0], method="DOP853",
                    rtol=1e-10, atol=1e-14, dense_output=True)
    y = sol.sol(np.clip(t_out, t0, t_stop))
    return y[0], y[2]


def paper_tip_allowance(params):
    """PAPER_SWING_SAFETY × the swing's deviation; past the second release (more than one
    segment out: no single swing) also the steady lag's, × PAPER_TIP_SAFETY."""
    swing = PAPER_SWING_SAFETY * paper_tip_swing(params)
    n, _, _, t_rel = phys.thread(params)
    if n < 2 or params["t_end"] <= t_rel[1]:
        return ("abs", swing)
    return ("abs", max(swing, PAPER_TIP_SAFETY * paper_release_deviation(params)[2]))


PAPER_ALLOWANCES = {"hub_rate": paper_hub_allowance, "tip_angle": paper_tip_allowance,
                    "angular_momentum": paper_momentum_allowance}


# The deployed length. The paper's Q-damper takes Q's velocity to be the departure velocity
# r ω e_x [8, 9], so its force differs from the conservative damper's by up to d r ω: on a
# steadily lagging segment d r ω (1 − cos θ), and on the Q-spring's ringing (~1e5 rad/s)
# more, where the step resolves it; the spring stretches by that over c. And the paper's
# spin change ΔΩ/Ω (paper_release_deviation) moves the centrifugal stretch m₀Ω²(L_c + ℓ)/c by
# twice that. At the scene's step (ringing unresolved) the steady term with the swing's
# largest lag was 1.00–1.21 × the deviation at 13 sets; resolved (dt/512) the deviation is
# 0.86–89 × that (seed 2026 set 7: 1.2e-11 m against 1.3e-13); the full d r ω / c is
# 2.1–25 × it at five sets but 0.48 at seed 2026 set 7 (1.16e-11 m): the ringing's damping is
# not modelled (docs/scenes/sail-deploy.md). The allowance is that bound; the verdicts rest on
# the runs' summed bands, 7e-10 m and more even at dt = 2e-6.
def paper_length_allowance(params):
    """|Δ deployed length| [m] of the paper's model against a conservative one, bounded
    (above)."""
    c, rw = params["stiffness"], params["r"] * params["omega_spool"]
    _, _, m, _ = phys.thread(params)
    out = min(rw * params["t_end"], params["L"])
    centrifugal = m[0] * params["Omega0"] ** 2 * (params["L_c"] + out) / c
    return ("abs", params["damping"] * rw / c
            + 2 * centrifugal * paper_release_deviation(params)[0])


# Formula 18 against every solver's hub rate (issue 47, item 7). The reference is the lumped
# formula (`phys.formula18_discrete`: the models' own n nodes; the continuous formula differs by
# the lumping, 1e-3 of Ω at 2 s, 10 × the effect judged). What it neglects of every model: the
# thread's quasi-steady lag θ (`phys.formula18_lag`: shorter radii, the payout's velocity along
# the trailing thread, θ set by centrifugal pull, Coriolis push and the despin's Euler force);
# the paper's model adds its release law's signed shift (`paper_hub_shift`). Measured over 18
# calibration sets and 10 more, short runs and full deployments (docs/scenes/sail-deploy.md):
# the lag's closed form is 0.90–1.11 × the deviation, so LAG_SAFETY 2. Where the lag has no
# quasi-steady state (|x| > LAG_DOMAIN: a fast payout on a slow hub, the thread folds back;
# L_c = 0) the formula states no error (inconclusive; 2 of 20 calibration sets, seed 0).
LAG_SAFETY = 2.0
LAG_DOMAIN = 0.9


def formula18_error(params, t, solver):
    """Formula 18's own error against `solver`'s model over `t`: LAG_SAFETY × max |Ω_lag −
    Ω₁₈| [rad/s] (for `thread-spool` with its release law's shift added), or why it states
    none."""
    omega, x = phys.formula18_lag(params, t)
    worst = float(np.max(np.abs(x)))
    if not worst <= LAG_DOMAIN:
        return (f"the thread has no quasi-steady lag (|x| = {worst:.3g} > {LAG_DOMAIN:g}: "
                "Coriolis push beyond the centrifugal and Euler restoring moments)")
    shift = omega - phys.formula18_discrete(params, t)
    if solver == "thread-spool":                # its release law shifts Ω further (signed)
        shift = shift + paper_hub_shift(params, t)
    return LAG_SAFETY * float(np.max(np.abs(shift)))


SAIL = TimeScene(
    name="sail-deploy",
    title="Two-blade heliogyro: threads unrolling from spools on a spinning hub",
    source=SOURCE, leaves={"thread-spool": "custom_models.sail.thread_spool",
            "thread-spool-conservative": "custom_models.sail.thread_spool",
            "exudyn": "reference_models.exudyn.sail", "mujoco": "reference_models.mujoco.sail"},
    params=(
        positive("J_hub", 0.004, "kg·m²", "spacecraft inertia about the spin axis"),
        positive("rho_L", 0.000735, "kg/m", "blade linear density"),
        positive("L", 5.0, "m", "blade length"),
        Param("L_c", 0.05, "m", "spin axis to spool (departure point)", lo=0.0, hi=100.0),
        positive("r", 0.01, "m", "spool radius"),
        Param("Omega0", 6.0, "rad/s", "initial spin", lo=-1e4, hi=1e4),
        positive("omega_spool", 3.5, "rad/s", "unrolling rate (deployment takes L/(r·ω))"),
        Param("tip_mass", 0.0005, "kg", "mass at each blade tip", lo=0.0, hi=1e3),
        Param("n", 20, "", "nodes per blade (paper: 20 and 40)", kind="int", lo=2, hi=2000),
        positive("stiffness", 1e7, "N/m", "thread spring stiffness (paper: 1e7…1e9)", hi=1e13),
        Param("damping", 1e-3, "N·s/m", "thread damping (paper: 1e-6…1)", lo=0.0, hi=1e6),
        Param("last_node", "attached", "", "at full payout t = L/(r·ω) the spool stops and the "
              "last node stays tied to the spool (attached) or leaves it (released: the blade "
              "flies free)", kind="choice", choices=("attached", "released")),
        positive("t_end", 142.9, "s", "horizon (full deployment L/(r·ω) = 142.857 s)", hi=1e5),
        positive("output_dt", 0.05, "s", "output grid"),
    ),
    channels=phys.CHANNELS,     # each built once, by compare.physics.sail.channels
    # Modelling allowances, whole deployment (t_end > 2 s; the short runs': SHORT_RUN below).
    # The engines step at their explicit stability limit (no accuracy knob, so no error
    # estimate): their allowance carries what they deviate from the conservative custom model.
    # The paper's model (`thread-spool`) differs by its non-conservative release, left beyond
    # the estimates against thread-spool-conservative (`python -m tests.allowances
    # sail-deploy`, case full; tests/allowances.json): hub_rate 9.2e-4 of scale, tip 5.9e-4
    # rad, angular momentum 3.0e-3; deployed length 3.9e-8 of scale (inside the estimates).
    tolerances={"hub_rate": 2e-4, "tip_angle": ("abs", 5e-5), "deployed_length": 1e-7,
                "angular_momentum": 1e-10,
                "by_solver": {"thread-spool": PAPER_ALLOWANCES,
                              "exudyn": {"angular_momentum": exudyn_momentum_allowance}},
                "wider": {p: "not in the default table: the engines' whole deployment runs "
                          "in `xval campaign long` (earlier: hub_rate 8e-5 of scale, tip "
                          "1.3e-5 rad)"
                          for p in ("thread-spool|exudyn", "thread-spool|mujoco",
                                    "thread-spool-conservative|exudyn",
                                    "thread-spool-conservative|mujoco", "exudyn|mujoco")}},
    # a run of ≤ 2 s (the campaign's sail-deploy-2s) is not a full deployment: its own
    # allowances, measured at 2 s and 0.2 s (cases 2s, 0.2s), left beyond the estimates
    # (relative; tip in rad, length in m): conservative–Exudyn hub 7.7e-8, tip 2.8e-6 rad,
    # length 1.0e-9 m, angular momentum 1.7e-11; conservative–MuJoCo 2.8e-8, 2.8e-6 rad,
    # 1.8e-10 m, 2.6e-14; Exudyn–MuJoCo 8.1e-8, 1.0e-9 m, 1.7e-11, tip its release offset's
    # (exudyn_tip_allowance; 3.4e-10 rad at the defaults); the paper's model: its release
    # law's closed form (PAPER_ALLOWANCES), length against conservative its Q-damper's and
    # spin change's (paper_length_allowance)
    allowance_cases=(AllowanceCase("t_end ≤ 2 s", lambda p: p["t_end"] <= 2.0, {
        "hub_rate": 3e-7, "tip_angle": ("abs", 1e-5), "deployed_length": ("abs", 3e-9),
        "angular_momentum": 5e-11,
        "by_solver": {"thread-spool": PAPER_ALLOWANCES,
                      "exudyn": {"angular_momentum": exudyn_momentum_allowance}},
        "by_pair": {"thread-spool-conservative|mujoco": {"hub_rate": 1e-7,
                                                         "deployed_length": ("abs", 5e-10),
                                                         "angular_momentum": 1e-13},
                    "thread-spool|mujoco": {"deployed_length": ("abs", 5e-10)},
                    "thread-spool|thread-spool-conservative": {
                        "deployed_length": paper_length_allowance},
                    "exudyn|mujoco": {"tip_angle": exudyn_tip_allowance}},
        "wider": {"thread-spool|thread-spool-conservative": {
            "deployed_length": "a bound of the deviation with the Q-spring's ringing resolved "
                               "(d r ω / c: 2.1–25 × it at five sets); the cases measure it at "
                               "the scene's step, where the ringing is not resolved and the "
                               "deviation up to 89 × smaller (docs/scenes/sail-deploy.md)"}}}),),
    key_channel="tip_angle",
    reference_solvers=("thread-spool-conservative", "exudyn"),
    invariant_channels=("angular_momentum",),
    analytic={"hub_rate": ("hub_rate_formula18", "formula18")},
    formula_checks=(FormulaCheck("hub_rate", "formula18", phys.formula18_discrete,
                                 formula18_error),),
    check=check,
    findings=sail_findings,
    draw_3d=draw_sail,
    extremes=SAIL_EXTREMES,
    # calibration: the default region at a 0.5-s horizon (the short-run allowances'), where the
    # engines' truth — 1/16 of their stability-bound step, 16 runs — costs ~1 min a set
    calibration=Calibration(fixed={"t_end": 0.5}),
    view_channels=("hub_rate", "tip_angle", "angular_momentum"),
    # full deployment: both custom variants and Exudyn (~4 min; MuJoCo needs ~15 min at k = 1e7
    # and checks the first 2 s)
    # the whole deployment with the custom solvers (seconds) in the default campaign; the
    # engines' whole deployment at k = 1e7 is step-bound by the thread's 1e5 rad/s modes
    # (Exudyn ~5 min, MuJoCo ~15 min) and runs in `xval campaign long`
    map_observables={"peak_tip_angle": (peak_tip_angle, "rad", "largest |tip angle|"),
                     "deployment_time": (deployment_time, "s", "whole blade out")},
    # the blade's lag over the initial spin, full deployment, the two custom solvers (~0.9 s a
    # run; the engines take minutes per deployment: `--engines everywhere` on a short horizon)
    maps=(MapSpec("tip-angle-vs-spin", x="Omega0=2:12", resolution=0.05, coarse=(5, 1),
                  observable="peak_tip_angle",
                  solvers=("thread-spool", "thread-spool-conservative")),),
    campaign_cases=({"name": "sail-deploy-full",
                     "solvers": ["thread-spool", "thread-spool-conservative"]},
                    {"name": "sail-deploy-2s", "set": {"t_end": 2}},
                    {"name": "sail-deploy-full-engines", "campaign": "long",
                     "solvers": ["thread-spool-conservative", "exudyn", "mujoco"],
                     "timeout_s": 3600}),
    notes="thread-spool is the paper's model (velocity turn at release, stored thread outside "
          "the hub inertia: not exactly conservative); thread-spool-conservative and the engines "
          "share one angular-momentum-conserving release law. The engines work in the inertial "
          "frame, the paper's model in the rotating one.",
)

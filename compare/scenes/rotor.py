"""Rotor on a spherical joint spun up through resonance (seed 000; spec scene-rotor.md)."""
import numpy as np

from ..analysis.identify import fft_peak, matrix_pencil, transverse_components
from ..analysis.metrics import first_crossing
from ..contract import Channel
from ..physics.rotation import quats_to_matrices
from ..physics.rotor import constants, instability_speed, unbalance_response, whirl_damped
from .base import (
    Calibration,
    Campbell,
    Extreme,
    Finding,
    MapSpec,
    ModesScene,
    Response,
    SpeedRegime,
    Threshold,
    TimeScene,
)
from .params import Param, positive

SOURCE = "seed 000 (Euler-vector rotor), seed 001 (quaternion formulation)"

ROTOR_PARAMS = (
    positive("l", 0.5, "m", "shaft length, pivot O to disk centre"),
    positive("k", 2000.0, "N·m/rad", "transverse angular spring stiffness (moment −kγ)"),
    positive("m", 5.0, "kg", "disk mass"),
    positive("R", 0.25, "m", "disk radius (I = diag(mR²/4, mR²/4, mR²/2))"),
    Param("eccentricity", 0.005, "m", "centre-of-mass offset along body y", lo=0.0, hi=1.0),
    Param("gravity", np.array([0.0, 0.0, -9.81]), "m/s²",
          "gravity vector; default stands the rotor up (disk above O)", kind="vector",
          lo=-1e3, hi=1e3),
    Param("tilt0", 0.0, "rad", "initial transverse turn about the fixed x axis", lo=0.0,
          hi=np.pi - 1e-3),
    Param("spin0", 0.0, "rad/s", "initial spin rate about the initial body axis", lo=-1e4, hi=1e4),
)


def spinup_levels(p):
    """The speeds `spinup_regime` decides by: √(k/I_t), which |ω| must reach, and 1.1 × the
    forward critical speed, which it must stay above."""
    c = constants(p)
    return c["omega_tilt"], 1.1 * c["forward_critical"]


# One run's regime, the findings' own decision: `not reached` (|ω| never reaches √(k/I_t)),
# `passage` (|ω| over the last 10 % of the run stays above 1.1 × the forward critical speed),
# else `capture`.
spinup_regime = SpeedRegime("omega_norm", spinup_levels, 0.9,
                            ("not reached", "capture", "passage"))


def spinup_findings(p, trajectories):
    """The statements the spin-up report must make, each solver's numbers side by side."""
    c = constants(p)
    ok = [tr for tr in trajectories if tr.status == "ok"]
    if not ok:
        return []

    def per_solver(fn):
        return {tr.solver: fn(tr) for tr in ok}

    def fmt(values, unit, digits=4):
        return ", ".join(f"{s} {v:.{digits}g}{unit}" if v is not None else f"{s} —"
                         for s, v in values.items())

    w = {tr.solver: tr.channels["omega_norm"] for tr in ok}
    cross = per_solver(lambda tr: first_crossing(tr.t, w[tr.solver], c["omega_tilt"]))
    ref = ok[0]
    t_c = cross[ref.solver]
    out = [Finding("critical_omega_tilt", c["omega_tilt"], "rad/s",
                   f"√(k/I_t) = {c['omega_tilt']:.4f} rad/s (I_t = {c['I_t']:.6g} kg·m²); with "
                   f"gravity √(k_eff/I_t) = {c['omega_tilt_eff']:.4f}; forward-whirl critical "
                   f"speed √(k_eff/(I_t−I_p)) = {c['forward_critical']:.4f} rad/s "
                   f"(k_eff = {c['k_eff']:.6g} N·m/rad)")]
    out.append(Finding("t_first_pass_omega_tilt", t_c, "s",
                       f"|ω| first passes {c['omega_tilt']:.4f} rad/s at t = "
                       + fmt(cross, " s", 6), at={s: v for s, v in cross.items() if v}))
    t_end = ref.t[-1]
    w_end = per_solver(lambda tr: float(w[tr.solver][-1]))
    # after the first passage: does the spin keep up with the drive or stall near resonance?
    if t_c is not None:
        win = ref.t >= min(t_c + 1.0, t_end)
        mean = per_solver(lambda tr: float(np.mean(w[tr.solver][win])))
        lo = float(np.min(w[ref.solver][win]))
        hi = float(np.max(w[ref.solver][win]))
        passed = spinup_regime(p, ref) == "passage"
        if passed:
            txt = ("passes through resonance: |ω| leaves the critical band and ends at "
                   + fmt(w_end, " rad/s", 6) + f" (> 1.1 × forward critical "
                   f"{c['forward_critical']:.4f} rad/s over the last 10 % of the run)")
        else:
            txt = (f"captured in resonance: after the first passage |ω| stalls between "
                   f"{lo:.3f} and {hi:.3f} rad/s (mean over t ≥ {t_c + 1:.2f} s: "
                   + fmt(mean, " rad/s", 6) + f"), i.e. {mean[ref.solver] / c['omega_tilt']:.3f}"
                   f" × √(k/I_t) and {mean[ref.solver] / c['forward_critical']:.3f} × the forward "
                   f"critical speed; the free ramp M·t/I_p would give "
                   f"{p['torque'] * t_end / c['I_p']:.1f} rad/s at t = {t_end:g} s")
        out.append(Finding("passes_resonance", float(passed), "", txt))
        out.append(Finding("omega_mean_after_pass", mean[ref.solver], "rad/s",
                           "mean |ω| after the first passage: " + fmt(mean, " rad/s", 6)))
    tilt_peak = per_solver(lambda tr: float(np.max(tr.channels["tilt"])))
    tilt_t = per_solver(lambda tr: float(tr.t[np.argmax(tr.channels["tilt"])]))
    out.append(Finding("tilt_peak", tilt_peak[ref.solver], "rad",
                       "peak tilt " + fmt(tilt_peak, " rad", 5)
                       + " at t = " + fmt(tilt_t, " s", 4)))
    out.append(Finding("omega_final", w_end[ref.solver], "rad/s",
                       f"|ω| at t = {t_end:g} s: " + fmt(w_end, " rad/s", 8)))
    return out


def draw_rotor(rec, params, traj, color, offset):
    """Shaft and disk in body axes; the body pose over time from the solver's orientation."""
    import rerun as rr
    q = traj.extra.get("orientation")
    if q is None:
        return
    ent = f"world/{traj.solver}"
    l, R, e = params["l"], params["R"], params["eccentricity"]
    rec.log(f"{ent}/shaft", rr.LineStrips3D([[[0, 0, 0], [0, 0, l]]], radii=0.01,
                                            colors=[color]), static=True)
    rec.log(f"{ent}/disk", rr.Cylinders3D(lengths=[0.02], radii=[R], centers=[[0, e, l]],
                                          colors=[color]), static=True)
    rec.log(f"{ent}/label", rr.Points3D([[0, 0, 0]], labels=[traj.solver], radii=0.02),
            static=True)
    ok = np.isfinite(q).all(axis=1)
    xyzw = np.column_stack([q[ok, 1:], q[ok, :1]])
    trans = np.tile(offset, (ok.sum(), 1))
    rec.send_columns(ent, indexes=[rr.TimeColumn("sim_time", duration=traj.t[ok])],
                     columns=rr.Transform3D.columns(translation=trans, quaternion=xyzw))


def _free_spin_ramp(p, tr):
    """Centred rotor spun from rest about its upright axis: no tilt is ever excited, so
    |ω(t)| = M t / I_p exactly (I_p about the axis through O)."""
    exact = p["torque"] * tr.t[-1] / (p["m"] * p["R"] ** 2 / 2)
    rel = abs(tr.channels["omega_norm"][-1] - exact) / exact
    return rel <= 1e-9, rel, f"|ω(t_end)| within {rel:.1e} of M t/I_p = {exact:.6g} rad/s"


# The spec's extremes (scene-rotor.md). Bounds are claims set from the measured outcome of the
# accurate default settings of all four solvers (`xval extremes rotor-spinup --all`).
# The engines' fixed steps (MuJoCo RK4 1e-3, Exudyn RK67 2e-3) do not resolve four of these
# motions to the 1e-6 bound; each drift is the step's own error (it falls as dt^4…dt^7 on
# halving, and each engine's error estimate says so), not an instability. Measured at the
# default step, on halving → the step given (run_case with the case's dt halved):
#   spin 1000 rad/s (ω h = 1 rad a step): MuJoCo 9.2e-4, 1.4e-4, 4.7e-6 → 1.25e-4: 1.5e-7;
#                                          Exudyn (dt 1e-3, the output grid) 6.9e-6 → 5e-4: 5.6e-8
#   torque 50 N·m: MuJoCo 8.1e-6 → 5e-4: 3.6e-7; Exudyn 2.2e-6 → 1e-3: 1.7e-8
#   tilt0 3.0: Exudyn 8.2e-6 → 1e-3: 9.4e-8 (MuJoCo 7.3e-8 at its default)
#   tilt0 π − 2e-3: MuJoCo 1.9e-5 → 5e-4: 1.3e-7; Exudyn 2.1e-4, 2.4e-6 → 5e-4: 3.5e-8
#   1000 s horizon: MuJoCo 3.7e-6 → 5e-4: 1.8e-7 (54 s). Exudyn ends `diverged` (the energy
#   rule: 70 % of the energy scale at 431 s; at 1e-3 still at 742 s) — an honest status the
#   case allows, left at its default step as the finding.
# The cases give the engines those steps (the largest halving below half the bound): what they
# test is stability and honesty at the extreme, which a step that does not resolve the motion
# cannot show. The bounds stay.
_RESOLVE_SPIN = {"dt": {"mujoco": 1.25e-4, "exudyn": 5e-4}}
_RESOLVE_TORQUE = {"dt": {"mujoco": 5e-4, "exudyn": 1e-3}}
_RESOLVE_TILT3 = {"dt": {"exudyn": 1e-3}}
_RESOLVE_TILT_PI = {"dt": {"mujoco": 5e-4, "exudyn": 5e-4}}
SPINUP_EXTREMES = (
    Extreme("torque 0.05 N·m, 200 s", {"torque": 0.05, "t_end": 200, "output_dt": 0.1},
            bound=1e-6, why="long slow spin-up below the critical speed"),
    Extreme("torque 50 N·m", {"torque": 50, "t_end": 2}, _RESOLVE_TORQUE, check="reference",
            bound=1e-6, why="violent passage (engines at the step that resolves it)"),
    Extreme("k 10 (falls over)", {"k": 10, "t_end": 3}, why="k < m g l: the upright rotor "
            "falls; through tilt π the spring −kγ is undefined: an honest status, or ok short "
            "of it"),
    Extreme("k 1e7 (stiff)", {"k": 1e7, "t_end": 1}, bound=1e-6,
            why="tilt frequency 2744 rad/s: fixed steps above RK4's limit 2.78/ω must stop"),
    Extreme("eccentricity 0", {"eccentricity": 0.0, "t_end": 5}, check=_free_spin_ramp,
            expect="ok", why="no whirl is excited: the closed-form free ramp"),
    Extreme("eccentricity 0.1", {"eccentricity": 0.1, "t_end": 5}, bound=1e-6,
            why="large imbalance"),
    Extreme("spin 1000 rad/s", {"spin0": 1000, "tilt0": 0.05, "torque": 0, "t_end": 1,
                                "output_dt": 0.001}, _RESOLVE_SPIN, bound=1e-6,
            why="fast gyroscopic top (engines at the step that resolves it)"),
    Extreme("tilt0 3.0", {"tilt0": 3.0, "t_end": 2}, _RESOLVE_TILT3, bound=1e-6,
            why="starts near the split's singularity at tilt π (Exudyn at the step that "
                "resolves it)"),
    Extreme("tilt0 π − 2e-3", {"tilt0": float(np.pi - 2e-3), "t_end": 1}, _RESOLVE_TILT_PI,
            why="1e-3 rad from where every solver stops (tilt π − 1e-3; engines at the step "
                "that resolves it)"),
    Extreme("1000 s horizon", {"t_end": 1000, "output_dt": 0.1}, {"dt": {"mujoco": 5e-4}},
            bound=1e-6, slow=True,
            why="energy drift growth over a long captured run"),
    Extreme("rk4 below its stability limit", {"k": 1e7, "t_end": 0.2, "output_dt": 0.001},
            {"integrator": "rk4", "dt": 2.5e-4}, bound=1e-6, expect="ok",
            why="ω h = 0.69 < 2.78"),
    Extreme("rk4 above its stability limit", {"k": 1e7, "t_end": 0.2, "output_dt": 0.005},
            {"integrator": "rk4", "dt": 5e-3}, expect="status",
            why="ω h = 13.7 > 2.78: must end diverged, never ok"),
)


SPINUP = TimeScene(
    name="rotor-spinup",
    title="Rotor on a spherical joint spun up through resonance",
    source=SOURCE,
    leaves={"euler-vector": "custom_models.rotor.euler_vector",
            "quaternion": "custom_models.rotor.quaternion",
            "exudyn": "reference_models.exudyn.rotor",
            "mujoco": "reference_models.mujoco.rotor"},
    params=ROTOR_PARAMS + (
        Param("torque", 1.5, "N·m", "drive torque about the fixed z axis", lo=-1e4, hi=1e4),
        positive("t_end", 10.0, "s", "horizon", hi=1e5),
        positive("output_dt", 0.01, "s", "common output grid step"),
    ),
    channels=(Channel("omega_norm", "rad/s"), Channel("spin_rate", "rad/s"),
              Channel("tilt", "rad"), Channel("work", "J"), Channel("kinetic", "J"),
              Channel("potential", "J"), Channel("energy_balance", "J")),
    # No allowance: the four solvers model one rigid rotor with one spring law, so no model
    # difference exists to name, and a numerical difference belongs to the error estimates
    # (issue 47). What the pairs deviate by beyond |y − y_tight| is the tight rerun's own
    # error: euler-vector's rtol-1e-13 runs scatter by up to 4.6e-9 J of work at 3.2 N·m, 5 s
    # (a 4-ulp change of rtol moves them that far: the step controller at the formulation's
    # rounding floor), which the estimate holds as 3.41 × its change on halving and quartering
    # the tolerance (`solvers._unseen_error`). Measured (`python -m tests.allowances
    # rotor-spinup`; `xval calibrate rotor-spinup --samples 20 --seed 11`): every pair within
    # its two estimates, Δ/bound ≤ 0.82 at the campaign's cases, ≤ 0.89 over the 20 sets.
    tolerances={c: 0.0 for c in ("omega_norm", "spin_rate", "tilt", "work", "kinetic",
                                 "potential")},
    key_channel="omega_norm",
    view_channels=("omega_norm", "tilt", "energy_balance"),
    energy_scale_channels=("kinetic", "potential", "work"),
    reference_solvers=("euler-vector", "quaternion"),
    findings=spinup_findings,
    draw_3d=draw_rotor,
    extremes=SPINUP_EXTREMES,
    calibration=Calibration(campaign=2),
    campaign_cases=({"name": "rotor-spinup-1.5Nm"},
                    {"name": "rotor-spinup-3.2Nm", "set": {"torque": "3.2", "t_end": "5"}}),
    regime=spinup_regime,
    # the default map: the capture/passage boundary M*(e) at t_end = 10 s, bracketed to 1 % of
    # the torque range, traced from 5 eccentricity rows to rows 1/32 of the range apart (the
    # custom solvers add 20: M*(e) is not monotonic — 1.20 N·m at e = 0.0025, none below
    # 0.001875, a peak of 4.11 at 0.00625 that the coarse rows 0.005 and 0.01 (3.05, 2.77) hid;
    # the engines check the coarse rows). The CLI's `xval map` brackets to 1e-3 by default.
    maps=(MapSpec("capture-boundary", x="torque=1:5", y="eccentricity=0:0.02",
                  set={"t_end": 10}, resolution=1e-2, y_resolution=1 / 32, coarse=(9, 5)),),
    notes="Spring −kγ exactly as the paper defines it (U = ½k|γ|², γ the transverse Euler "
          "vector); a Cardan spring ½k(α²+β²) is a different model.",
)

def identify_free_response(params, run, solver_names=None, t_end=2.0, dt=1e-3, tilt0=1e-3):
    """Release the rotor with a small tilt and no torque; identify the tilt frequency from each
    time-domain solver's record (matrix pencil, FFT peak) for several record lengths.

    `run(scene, solver_name, params, max_dt)` runs one time-domain solver (the compare layer's
    adapter); returns (rows for the JSON output, Markdown lines for the report)."""
    p = SPINUP.resolve({"torque": 0.0, "tilt0": tilt0, "t_end": t_end, "output_dt": dt})
    p.update({k: params[k] for k in ("l", "k", "m", "R", "eccentricity", "gravity")})
    lengths = [t_end / 8, t_end / 4, t_end / 2, t_end]
    rows = []
    for name in SPINUP.leaves:
        if solver_names and name not in solver_names:
            continue
        tr = run(SPINUP, name, p, dt)
        if tr.status != "ok" or "orientation" not in tr.extra:
            rows.append({"solver": name, "status": tr.status, "reason": tr.reason})
            continue
        gx, _ = transverse_components(tr.extra["orientation"])
        rec = {"solver": name, "status": "ok", "record_s": lengths, "matrix_pencil": [],
               "fft": []}
        for T in lengths:
            n = int(round(T / dt)) + 1
            w, _ = matrix_pencil(gx[:n], dt, n_modes=2)
            rec["matrix_pencil"].append(float(w[np.argmax(w > 1.0)]) if np.any(w > 1) else None)
            rec["fft"].append(float(fft_peak(gx[:n], dt)))
        rows.append(rec)
    md = ["## Frequencies identified from free responses", "",
          f"Rotor released with tilt0 = {tilt0:g} rad, no torque, {t_end:g} s record at "
          f"{dt * 1e3:g} ms; identified tilt frequency [rad/s] vs record length; closed form "
          f"√(k_eff/I_t) = {constants(params)['omega_tilt_eff']:.8g} rad/s.", "",
          "| solver | method | " + " | ".join(f"{T:g} s" for T in lengths) + " |",
          "|---|---|" + "---|" * len(lengths)]
    for r in rows:
        if r["status"] == "ok":
            for m in ("matrix_pencil", "fft"):
                md.append(f"| {r['solver']} | {m} | "
                          + " | ".join(f"{w:.8g}" if w else "—" for w in r[m]) + " |")
    return rows, md


def _critical(p):
    """The forward critical speed and the damping ratio of the synchronous response there:
    the denominator of `unbalance_response` is k_eff − (I_t − I_p)Ω² + i c_e Ω, an oscillator
    in Ω with ζ = c_e / (2 √(k_eff (I_t − I_p)))."""
    c = constants(p)
    return c["forward_critical"], p["c_ext"] / (2 * np.sqrt(c["k_eff"] * (c["I_t"] - c["I_p"])))


def _time_params(p, spin, t_end, output_dt, release=0.0):
    """rotor-spinup's parameters for a run at constant spin (started at the spin, upright or
    tilted by `release` about the fixed x axis) and the dampers, which only the engine leaves
    take. The drive torque balances the external damper's drag in the steady whirl,
    c_e Ω sin²θ ≈ c_e Ω |a|² (second order in the tilt; the internal damper sees a rigid
    rotation and drags nothing)."""
    a = unbalance_response(p, [spin])[0]
    over = {k: p[k] for k in ("l", "k", "m", "R", "eccentricity", "gravity")}
    over.update(tilt0=release, spin0=spin, torque=p["c_ext"] * spin * abs(a) ** 2,
                t_end=t_end, output_dt=output_dt)
    return over, {"c_ext": p["c_ext"], "c_int": p["c_int"]}


def _observe(p, tr):
    """θ = γ_x + iγ_y, the fixed-frame tilt, and e^{iφ}, φ the rotor's angle (of its body x
    axis; to first order in the tilt its spin angle)."""
    q = tr.extra["orientation"]
    gx, gy = transverse_components(q)
    R = quats_to_matrices(np.ascontiguousarray(q, dtype=float))
    u = R[:, 0, 0] + 1j * R[:, 1, 0]
    return gx + 1j * gy, u / np.abs(u)


# The unbalance response (`xval response rotor-whirl`). rotor-whirl rather than bearing-rotor:
# its closed form gives the synchronous response exactly (to first order in e), every one of
# its four linearising solvers takes the unbalance as an input of its own model, and both
# engines' time leaves carry its dampers. The time domain is the nonlinear rotor: it leaves
# the linear answer by O(θ²) relative, amplified near the critical (measured, MuJoCo against
# the closed form: e = 1e-6 m 7.7e-10 at 38.9 rad/s, 2.2e-12 at 20; e = 1e-7 m 1.1e-11,
# ∝ e²). e = 1e-8 m (tilt ≤ 1.6e-7 rad) puts that at ~1e-13, below MuJoCo's own error bars
# there (3e-12); a larger e is a test of how far the response stays linear. c_ext = 5
# N·m·s/rad: ζ = 0.052 at the critical (Q ≈ 10), settling (to 1e-12) in ~15 s.
RESPONSE = Response(
    time_scene="rotor-spinup", time_solvers=("exudyn", "mujoco"), critical=_critical,
    decay=lambda p, spin: float(np.min(-whirl_damped(p, spin).real)),
    time_params=_time_params, observe=_observe, set={"eccentricity": 1e-8, "c_ext": 5.0},
    # θ = a e^{iΩt} with the heavy spot at e^{i(Ωt + π/2)}; the disk's displacement is
    # l·(−iθ): relative to the heavy spot −a (in phase below the critical, 90° behind at it)
    high_spot=-1.0, amplitude="tilt amplitude |θ| [rad] (disk centre: l·|θ|)",
    drive="started upright at the spin; a drive torque c_e Ω |a|² balances the external "
          "damper's drag in the steady whirl; the phase is taken against the rotor's "
          "measured angle (a keyphasor)")


def _growing_root(p, spin):
    """(σ, ω) of the closed form's root with the largest real part at `spin`."""
    lam = whirl_damped(p, spin)
    lam = lam[np.argmax(lam.real)]
    return float(lam.real), float(lam.imag)


# The internal-damping threshold (issue 28). The time domain releases the centred rotor
# (eccentricity 0: no forcing) at the spin with a tilt of 1e-5 rad. Its nonlinearity moves the
# fitted growth rate by O(θ²): measured at 0.95 and 1.05 Ω_th (c_int = c_ext = 1), Exudyn at
# its tighter step 3e-10 /s off the closed form at tilt 1e-4, 3e-8 at 1e-3 (MuJoCo alike),
# ~4e-12 at 1e-5 — below the engines' own errors (≥ 1e-11 /s).
THRESHOLD = Threshold(parameter="spin", active=lambda p: p["c_int"] > 0,
                      speed=instability_speed, growth=_growing_root, release=1e-5,
                      free={"eccentricity": 0.0})


WHIRL = ModesScene(
    name="rotor-whirl",
    title="Whirl frequencies of the rotor at constant spin (Campbell diagram)",
    source=SOURCE,
    leaves={"closed-form": "custom_models.rotor.closed_form",
            "euler-vector": "custom_models.rotor.whirl",
            "exudyn": "reference_models.exudyn.rotor",
            "mujoco": "reference_models.mujoco.rotor"},
    params=ROTOR_PARAMS[:4] + (
        Param("eccentricity", 0.0, "m", "centre-of-mass offset along body y (0: closed form "
              "exact)", lo=0.0, hi=1.0),
        ROTOR_PARAMS[5],
        Param("spin", 0.0, "rad/s", "spin at which `xval modes` reports", lo=-1e4, hi=1e4),
        positive("spin_max", 150.0, "rad/s", "upper end of the Campbell sweep", hi=1e5,
                 physical=False),
        Param("n_spin", 100, "", "points of the Campbell sweep", kind="int", lo=2, hi=10000),
        # the dampers of compare.physics.rotor.whirl_damped: internal damping destabilises
        # forward whirl above instability_speed (gyroscopic Jeffcott threshold)
        Param("c_ext", 0.0, "N·m·s/rad", "external damping on the fixed-frame tilt rate",
              lo=0.0, hi=1e6),
        Param("c_int", 0.0, "N·m·s/rad", "internal (rotating) damping on the tilt rate seen "
              "in the spinning rotor's frame", lo=0.0, hi=1e6),
    ),
    energy_channel=None,
    # No modelling difference: every solver models the same rigid rotor, and each carries its
    # own round-off (and, linearising by finite differences, the change with its step) in its
    # frequency and ζ error estimates (compare/physics/eigen.py), so the allowances are 0
    tolerances={"frequency": 0.0, "damping": 0.0},
    # the whirl frequencies seen from the ground (fixed frame), labelled forward/backward:
    # drawable in the rotor's frame too; unbalance meets them at √(k_eff/(I_t ∓ I_p))
    campbell=Campbell("spin", 0.0, "spin_max", "n_spin",
                      excitation_hz=lambda p, spin: spin / (2 * np.pi), whirls=True),
    response=RESPONSE,
    threshold=THRESHOLD,
    identify=lambda params, run, names=None: (
        identify_free_response(params, run, names) if params["spin"] == 0 else ([], [])),
    campaign_cases=({"name": "rotor-whirl"},),
    # `xval map rotor-whirl --x spin=LO:HI --observable growth_rate --level 0`: where each
    # solver's largest Re λ crosses zero — the internal-damping threshold located by a map
    map_observables={"growth_rate": (lambda p, m: m.extra.get("max_re_per_s"), "1/s",
                                     "largest real part of the eigenvalues (> 0: a root grows)")},
    # the spin over the Campbell sweep (gyroscopic split) and both dampers (ζ up to ~0.05; roots
    # grow above the internal-damping threshold); at eccentricity 0 (held) the closed form is
    # exact, the truth of the three that linearise
    calibration=Calibration(region={"spin": (0.0, 150.0), "c_ext": (0.0, 5.0),
                                    "c_int": (0.0, 5.0)},
                            truth=dict.fromkeys(("euler-vector", "exudyn", "mujoco"),
                                                "closed-form"), campaign=2),
)

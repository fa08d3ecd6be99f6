"""Rotor on a spherical joint spun up through resonance (seed 000; spec scene-rotor.md)."""
import numpy as np

from ..metrics import first_crossing
from ..params import Param, positive
from .base import Finding, Scene

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


def constants(p):
    """Closed-form rotor numbers: inertias about O and the effective transverse stiffness.

    Gravity enters the tilt stiffness only through its axial component: k_eff = k + m·l·g_z
    (disk above O and g_z < 0 softens the spring)."""
    I_t = p["m"] * p["R"] ** 2 / 4 + p["m"] * p["l"] ** 2
    I_p = p["m"] * p["R"] ** 2 / 2
    k_eff = p["k"] + p["m"] * p["l"] * float(np.asarray(p["gravity"])[2])
    return {"I_t": I_t, "I_p": I_p, "k_eff": k_eff,
            "omega_tilt": np.sqrt(p["k"] / I_t),                 # the paper's 38.8 rad/s
            "omega_tilt_eff": np.sqrt(max(k_eff, 0.0) / I_t),
            "forward_critical": np.sqrt(max(k_eff, 0.0) / (I_t - I_p))}


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
                       + fmt(cross, " s", 6)))
    t_end = ref.t[-1]
    w_end = per_solver(lambda tr: float(w[tr.solver][-1]))
    # after the first passage: does the spin keep up with the drive or stall near resonance?
    if t_c is not None:
        win = ref.t >= min(t_c + 1.0, t_end)
        mean = per_solver(lambda tr: float(np.mean(w[tr.solver][win])))
        lo = float(np.min(w[ref.solver][win]))
        hi = float(np.max(w[ref.solver][win]))
        passed = bool(np.min(w[ref.solver][ref.t >= 0.9 * t_end]) > 1.1 * c["forward_critical"])
        if passed:
            txt = (f"passes through resonance: |ω| leaves the critical band and ends at "
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
                       "peak tilt " + fmt(tilt_peak, " rad", 5) + " at t = " + fmt(tilt_t, " s", 4)))
    out.append(Finding("omega_final", w_end[ref.solver], "rad/s",
                       f"|ω| at t = {t_end:g} s: " + fmt(w_end, " rad/s", 8)))
    return out


SPINUP = Scene(
    name="rotor-spinup",
    title="Rotor on a spherical joint spun up through resonance",
    source=SOURCE,
    kind="time",
    params=ROTOR_PARAMS + (
        Param("torque", 1.5, "N·m", "drive torque about the fixed z axis", lo=-1e4, hi=1e4),
        positive("t_end", 10.0, "s", "horizon", hi=1e5),
        positive("output_dt", 0.01, "s", "common output grid step"),
    ),
    channels=("omega_norm", "spin_rate", "tilt", "work", "kinetic", "potential",
              "energy_balance"),
    tolerances={"omega_norm": 1e-4, "tilt": 1e-4, "spin_rate": 1e-4, "work": 1e-4,
                "kinetic": 1e-4},
    key_channel="omega_norm",
    reference_solvers=("euler-vector", "quaternion"),
    findings=spinup_findings,
    notes="Spring −kγ exactly as the paper defines it (U = ½k|γ|², γ the transverse Euler "
          "vector); a Cardan spring ½k(α²+β²) is a different model.",
)

WHIRL = Scene(
    name="rotor-whirl",
    title="Whirl frequencies of the rotor at constant spin (Campbell diagram)",
    source=SOURCE,
    kind="modes",
    params=ROTOR_PARAMS[:4] + (
        Param("eccentricity", 0.0, "m", "centre-of-mass offset along body y (0: closed form "
              "exact)", lo=0.0, hi=1.0),
        ROTOR_PARAMS[5],
        Param("spin", 0.0, "rad/s", "spin at which `xval modes` reports", lo=-1e4, hi=1e4),
        positive("spin_max", 150.0, "rad/s", "upper end of the Campbell sweep", hi=1e5),
        Param("n_spin", 100, "", "points of the Campbell sweep", kind="int", lo=2, hi=10000),
    ),
    energy_channel=None,
    tolerances={"frequency": 1e-6},
)

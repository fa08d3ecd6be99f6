"""Bricard's mechanism (IFToMM Library of Computational Benchmark Problems, problem A04): five
uniform rods of square cross-section (side a = 0.1 m, as the library states them; a = 0: thin
rods) in a closed loop of six revolute joints, one degree of freedom where the
Grübler count gives zero (redundant constraints), swinging under gravity from rest for 10 s.
The reference is our own integration in the one minimal coordinate (compare.physics.bricard:
DOP853 at rtol 1e-12, Radau agreeing to 1.1e-11), tabulated at whole seconds below; energy is
conserved (no work is done on the loop)."""
import numpy as np

from ..analysis.verdict import Verdict
from ..physics import bricard as phys
from .base import Benchmark, Finding, TimeScene, tabulated
from .drawing import send_strips
from .params import Param, positive

SOURCE = ("IFToMM Technical Committee for Multibody Dynamics, Library of Computational "
          "Benchmark Problems, problem A04 “Bricard's mechanism”; M. González, D. Dopico, "
          "U. Lugrís, J. Cuadrado, A benchmarking system for MBS simulation software, Multibody "
          "System Dynamics 16 (2006) 179–190; R. Bricard, J. Math. Pures Appl. 3 (1897) 113–148")

PARAMS = (positive("m", 1.0, "kg", "mass of each rod", hi=1e3),
          positive("L", 1.0, "m", "length of each rod (the joints sit at the rods' ends)",
                   hi=1e2),
          positive("g", 9.81, "m/s²", "gravity, along −y", hi=1e3),
          # the library's "square cross section length 0.1 m" (as its OpenSim port documents
          # it): a uniform prism, m (L² + a²)/12 across the rod, m a²/6 about it
          Param("a", 0.1, "m", "side of each rod's square cross-section (0: thin rods)", lo=0.0,
                hi=1e2))

# every solver's model closes the loop exactly (minimal coordinates) or to the engines'
# constraint tolerance; the solvers' own errors are in their estimates (the allowance: 1e-9 of
# scale, the estimates' own inaccuracy)
TOLERANCES = {str(c): 1e-9 for c in phys.CHANNELS}

# the reference: P3 at t = 0, 1, …, 10 s at the library's parameters, rods of square section
# a = 0.1 m (phys.reference, DOP853 at rtol = atol = 1e-12; Radau at the same tolerance agrees
# to 1.1e-11 m, DOP853 at 1e-10 to 8.3e-10 rad; the energy balance stays within 6.8e-11 J of
# the 4.55 J peak kinetic energy). Thin rods (a = 0) are up to 0.016 m from it (p3_x, 9 s).
REF_T = np.arange(11.0)
REF_P3 = np.array([
    [1.0, 0.510501461188, -0.969340344778, -0.967199800049, 0.524899593391, 0.999999997738,
     0.495873449945, -0.971373849242, -0.964948571669, 0.539064288493, 0.999999963806],
    [-1.0, -1.649167599395, -1.221246894956, -1.228020214674, -1.643876001336,
     -1.000067257698, -1.654324512273, -1.214541874858, -1.234859545233, -1.638453308241,
     -1.000269012696],
    [1.0, 0.140123114553, 0.75427801078, 0.745983176176, 0.148835846115, 0.99993274004,
     0.131605204046, 0.762444017108, 0.737560951773, 0.157735378357, 0.99973095112]]).T
REFERENCE_UNCERTAINTY = 1e-10    # m: the table's rounding (5e-13) and the integration's own
P3 = ("p3_x", "p3_y", "p3_z")


def reference_findings(params, trajectories):
    """Each solver's P3 at the tabulated whole seconds against the reference table: the largest
    deviation, judged against the solver's own error bar there plus the reference's
    uncertainty. Only at the library's parameters."""
    defaults = {p.name: p.default for p in PARAMS}
    if any(params[n] != v for n, v in defaults.items()):
        return [Finding("reference", None, "m", "the reference table holds at the library's "
                        "parameters only: not compared here")]
    out = []
    for tr in trajectories:
        rows = [(k, int(np.argmin(np.abs(tr.t - t)))) for k, t in enumerate(REF_T)
                if t <= tr.t[-1] + 1e-12]
        rows = [(k, i) for k, i in rows if abs(tr.t[i] - REF_T[k]) <= 1e-9]
        if tr.status != "ok" or len(rows) < 2:
            out.append(Finding(f"reference_{tr.solver}", None, "m",
                               f"{tr.solver}: {Verdict.SKIPPED} against the reference table "
                               f"({tr.status}, no values at whole seconds)"))
            continue
        ks, idx = [k for k, _ in rows], [i for _, i in rows]
        dev = np.array([[tr.channels[c][i] for c in P3] for i in idx]) - REF_P3[ks]
        err = np.array([[abs(float(tr.errors[c][i])) if c in tr.errors else np.nan
                         for c in P3] for i in idx])
        bar = err + TOLERANCES["p3_x"] * float(params["L"]) + REFERENCE_UNCERTAINTY
        if not np.all(np.isfinite(err)):
            verdict = Verdict.INCONCLUSIVE
        else:
            verdict = Verdict.AGREE if np.all(np.abs(dev) <= bar) else Verdict.DISAGREE
        r, c = np.unravel_index(int(np.argmax(np.abs(dev))), dev.shape)
        out.append(Finding(
            f"reference_{tr.solver}", float(np.max(np.abs(dev))), "m",
            f"{tr.solver}: P3 at t = 0…{REF_T[ks[-1]]:g} s vs the reference: {verdict} — "
            f"largest deviation {dev[r, c]:+.3g} m ({P3[c]} at {REF_T[ks[r]]:g} s; error bar "
            f"{bar[r, c]:.3g} m)"))
    return out


# IFToMM library problem A04: P3 over 0…10 s on the run's grid; its reference the table above,
# at the library's parameters only
BENCHMARK = Benchmark(
    problem="A04", columns=P3,
    reference=tabulated(REF_T, dict(zip(P3, REF_P3.T)),
                        lambda params: all(params[p.name] == p.default for p in PARAMS)),
    reference_name="our integration in the one minimal coordinate (compare.physics.bricard."
                   "reference: DOP853 at rtol = atol = 1e-12), tabulated at t = 0, 1, …, 10 s",
    uncertainty=REFERENCE_UNCERTAINTY)




def draw_bricard(rec, params, traj, color, offset):
    """The five rods as one line strip through the six joints, placed from the solver's θ1 with
    the loop closed again (compare.physics.bricard.close)."""
    p = phys.pack(params)
    th = traj.channels["theta1"]
    rows = np.nonzero(np.isfinite(th))[0]
    if not len(rows):
        return
    strips, guess = [], np.zeros(5)
    for i in rows:
        q, ok = phys.close(float(th[i]), guess, p, 1e-13, 50)
        guess = q[1:].copy()
        _, Rs, ts = phys.forward(q, p)
        pts = [Rs[max(k, 1)] @ (phys.POINTS[k] * p[phys.LEN]) + ts[max(k, 1)]
               for k in range(6)]
        strips.append(np.array(pts) + offset)
    send_strips(rec, f"world/{traj.solver}/rods", traj.t[rows], strips,
                [tuple(color)] * len(strips), 5e-3)


BRICARD = TimeScene(
    name="bricard", title="Bricard's mechanism (IFToMM benchmark A04): redundant constraints",
    source=SOURCE,
    leaves={"lagrange-partial": "custom_models.bricard.partial",
            "exudyn": "reference_models.exudyn.bricard",
            "mujoco": "reference_models.mujoco.bricard"},
    params=PARAMS + (positive("t_end", phys.T_END, "s", "horizon (library: 10 s)", hi=1e3),
                     positive("output_dt", 1e-2, "s", "output grid")),
    channels=phys.CHANNELS, tolerances=TOLERANCES, key_channel="p3_y",
    energy_scale_channels=("kinetic_energy",), findings=reference_findings,
    view_channels=("p3_x", "p3_y", "p3_z", "energy_balance"), draw_3d=draw_bricard,
    campaign_cases=({"name": "bricard", "campaign": "benchmarks"},),
    group="benchmarks", benchmark=BENCHMARK,
    notes="Energy balance = kinetic + gravity potential − its start (no work is done). Rods: "
          "uniform square prisms of side a (the library's 0.1 m; a = 0: thin rods).")

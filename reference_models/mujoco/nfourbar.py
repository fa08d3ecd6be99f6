"""MuJoCo model of the N four-bar mechanism (scene `n-four-bar`).

Model: a tree of hinges about z — each crank k a child of the world (hinge at (kL, 0, 0)),
each coupler k a child of crank k (hinge at its tip B_k) — and one `connect` per loop closing
it: coupler k's end to crank k+1's tip. All frames are level at qpos = 0 (every rod along +x,
where the connect's two points coincide); the start sets the crank hinges to φ0 and the
coupler hinges to −φ0 (couplers level), with the rigid mechanism's rates. So φ_k = the crank
hinge, ψ_k = crank hinge + coupler hinge. Rods: m, m L²/12 about their centre (about z the
only one that acts: the motion is planar). A connect is three equations of which the z row is
identically zero here, and the loops' equations lose rank at the singular positions: MuJoCo's
soft constraints take both as they are (its solver regularises them), solref (solref_factor·dt,
1) and solimp (0.9999, 0.9999, 0.001, 0.5, 2). Gravity −g ŷ. RK4.
"""
from __future__ import annotations

import mujoco
import numpy as np

from compare.contract import LeafResult
from compare.physics import nfourbar as phys

from .. import loop_common as lc

# dt 2.5e-4 (bricard's 1e-4 is 4× the time here: 81 hinges, 120 constraint rows)
DEFAULT_SETTINGS = {"integrator": "rk4", "dt": 2.5e-4, "solref_factor": 4.0,
                    "solimp": (0.9999, 0.9999, 0.001, 0.5, 2.0)}
INTEGRATORS = ("rk4", "euler", "implicitfast", "implicit")
# the soft loops move the motion off the rigid mechanism and spread the cranks by an amount
# that grows as tc^1.2…1.6 (tc = the constraints' time constant, solref_factor·dt, at least
# 2·dt: MuJoCo's floor; measured in tests/engines/test_nfourbar_engines.py, not bricard's tc²):
# the knob varies it on its own, declared order 1 (the estimate's floor ratio ½)
KNOBS = {"solref_factor": 1}


def check_settings(settings: dict | None, t_out: np.ndarray | None = None) -> dict:
    """The settings merged and checked before anything runs (ValueError with one line)."""
    return lc.mujoco_settings(settings, DEFAULT_SETTINGS, INTEGRATORS)


_f = lc.fmt


def xml(params: dict, s: dict) -> str:
    m, L, g, n = float(params["m"]), float(params["L"]), float(params["g"]), int(params["N"])
    solref, solimp = lc.soft_strings(s)
    integ = lc.MJ_INTEGRATORS[s["integrator"]]
    i_c = _f(m * L * L / 12.0)
    inertial = (f'<inertial pos="{_f(0.5 * L)} 0 0" mass="{_f(m)}" '
                f'diaginertia="{i_c} {i_c} {i_c}"/>')
    tree = "".join(
        f'<body name="crank{k}" pos="{_f(k * L)} 0 0">'
        f'<joint name="phi{k}" type="hinge" axis="0 0 1"/>{inertial}'
        + (f'<body name="coupler{k}" pos="{_f(L)} 0 0">'
           f'<joint name="psi{k}" type="hinge" axis="0 0 1"/>{inertial}</body>' if k < n else "")
        + '</body>' for k in range(n + 1))
    connects = "".join(f'<connect body1="coupler{k}" body2="crank{k + 1}" anchor="{_f(L)} 0 0" '
                       f'solref="{solref}" solimp="{solimp}"/>' for k in range(n))
    return f"""
<mujoco model="n-four-bar">
  <option timestep="{_f(s['dt'])}" integrator="{integ}" gravity="0 {_f(-g)} 0"
          jacobian="sparse">
    <flag contact="disable" autoreset="disable"/>
  </option>
  <worldbody>{tree}</worldbody>
  <equality>{connects}</equality>
</mujoco>
"""


def _angles(model, n):
    """qpos/qvel addresses of the crank hinges and the coupler hinges."""
    cr = np.array([model.jnt_qposadr[model.joint(f"phi{k}").id] for k in range(n + 1)])
    co = np.array([model.jnt_qposadr[model.joint(f"psi{k}").id] for k in range(n)], int)
    return cr, co


def simulate(params: dict, t_out: np.ndarray, settings: dict | None = None) -> LeafResult:
    s = check_settings(settings)
    t_out = np.asarray(t_out, float)
    n = int(params["N"])
    m, d = lc.mujoco_model(xml(params, s))
    cr, co = _angles(m, n)
    phi0, rate = float(params["phi0"]), phys.initial_rate(params)
    d.qpos[cr], d.qvel[cr] = phi0, rate
    d.qpos[co], d.qvel[co] = -phi0, -rate
    mujoco.mj_forward(m, d)
    nt = len(t_out)
    PHI, PHID = np.full((nt, n + 1), np.nan), np.full((nt, n + 1), np.nan)
    PSI, PSID = np.full((nt, n), np.nan), np.full((nt, n), np.nan)

    def record(i):
        PHI[i], PHID[i] = d.qpos[cr], d.qvel[cr]
        PSI[i], PSID[i] = d.qpos[cr[:-1]] + d.qpos[co], d.qvel[cr[:-1]] + d.qvel[co]
    record(0)
    steps, status, t_fail, reason, evals, h = lc.mujoco_run(m, d, t_out, s, record)
    return LeafResult(channels=phys.channels(PHI, PHID, PSI, PSID, params), status=status,
                      t_fail=t_fail, reason=reason, stats={"steps": steps, "rhs_evals": evals},
                      settings={**s, "dt": h})

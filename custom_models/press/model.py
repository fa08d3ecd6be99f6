"""The custom press model's data: the scene's resolved parameters packed into one float array
`p` for the compiled code (indices below), and the inertia items built from the shared link
layout (compare.physics.press.link_layout, the same mass placement the engines use).

Kinetic energy T = ½ q'ᵀ A(q) q' is a sum over "inertia items": a scalar coordinate c(q) (a
point's x or y, or a link angle) with a weight (mass or moment of inertia), T = ½ Σ w (∇c·q')².
Each link's centre of mass is a linear combination of the eight base coordinates
(x_A, y_A, x_B, y_B, x_C, φ, θ2, ψ), so both mass models (paper: masses lumped at the joints,
eq. 21; midpoint) are item tables over them.
"""
import math

import numpy as np

from compare.physics import press as phys

# base coordinates (columns of the gradient table G)
XA, YA, XB, YB, XC, PHI, TH2, PSI = range(8)
NB = 8

# ---- packed parameter array p -------------------------------------------------------------
(L1, L2, L3, SIGMA, GRAV, K_S, C_S, XC0, U, DPHI, DPSI, MODE, PRESS, VREG, LOCK_PSI,
 SING_TOL, E0, E_JUMP, E_LOST, E_SCALE, N_ITEMS, SOLVER) = range(22)
HV = 22                       # 8 gravity "height" coefficients: V_g = g Σ HV_b · base_b
ITEMS = HV + NB               # n_items rows of (8 coefficients, weight)
MAX_ITEMS = 10
P_LEN = ITEMS + MAX_ITEMS * (NB + 1)
NZ = 3                        # work integrals: motor, damper, press load
SOLVER_IDS = {"exact": 0.0, "partial": 1.0}


def inertia_items(par: dict):
    """Inertia items (coefficients over the base coordinates, weight) and gravity heights, from
    the shared link layout: crank COM at f·A, rod COM at (1 − f)A + fB, rocker COM at
    (1 − f)C + fB (y_C = 0), slider mass at C. Items with the same coefficients are merged."""
    lay = phys.link_layout(par)
    items, heights = {}, np.zeros(NB)        # coefficients (a tuple) -> summed weight

    def add(coef, w):
        if any(coef):
            items[coef] = items.get(coef, 0.0) + w

    def c(**kw):
        v = [0.0] * NB
        for name, val in kw.items():
            v[{"xA": XA, "yA": YA, "xB": XB, "yB": YB, "xC": XC, "phi": PHI, "th2": TH2,
               "psi": PSI}[name]] = val
        return tuple(v)
    cx, m, J = lay["crank"]
    f = cx / float(par["l1"])
    add(c(xA=f), m)
    add(c(yA=f), m)
    add(c(phi=1), J)
    heights[YA] += m * f
    cx, m, J = lay["rod"]
    f = cx / float(par["l2"])
    add(c(xA=1 - f, xB=f), m)
    add(c(yA=1 - f, yB=f), m)
    add(c(th2=1), J)
    heights[YA] += m * (1 - f)
    heights[YB] += m * f
    cx, m, J = lay["rocker"]
    f = cx / float(par["l3"])
    add(c(xB=f, xC=1 - f), m)
    add(c(yB=f), m)
    add(c(psi=1), J)
    heights[YB] += m * f
    add(c(xC=1), float(par["m4"]))
    return list(items.items()), heights


def pack(par: dict, dphi_deg: float = 0.1, dpsi_deg: float = 0.1, singular_tol: float = 0.02,
         energy_jump: float = 1e3) -> np.ndarray:
    """The scene's resolved parameters (+ the finite-difference steps and guard limits) as one
    float array. press-cycle's load and lock angle where the parameters carry them."""
    p = np.zeros(P_LEN)
    p[L1], p[L2], p[L3] = par["l1"], par["l2"], par["l3"]
    p[SIGMA] = phys.assembly_sign(par)
    p[GRAV], p[K_S], p[C_S] = par["gravity"], par["slider_stiffness"], par["slider_damping"]
    p[U] = par["gear_ratio"]
    p[DPHI], p[DPSI] = math.radians(dphi_deg), math.radians(dpsi_deg)
    if phys.is_cycle(par):
        p[PRESS], p[VREG] = par["press_force"], par["press_force_vreg"]
        p[LOCK_PSI] = math.radians(par["lock_angle"])
    else:
        p[VREG] = 1.0                         # unused (no load): any positive scale
    p[SING_TOL], p[E_JUMP] = singular_tol, energy_jump
    items, heights = inertia_items(par)
    p[N_ITEMS] = len(items)
    p[HV:HV + NB] = heights
    for i, (coef, w) in enumerate(items):
        p[ITEMS + i * (NB + 1): ITEMS + i * (NB + 1) + NB] = coef
        p[ITEMS + i * (NB + 1) + NB] = w
    xA, yA, xB, yB, xC, ok = phys.loop_closure(math.radians(par["phi0"]),
                                               math.radians(par["psi0"]), p[L1], p[L2], p[L3],
                                               p[SIGMA])
    if not ok:
        raise ValueError(f"the loop cannot close at phi0={par['phi0']}, psi0={par['psi0']} deg "
                         "(|y_B - y_A| > l2)")
    p[XC0] = xC                               # the spring acts about the initial slider position
    return p

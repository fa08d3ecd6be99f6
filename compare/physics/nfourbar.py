"""The N four-bar mechanism (scene `n-four-bar`; IFToMM Library of Computational Benchmark
Problems, problem A02, González, Dopico, Lugrís & Cuadrado 2006): N + 1 equal uniform rods
("cranks", mass m, length L) pinned to the ground at x = 0, L, …, N·L, their tips B_0 … B_N
joined by N equal rods ("couplers"), gravity g along −y. Every loop is a rhombus, so on the
mechanism's motion every crank has the same angle φ (from +x) and the couplers translate
horizontally: one degree of freedom. Where φ = 0 or π (all rods horizontal) each loop's
closure Jacobian loses rank — the loop can leave the parallelogram (at φ = 0 crank k + 1 is
momentarily free, at φ = π the folded branch φ_{k+1} = π meets it): the singular positions.

Everything every solver computes alike lives here: the channels from the common kinematic
output (every crank's angle φ_k and every coupler's angle ψ_k, with their rates), and the
reference — the motion in φ alone, from

    T = ½ c_T φ'²,  c_T = m L² [(N + 1)/3 + N]   (cranks about their pins; couplers
                                                   translate with the tips' speed L φ')
    V = c_V sin φ,  c_V = m g L [(N + 1)/2 + N]   (crank centres at L/2 sin φ, couplers
                                                   at L sin φ)

so c_T φ'' = −c_V cos φ, integrated by scipy. Numpy and scipy only.
"""
from __future__ import annotations

import numpy as np

from ..contract import Channel

T_END = 10.0
N_DEFAULT = 40
PHI0 = np.pi / 2      # the library's start: every crank vertical
# a chain closed loop by loop (Exudyn's index-3 joints) rounds each crank's angle by the
# closure's rounding, a few eps, over its conditioning, the loop Jacobian ∝ L sin φ: the
# spread of N + 1 cranks is ≤ CLOSURE_ROUNDING · eps · (N + 1) / |sin φ| — measured
# max_t |spread · sin φ| / (eps (N + 1)) = 1.1–10.7 over n-four-bar's 20 calibration sets
# (seed 11, 1 s; the peak 1.1e-10 rad at |sin φ| = 3.6e-4), independent of step and Newton
# tolerance (a rounding, not a discretisation, error)
CLOSURE_ROUNDING = 16.0


def closure_rounding(channels: dict, params: dict) -> np.ndarray:
    """The cranks' spread a loop-by-loop closure rounds to at each output time (rad)."""
    s = np.maximum(np.abs(np.sin(np.asarray(channels["phi"], float))), np.finfo(float).eps)
    return CLOSURE_ROUNDING * np.finfo(float).eps * (int(params["N"]) + 1) / s


CHANNELS = (Channel("phi", "rad"), Channel("phi_dot", "rad/s"), Channel("b0_x", "m"),
            Channel("b0_y", "m"), Channel("kinetic_energy", "J"),
            Channel("potential_energy", "J"), Channel("energy_balance", "J"),
            Channel("parallelogram", "rad", rounding=closure_rounding))


def coefficients(params: dict) -> tuple[float, float]:
    """(c_T, c_V): T = ½ c_T φ'², V = c_V sin φ on the parallelogram."""
    m, L, g, n = (float(params["m"]), float(params["L"]), float(params["g"]),
                  int(params["N"]))
    return m * L * L * ((n + 1) / 3.0 + n), m * g * L * ((n + 1) / 2.0 + n)


def initial_rate(params: dict) -> float:
    """φ'(0) from B_0's horizontal velocity vx0: x_B0 = L cos φ, so ẋ = −L sin φ φ'."""
    return -float(params["vx0"]) / (float(params["L"]) * np.sin(float(params["phi0"])))


def wrap(a):
    """Angles to (−π, π]."""
    return np.pi - np.mod(np.pi - np.asarray(a, float), 2.0 * np.pi)


def channels(PHI, PHID, PSI, PSID, params: dict) -> dict:
    """The channels from crank angles PHI (n, N+1), their rates PHID, coupler angles PSI (n, N)
    (coupler k from B_k to B_{k+1}) and rates PSID, exactly as the rods stand (no closure
    assumed): φ and φ' of crank 0, B_0, the energies (V = m g Σ y_c, zero with every rod
    horizontal), the balance T + V − E₀ (zero for an exact solution: no work is done) and the
    parallelogram residual max_k |φ_k − φ_0| (wrapped; 0 on the mechanism's own motion)."""
    m, L, g = float(params["m"]), float(params["L"]), float(params["g"])
    PHI, PHID = np.atleast_2d(np.asarray(PHI, float)), np.atleast_2d(np.asarray(PHID, float))
    PSI, PSID = np.atleast_2d(np.asarray(PSI, float)), np.atleast_2d(np.asarray(PSID, float))
    t_cr = 0.5 * (m * L * L / 3.0) * np.sum(PHID ** 2, axis=1)
    v_cr = m * g * 0.5 * L * np.sum(np.sin(PHI), axis=1)
    a = PHI[:, :-1]
    ad = PHID[:, :-1]
    # a coupler's centre: B_k + ½L(cos ψ, sin ψ); its velocity from B_k's and its own rotation
    vx = -L * np.sin(a) * ad - 0.5 * L * np.sin(PSI) * PSID
    vy = L * np.cos(a) * ad + 0.5 * L * np.cos(PSI) * PSID
    t_co = np.sum(0.5 * m * (vx ** 2 + vy ** 2) + 0.5 * (m * L * L / 12.0) * PSID ** 2, axis=1)
    v_co = m * g * np.sum(L * np.sin(a) + 0.5 * L * np.sin(PSI), axis=1)
    T, V = t_cr + t_co, v_cr + v_co
    par = (np.max(np.abs(wrap(PHI[:, 1:] - PHI[:, :1])), axis=1) if PHI.shape[1] > 1
           else np.zeros(len(PHI)))
    return {"phi": PHI[:, 0].copy(), "phi_dot": PHID[:, 0].copy(),
            "b0_x": L * np.cos(PHI[:, 0]), "b0_y": L * np.sin(PHI[:, 0]),
            "kinetic_energy": T, "potential_energy": V, "energy_balance": T + V - (T[0] + V[0]),
            "parallelogram": par}


def parallelogram_state(phi, phid, n: int):
    """The full output of a motion on the mechanism: every crank at φ, the couplers level."""
    phi, phid = np.asarray(phi, float), np.asarray(phid, float)
    PHI = np.repeat(phi[:, None], n + 1, axis=1)
    PHID = np.repeat(phid[:, None], n + 1, axis=1)
    return PHI, PHID, np.zeros((len(phi), n)), np.zeros((len(phi), n))


def reference(params: dict, t_out, rtol: float = 1e-12, atol: float = 1e-12,
              method: str = "DOP853", events=None):
    """The reference: c_T φ'' = −c_V cos φ from φ0, φ'(0) = initial_rate, by scipy's `method`
    at rtol/atol on the grid t_out; `events` (functions of (t, [φ, φ'])) passed to scipy.
    Returns scipy's result (sol.y = [φ, φ'] on t_out)."""
    from scipy.integrate import solve_ivp
    c_t, c_v = coefficients(params)
    k = c_v / c_t

    def rhs(t, y):
        return np.array([y[1], -k * np.cos(y[0])])

    def jac(t, y):
        return np.array([[0.0, 1.0], [k * np.sin(y[0]), 0.0]])

    t_out = np.asarray(t_out, float)
    y0 = [float(params["phi0"]), initial_rate(params)]
    extra = {"jac": jac} if method in ("Radau", "BDF", "LSODA") else {}
    return solve_ivp(rhs, (0.0, float(t_out[-1])), y0, method=method, rtol=rtol, atol=atol,
                     t_eval=t_out, events=events, **extra)


def reference_channels(params: dict, t_out, **kw) -> dict:
    """The scene's channels of the reference motion on t_out."""
    sol = reference(params, t_out, **kw)
    return channels(*parallelogram_state(sol.y[0], sol.y[1], int(params["N"])), params)

"""Cost per modal point of xval against ROSS (a generic FE rotordynamics code) on the same
spinning cantilever shaft (issue 28's last acceptance line).

ROSS cannot share xval's environment (its plotting stack pins plotly < 6), so this runs in
two interpreters:

    python -m venv ross-env && ross-env/bin/pip install ross-rotordynamics 'plotly<6'
    ross-env/bin/python tools/ross_cost.py ross           # ROSS: frequencies and s/point
    python tools/ross_cost.py xval                        # xval's solvers: the same

The ROSS model: spinning-shaft's defaults (L 1.29 m, EI 582.996 N·m², m 2.87 kg/m) as 40
Euler–Bernoulli elements (no shear, no rotary inertia: the scene's model), a solid section
whose E and ρ give that EI and m, clamped at its root by two rigid supports 0.1 mm apart
(ROSS's bearings carry no moment). Each prints the first four frequencies at rest against
the clamped–free closed form (λ² = 3.516, 22.03, 61.70, 120.9 × ω₀) and the wall time per
modal point over spins 0 … 6 ω₀, best of three sweeps (ROSS dense, its faster path here:
sparse ARPACK took 4× longer per point).
"""
import sys
import time

import numpy as np

L, EI, M = 1.29, 582.996, 2.87
W0 = np.sqrt(EI / (M * L ** 4))                      # ω₀ [rad/s]
# roots of cos βL cosh βL = −1 to 17 digits (9 digits capped the printed errors at ~1e-9)
BETA_L = np.array([1.8751040687119611, 4.6940911329741746, 7.8547574382376126,
                   10.995540734875467])
EXACT_HZ = BETA_L ** 2 * W0 / (2 * np.pi)
SPINS = np.linspace(0.0, 6.0, 13)                    # Ω* = Ω/ω₀


def best_of_three(fn):
    """Seconds per point, best of three sweeps; each sweep's spins shifted by a hair, so that
    no answer comes from a cache (ROSS memoises run_modal by its arguments)."""
    times = []
    for k in range(3):
        t0 = time.perf_counter()
        for s in SPINS:
            fn(s + 1e-9 * (k + 1))
        times.append((time.perf_counter() - t0) / len(SPINS))
    return min(times)


def ross():
    import ross as rs
    d = 0.04
    area, inertia = np.pi * d ** 2 / 4, np.pi * d ** 4 / 64
    steel = rs.Material(name="shaft", rho=M / area, E=EI / inertia, G_s=EI / inertia / 2.6)
    clamp = 1e-4
    shaft = [rs.ShaftElement(L=clamp, idl=0, odl=d, material=steel, shear_effects=False,
                             rotary_inertia=False, gyroscopic=False)]
    shaft += [rs.ShaftElement(L=L / 40, idl=0, odl=d, material=steel, shear_effects=False,
                              rotary_inertia=False, gyroscopic=False) for _ in range(40)]
    rigid = 1e18        # the pair's moment stiffness k·d²/2 = 5e9 N·m/rad ≫ EI/L = 452
    bearings = [rs.BearingElement(n=i, kxx=rigid, cxx=0, scale_factor=0) for i in (0, 1)]
    rotor = rs.Rotor(shaft, [], bearings)
    f = np.sort(rotor.run_modal(speed=0.0, num_modes=16, sparse=False).wn)[:8:2] / (2 * np.pi)
    report("ROSS 2.3 (40 elements)", f,
           best_of_three(lambda s: rotor.run_modal(speed=s * W0, num_modes=16, sparse=False)))


def xval():
    from compare import solvers
    from compare.scenes import get_scene
    sc = get_scene("spinning-shaft")
    for name in sc.leaves:
        s = solvers.get_solver(name)
        base = sc.resolve({})
        m = solvers.modes(sc, s, base)
        f = np.sort(np.asarray(m.frequencies_hz))[:8:2]
        report(f"xval {name}", f, best_of_three(
            lambda r, s=s, base=base: solvers.modes(sc, s, {**base, "spin_ratio": float(r)})))


def report(name, f, per_point):
    rel = np.abs(np.asarray(f[:4]) / EXACT_HZ[:len(f)] - 1)
    print(f"{name}: {per_point * 1e3:.3g} ms per modal point; first frequencies "
          f"{', '.join(f'{x:.6g}' for x in f[:4])} Hz, rel. errors "
          f"{', '.join(f'{x:.1e}' for x in rel)}")


if __name__ == "__main__":
    {"ross": ross, "xval": xval}[sys.argv[1]]()

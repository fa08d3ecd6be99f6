# ---
# jupyter:
#   jupytext:
#     formats: py:percent
#     text_representation:
#       extension: .py
#       format_name: percent
#   kernelspec:
#     display_name: Python 3
#     language: python
#     name: python3
# ---

# %% [markdown]
# # Cross-validate a system of your own in ten minutes
#
# A plane pendulum — a point mass `m` on a massless rod `l`, angle θ from the downward
# vertical, no damping — run by two solvers: one of your own (scipy's DOP853 on the equation
# of motion θ'' = −(g/l) sin θ) and a MuJoCo model of the same pendulum. xval runs both,
# estimates each one's own error, and says whether they agree. Two closed forms check the
# pair independently: the period at amplitude θ0, T = 4 √(l/g) K(sin²(θ0/2)), and the speed
# at the bottom that takes the pendulum over the top, ω_c = 2 √(g/l).
#
# Your system lives in a package of your own — a *plug-in* — and xval finds it through the
# entry-point group `xval.scenes`: nothing inside xval is edited. The package has three
# modules: the scene (parameters, channels, allowances, regimes) and one *leaf* per solver.
# This page is a notebook kept as text ([own_system.py](own_system.py), jupytext's
# py:percent format); the tests run it as a script, in an empty folder. To run it as a
# notebook, with the docs extra (`pip install -e '.[docs]'`), in an empty folder:
# `jupytext --to ipynb -o own_system.ipynb PATH/TO/own_system.py` then
# `jupyter execute --inplace own_system.ipynb` (nbclient; or open it in Jupyter). The first
# cells write the package's files.

# %%
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
from scipy.special import ellipk


def write(path, text):
    """Write one file of the plug-in package (creating its folder)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text.lstrip("\n"))


# %% [markdown]
# ## 1. The scene: the single source of the system
#
# Parameters with defaults, units and ranges; the channels every solver reports, computed
# once from each solver's angle and rate (one implementation, so an agreement cannot hide a
# bookkeeping slip); the allowance — what the two models may differ by beyond their own
# error estimates; and a `regime`, which makes the scene mappable with `xval map`.
# `t_end` and `output_dt` say how the system is run, not what it is (`physical=False`), so
# `xval power` leaves them alone.

# %%
write("my_pendulum/my_pendulum/__init__.py", '"""A plane pendulum as an xval plug-in."""\n')
write("my_pendulum/my_pendulum/scene.py", '''
"""A plane pendulum: point mass m on a massless rod l, θ from the downward vertical, no
damping, so E = ½ m l² ω² − m g l cos θ is conserved."""
import numpy as np

from compare.contract import Channel
from compare.scenes.base import TimeScene
from compare.scenes.params import Param, positive

# each channel carries its unit: every plot and table reads it from here
CHANNELS = (Channel("theta", "rad"), Channel("omega", "rad/s"), Channel("energy", "J"),
            Channel("energy_balance", "J"))


def channels(params, theta, omega):
    """Every solver's channels from its angle and rate (one implementation for all)."""
    m, l, g = params["m"], params["l"], params["g"]
    energy = 0.5 * m * l**2 * omega**2 - m * g * l * np.cos(theta)
    return {"theta": theta, "omega": omega, "energy": energy,
            "energy_balance": energy - energy[0]}


def regime(params, trajectory):
    """`over the top` when |θ| passes π within the run, else `swings`."""
    over = np.nanmax(np.abs(trajectory.channels["theta"])) > np.pi
    return "over the top" if over else "swings"


SCENE = TimeScene(
    name="pendulum",
    title="Plane pendulum (tutorial)",
    source="xval's tutorial: a system of your own",
    leaves={"pendulum-scipy": "my_pendulum.scipy_leaf", "mujoco": "my_pendulum.mujoco_leaf"},
    params=(positive("m", 1.0, "kg", "bob mass"),
            positive("l", 1.0, "m", "rod length"),
            positive("g", 9.81, "m/s²", "gravity"),
            Param("theta0", 1.0, "rad", "initial angle", lo=-np.pi, hi=np.pi),
            Param("omega0", 0.0, "rad/s", "initial rate", lo=-100.0, hi=100.0),
            positive("t_end", 5.0, "s", "horizon", hi=1e3, physical=False),
            positive("output_dt", 0.01, "s", "output grid", physical=False)),
    channels=CHANNELS,
    # one ideal pendulum in both solvers: only their own errors separate them. Measured at
    # the defaults (`xval run pendulum`): every deviation within the two error estimates,
    # the largest 5.2e-10 of its channel's scale (energy); the allowance 1e-9 is 2× that,
    # its floor 1e-9 J keeps energy_balance (~0) from a zero allowance
    tolerances={c: ("rel+abs", 1e-9, 1e-9) for c in CHANNELS},
    key_channel="theta",
    energy_scale_channels=("energy",),
    regime=regime,
)

SCENES = (SCENE,)
# the solver this package adds (xval's `mujoco` serves the scene through `leaves`)
SOLVERS = ({"name": "pendulum-scipy", "engine": "scipy",
            "doc": "the pendulum's equation of motion on scipy's solve_ivp (tutorial)"},)
''')

# %% [markdown]
# ## 2. Your solver: a leaf
#
# A leaf is a module with `simulate(params, t_out, settings) -> LeafResult`, its accurate
# `DEFAULT_SETTINGS` and the `INTEGRATORS` it offers. `ADAPTIVE` names the error-controlled
# ones: xval then estimates the run's own error from a rerun at `rtol / 100`. A leaf never
# defaults a parameter (it receives them all, resolved by the scene) and reports a failure
# as a status, with the time and the reason, instead of raising.

# %%
write("my_pendulum/my_pendulum/scipy_leaf.py", '''
"""`pendulum-scipy`: θ'' = −(g/l) sin θ on scipy's solve_ivp."""
import numpy as np
from scipy.integrate import solve_ivp

from compare.contract import LeafResult, merge_settings

from .scene import channels

INTEGRATORS = ("dop853", "rk45")
ADAPTIVE = INTEGRATORS
DEFAULT_SETTINGS = {"integrator": "dop853", "rtol": 1e-10}


def simulate(params, t_out, settings=None):
    s = merge_settings(settings, DEFAULT_SETTINGS, INTEGRATORS)
    w2 = params["g"] / params["l"]
    sol = solve_ivp(lambda t, y: (y[1], -w2 * np.sin(y[0])), (0.0, t_out[-1]),
                    [params["theta0"], params["omega0"]], method=s["integrator"].upper(),
                    rtol=s["rtol"], atol=s["rtol"], dense_output=True)
    failed = not sol.success
    y = sol.sol(t_out)                                  # the method's own dense output
    y[:, t_out > sol.t[-1]] = np.nan                    # nothing after a failure
    return LeafResult(channels=channels(params, *y), settings=s,
                      stats={"steps": len(sol.t) - 1, "rhs_evals": sol.nfev},
                      status="diverged" if failed else "ok",
                      t_fail=float(sol.t[-1]) if failed else None,
                      reason=sol.message if failed else None)
''')

# %% [markdown]
# ## 3. The engine's leaf
#
# The same pendulum in MuJoCo: a hinge, the mass as a point inertial (MuJoCo needs a
# positive inertia: 1e-12 kg·m² against m l² = 1), its RK4 at a fixed step of 1 ms, ten steps
# per output sample, checked before anything runs (`check_settings`). A fixed step's own
# error comes from a rerun at half the step.

# %%
write("my_pendulum/my_pendulum/mujoco_leaf.py", '''
"""MuJoCo leaf: one hinge about −y, the bob a point inertial, RK4 at a fixed step."""
import mujoco
import numpy as np

from compare.contract import LeafResult, merge_settings

from .scene import channels

INTEGRATORS = ("rk4",)
DEFAULT_SETTINGS = {"integrator": "rk4", "dt": 1e-3}


def check_settings(settings, t_out=None):
    """Called for every solver before anything runs: bad settings stop the command there."""
    s = merge_settings(settings, DEFAULT_SETTINGS, INTEGRATORS)
    steps = (t_out[1] - t_out[0]) / s["dt"] if t_out is not None else 1.0
    if not s["dt"] > 0 or abs(steps - round(steps)) > 1e-9 * steps:
        raise ValueError(f"dt {s['dt']} must divide the output step into whole steps")
    return s


def simulate(params, t_out, settings=None):
    s = check_settings(settings, t_out)
    p = {k: float(v) for k, v in params.items()}
    xml = f"""<mujoco>
      <option timestep="{s['dt']!r}" integrator="RK4" gravity="0 0 {-p['g']!r}">
        <flag contact="disable"/></option>
      <worldbody><body><joint type="hinge" axis="0 -1 0"/>
        <inertial pos="0 0 {-p['l']!r}" mass="{p['m']!r}" diaginertia="1e-12 1e-12 1e-12"/>
      </body></worldbody></mujoco>"""
    model = mujoco.MjModel.from_xml_string(xml)
    data = mujoco.MjData(model)
    data.qpos[0], data.qvel[0] = p["theta0"], p["omega0"]
    n = round((t_out[1] - t_out[0]) / s["dt"])          # steps per output sample
    y = np.full((2, len(t_out)), np.nan)
    y[:, 0] = data.qpos[0], data.qvel[0]
    for i in range(1, len(t_out)):
        mujoco.mj_step(model, data, nstep=n)
        y[:, i] = data.qpos[0], data.qvel[0]
    return LeafResult(channels=channels(params, *y), settings=s,
                      stats={"steps": n * (len(t_out) - 1), "rhs_evals": -1})
''')

# %% [markdown]
# ## 4. Register it: one line in `pyproject.toml`
#
# The entry point names the scene module; its `SCENES` and `SOLVERS` are what xval adds.

# %%
write("my_pendulum/pyproject.toml", '''
[build-system]
requires = ["setuptools>=68"]
build-backend = "setuptools.build_meta"

[project]
name = "my-pendulum"
version = "0.1.0"
dependencies = ["xval"]

[project.entry-points."xval.scenes"]
pendulum = "my_pendulum.scene"
''')

# %% [markdown]
# In your own project you would now `pip install -e my_pendulum` and restart the kernel.
# Here the package goes into a folder `site/`, put first on the path, so the tutorial leaves
# your environment as it was. xval reads the entry points when it is first imported:
# import it after the install.

# %%
subprocess.run([sys.executable, "-m", "pip", "install", "-q", "--no-deps", "--target", "site",
                "./my_pendulum"], check=True)
sys.path.insert(0, str(Path("site").resolve()))
# and for the worker processes a map starts (a fresh interpreter each, run in a notebook)
os.environ["PYTHONPATH"] = os.pathsep.join(filter(None, [sys.path[0],
                                                         os.environ.get("PYTHONPATH")]))

import xval  # noqa: E402

print(xval.scenes()["pendulum"])           # ['pendulum-scipy', 'mujoco']
print(xval.show("pendulum"))               # parameters with default, unit, range

# %% [markdown]
# The command line sees it too: `xval list`, `xval show pendulum`, `xval run pendulum`,
# `xval map pendulum …` and campaign files treat it like a built-in scene.
#
# ## 5. Run both solvers and judge them
#
# `xval.run` runs each solver, reruns it tighter to estimate its own error on every channel,
# and compares every pair: `agree` when the largest deviation is within both error estimates
# plus the scene's allowance. `assert_agree` fails with the verdict table otherwise.

# %%
r = xval.run("pendulum", theta0=1.0, t_end=5)
print(r)
xval.assert_agree(r)

# %% [markdown]
# Agreement between two solvers is not yet correctness: they could share a mistake. The
# closed form is independent of both. The period at amplitude θ0 is
# T = 4 √(l/g) K(m) with m = sin²(θ0/2) (the complete elliptic integral of the first kind);
# measure it from the zero crossings of θ(t) in each solver's trajectory.

# %%
T_exact = 4 * np.sqrt(1.0 / 9.81) * ellipk(np.sin(1.0 / 2) ** 2)
for solver in ("pendulum-scipy", "mujoco"):
    tr = r[solver]
    t, th = tr.t, tr.channels["theta"]
    i = np.nonzero(np.sign(th[:-1]) != np.sign(th[1:]))[0]
    crossings = t[i] - th[i] * (t[i + 1] - t[i]) / (th[i + 1] - th[i])
    T = 2 * np.mean(np.diff(crossings))
    print(f"{solver}: period {T:.6f} s, closed form {T_exact:.6f} s")
    # measured 5.9e-8 s in both solvers: the crossings' linear interpolation, not the solvers
    assert abs(T - T_exact) < 6e-7, (solver, T, T_exact)
    # energy is conserved: drift measured 2.8e-9 J (scipy at rtol 1e-10), 4e-12 J (MuJoCo)
    assert np.max(np.abs(tr.channels["energy_balance"])) < 3e-8, solver

# %% [markdown]
# ## 6. Map where the behaviour changes
#
# `xval.map` answers the scene's question over a range instead of at a point: here, started
# at the bottom with rate ω0, does the pendulum swing or go over the top? A coarse grid, then
# each change of regime bisected until its bracket is ≤ `resolution` × the range, in every
# solver; the runs next to each crossing are rerun tighter for its error estimate, and two
# solvers agree when their crossings are within the resolution and both errors. The closed
# form puts the crossing at ω_c = 2 √(g/l). (Run as a script, the map says in one line that
# it runs in this process: a script's pool workers would run the script again. In a
# notebook, or under `if __name__ == "__main__":`, it uses a process pool.)

# %%
m = xval.map("pendulum", x="omega0=4:8", coarse=9, resolution=1e-3, record=False,
             theta0=0.0, t_end=5)
print(m)
omega_c = 2 * np.sqrt(9.81 / 1.0)
for solver, crossings in m["boundaries"].items():
    (c,) = crossings                      # one crossing: swings → over the top
    lo, hi = c["bracket"]
    print(f"{solver}: ω_c in [{lo:.5f}, {hi:.5f}] rad/s, closed form {omega_c:.5f}")
    assert lo <= omega_c <= hi, (solver, c["bracket"], omega_c)
assert all(v["verdict"] == "agree" for v in m["verdicts"])

# %% [markdown]
# ## Where next
#
# - `xval power pendulum` measures what an `agree` is worth: the smallest relative change of
#   each parameter, in one solver only, that the verdicts catch.
# - A campaign file with `scene = "pendulum"` runs it with everything else, resumably.
# - [Writing a plug-in](../plugins.md) lists every hook a scene can have; the example
#   package `examples/double_pendulum/` adds an Exudyn leaf, extremes and a default campaign
#   case.

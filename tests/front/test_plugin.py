"""Users' own systems as plug-ins: the example package examples/double_pendulum installed (into a
folder of its own, as `pip install` does) and driven through `xval` like a built-in scene; its
solvers checked against the small-oscillation closed form and energy conservation."""
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
G, L = 9.81, 1.0


@pytest.fixture(scope="module")
def plugin_path(tmp_path_factory):
    target = tmp_path_factory.mktemp("site")
    r = subprocess.run([sys.executable, "-m", "pip", "install", "-q", "--no-deps", "--target",
                        str(target), str(ROOT / "examples" / "double_pendulum")],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr[-2000:]
    return target


def xval(plugin_path, *args, cwd):
    env = {**os.environ, "PYTHONPATH": str(plugin_path)}
    return subprocess.run([sys.executable, "-m", "compare", *args], cwd=cwd, env=env,
                          capture_output=True, text=True)


# The module's command lines, run one after another in ONE fresh process with the plug-in on
# its path (`tests.conftest.xval`: `compare.cli.main` with its exit status and output caught),
# each as a user types it. A process per command started and imported everything seven times:
# the module took 48.5 CPU-s, 30.4 so. `python -m compare` itself, the entry point a user
# runs, is checked with `list`.
OSC = 1e-3                                       # the small-oscillation amplitude (rad)
COMMANDS = {
    "run": ["run", "double-pendulum", "--json", "--no-record", "--out", "run"],
    "osc": ["run", "double-pendulum", "--set", f"theta1_0={OSC}", "--set",
            f"theta2_0={np.sqrt(2) * OSC}", "--set", "t_end=6", "--set", "output_dt=0.001",
            "--json", "--no-record", "--out", "osc"],
    "bench": ["bench", "double-pendulum", "--repeats", "1", "--set", "t_end=1", "--out",
              "bench"],
    "extremes": ["extremes", "double-pendulum", "--strict", "--json", "--out", "extremes"],
    "map": ["map", "double-pendulum", "--x", "theta1_0=1:3", "--set", "theta2_0=0", "--solver",
            "dp-lagrange", "--resolution", "1e-2", "--coarse", "9", "--json", "--no-record",
            "--out", "map"],
    "campaign": ["campaign", "dp.toml", "--json", "--out", "campaign"],
    # the second run reuses every job (digest of the plug-in)
    "campaign again": ["campaign", "dp.toml", "--json", "--out", "campaign"]}
BATCH = ("import json, sys\n"
         "from tests.conftest import xval\n"
         "out = {k: xval(*a) for k, a in json.loads(sys.argv[1]).items()}\n"
         "sys.stdout.write(json.dumps(out))\n")


@pytest.fixture(scope="module")
def commands(plugin_path, tmp_path_factory):
    """(exit status, stdout, stderr) of each of COMMANDS, keyed as there, and their folder."""
    folder = tmp_path_factory.mktemp("commands")
    (folder / "dp.toml").write_text(
        'name = "dp"\n[[cases]]\nscene = "double-pendulum"\nset = { t_end = 1 }\n')
    env = {**os.environ, "PYTHONPATH": os.pathsep.join((str(plugin_path), str(ROOT)))}
    r = subprocess.run([sys.executable, "-c", BATCH, json.dumps(COMMANDS)], cwd=folder, env=env,
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr[-2000:]
    return json.loads(r.stdout), folder


def test_the_plugin_scene_is_listed_by_the_entry_point(plugin_path, tmp_path):
    r = xval(plugin_path, "list", cwd=tmp_path)
    assert r.returncode == 0, r.stderr[-2000:]
    assert "double-pendulum" in r.stdout and "plug-in: xval-double-pendulum" in r.stdout


def test_the_plugin_scene_runs_with_all_three_solvers(commands):
    rc, stdout, stderr = commands[0]["run"]
    assert rc == 0, stderr[-2000:]
    obj = json.loads(stdout)
    assert {x["solver"]: x["status"] for x in obj["runs"]} == {
        "dp-lagrange": "ok", "exudyn": "ok", "mujoco": "ok"}
    assert obj["comparisons"] and all(c["verdict"] == "agree" for c in obj["comparisons"])
    # energy conserved: no damping, no drive (measured |ΔE| ≤ 6.4e-12 J of ~30 J at defaults)
    for x in obj["runs"]:
        scale = max(abs(x["final"]["kinetic"]), abs(x["final"]["potential"]))
        assert abs(x["final"]["energy_balance"]) < 1e-10 * scale, x["solver"]


def test_small_oscillations_match_the_closed_form(commands):
    """Started in the slow normal mode (θ2 = √2 θ1 for equal masses and rods), every solver
    swings at ω = √((g/l)(2 − √2)); the period from the zero crossings of θ1 (five in 6 s:
    the period 2.62 s)."""
    rc, stdout, stderr = commands[0]["osc"]
    assert rc == 0, stderr[-2000:]
    w_exact = np.sqrt(G / L * (2 - np.sqrt(2)))
    runs = json.loads(stdout)["runs"]
    assert {run["solver"] for run in runs} == {"dp-lagrange", "exudyn", "mujoco"}
    for run in runs:
        with np.load(commands[1] / run["trajectory"]) as z:
            t, th = z["t"], z["theta1"]
        i = np.nonzero(np.sign(th[:-1]) != np.sign(th[1:]))[0]
        tz = t[i] - th[i] * (t[i + 1] - t[i]) / (th[i + 1] - th[i])    # linear interpolation
        period = 2 * np.mean(np.diff(tz))
        # amplitude 1e-3 shifts the frequency by ~a²/16 ≈ 6e-8; measured 8.6e-8 in every solver
        # over 6 s and 10 s alike (5 and 8 crossings): the horizon adds nothing to the check
        assert abs(2 * np.pi / period - w_exact) / w_exact < 1e-6, run["solver"]


def test_bench_extremes_and_campaign_work_on_the_plugin(commands):
    out = commands[0]
    rc, stdout, stderr = out["bench"]
    assert rc == 0, stderr[-2000:]
    assert "fastest" in stdout
    rc, stdout, stderr = out["extremes"]
    assert rc == 0, stderr[-2000:]
    assert json.loads(stdout)["n_failed"] == 0
    rc, stdout, stderr = out["map"]
    assert rc == 0, stderr[-2000:]
    cs = json.loads(stdout)["boundaries"]["dp-lagrange"]
    assert cs and all(np.ptp(c["bracket"]) <= 0.02 + 1e-12 for c in cs)
    for key in ("campaign", "campaign again"):
        rc, stdout, stderr = out[key]
        assert rc == 0, stderr[-2000:]
    s = json.loads(stdout)
    assert s["n_jobs"] == 3 and s["n_reused"] == 3


class _EP:
    def __init__(self, name, load):
        self.name, self.value, self._load, self.dist = name, f"fake.{name}:X", load, None

    def load(self):
        return self._load()


def test_a_broken_or_clashing_plugin_is_left_out_with_one_line(capsys):
    from compare.scenes import SCENES, load_plugins
    before = dict(SCENES)

    def broken():
        raise ImportError("no module named 'missing_dependency'")

    load_plugins([_EP("broken", broken), _EP("clash", lambda: [SCENES["rotor-spinup"]])])
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 2
    assert "plug-in broken" in err[0] and "missing_dependency" in err[0]
    assert "'rotor-spinup' left out: the name is taken" in err[1]
    assert SCENES == before

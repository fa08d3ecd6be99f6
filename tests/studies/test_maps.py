"""`xval map`: boundaries against an independent bisection, the batch path against single runs,
resume, Dask = process pool, work bounded before anything runs."""
import json
import subprocess
import sys

import numpy as np
import pytest

from compare import solvers
from compare.physics.rotor import constants
from compare.scenes import get_scene
from compare.workflows import map_run, maps
from compare.workflows.campaign import run_campaign
from tests.conftest import xval

BASE = {"eccentricity": 0.005, "t_end": 10}
RES = 1e-2                                    # of the torque range 2.5–3.5: brackets ≤ 0.01


def _passes(torque, solver, base=None):
    """The test's own reading of the spec: passage when |ω| over the last 10 % of the run stays
    above 1.1 × the forward critical speed √(k_eff / (I_t − I_p))."""
    sc = get_scene("rotor-spinup")
    p = sc.resolve({**BASE, **(base or {}), "torque": torque})
    tr = solvers.simulate(sc, solvers.get_solver(solver), p,
                          solvers.settings_for(solvers.get_solver(solver), sc.name,
                                               t_out=sc.output_grid(p)))
    w, t = tr.channels["omega_norm"], tr.t
    return bool(np.min(w[t >= 0.9 * t[-1]]) > 1.1 * constants(p)["forward_critical"])


def test_map_boundary_equals_an_independent_bisection_with_another_solver():
    plan = maps.plan_map("rotor-spinup", "torque=2.5:3.5", overrides=BASE,
                         solver_names=["quaternion"], resolution=RES, coarse=(5, 1))
    res = maps.run_map(plan)
    (c,) = res["boundaries"]["quaternion"]
    assert (c["from"], c["to"]) == ("capture", "passage")
    assert np.ptp(c["bracket"]) <= RES * 1.0 + 1e-12
    lo, hi = 2.5, 3.5                          # bisection with euler-vector, done here
    assert not _passes(lo, "euler-vector") and _passes(hi, "euler-vector")
    while hi - lo > RES:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if not _passes(mid, "euler-vector") else (lo, mid)
    # the two brackets overlap: the same crossing to within the resolution
    assert c["bracket"][0] <= hi and lo <= c["bracket"][1]
    assert abs(c["x"] - 0.5 * (lo + hi)) <= RES


def test_batch_path_returns_the_single_runs():
    sc = get_scene("rotor-spinup")
    s = solvers.get_solver("quaternion")
    p = sc.resolve({**BASE, "torque": 3.0})
    st = solvers.settings_for(s, sc.name, t_out=sc.output_grid(p))
    rows = maps.evaluate_chunk(sc.name, s.name, BASE, [{"torque": 2.0}, {"torque": 3.3}], st,
                               None)
    for row, torque in zip(rows, (2.0, 3.3)):
        q = sc.resolve({**BASE, "torque": torque})
        one = solvers.simulate(sc, s, q, st)
        assert row["label"] == sc.regime(q, one)
    # a point after the first skips the warm-up call: the trajectory is bit-identical
    a = solvers.simulate(sc, s, p, st)
    b = solvers.simulate(sc, s, p, st, warm_up=False)
    for ch in sc.channels:
        np.testing.assert_array_equal(a.channels[ch], b.channels[ch])


def _campaign(tmp_path, executor="local"):
    camp = {"name": "m", "maps": [{"name": "m1", "scene": "rotor-spinup", "x": "torque=2.5:3.5",
                                   "set": BASE, "solvers": ["quaternion"], "resolution": 0.05,
                                   "coarse": [3, 1]}]}
    path = tmp_path / "m.json"
    path.write_text(json.dumps(camp))
    return run_campaign(str(path), tmp_path / "out", executor=executor, workers=1)


def test_campaign_maps_resume_their_points(tmp_path):
    first = _campaign(tmp_path)
    (m,) = first["maps"]
    assert m["reused"] == 0 and m["boundaries"]["quaternion"]
    second = _campaign(tmp_path)
    (m2,) = second["maps"]
    assert m2["reused"] == sum(m["runs"].values()) and sum(m2["runs"].values()) == 0
    assert m2["boundaries"] == m["boundaries"]


def test_dask_map_equals_the_process_pool(tmp_path):
    pytest.importorskip("distributed")
    plan = maps.plan_map("rotor-spinup", "torque=2.5:3.5", overrides=BASE,
                         solver_names=["quaternion"], resolution=0.05, coarse=(3, 1))
    a = maps.map_to_folder(plan, tmp_path / "a", executor="local", workers=2, record=False)
    b = maps.map_to_folder(plan, tmp_path / "b", executor="dask", workers=2, record=False)
    assert a["points"] == b["points"] and a["boundaries"] == b["boundaries"]


def test_python_m_compare_maps_on_the_worker_pool(tmp_path):
    """`python -m compare` is `xval` (docs/commands/index.md): its map runs on the workers, not
    in the main process one point at a time as for a script that calls it unguarded."""
    r = subprocess.run([sys.executable, "-m", "compare", "map", "rotor-spinup", "--x",
                        "torque=2.5:3.5", "--set", "eccentricity=0.005", "--solver", "quaternion",
                        "--resolution", "0.2", "--coarse", "3", "--json", "--no-record",
                        "--out", str(tmp_path)], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert "running in this process" not in r.stderr
    assert json.loads(r.stdout)["scene"] == "rotor-spinup"


def test_campaign_map_takes_coarse_as_the_command_does(tmp_path):
    """`coarse = 3` in a campaign's [[maps]] is `--coarse 3` (it raised a TypeError); a string
    is one line, exit 2, nothing written."""
    f = tmp_path / "m.toml"
    body = ('name = "m"\n[[maps]]\nname = "m"\nscene = "rotor-spinup"\nx = "torque=2.5:3.5"\n'
            'solvers = ["quaternion"]\nresolution = 0.2\ncoarse = %s\n'
            'set = { eccentricity = 0.005 }\n')
    f.write_text(body % "3")
    rc, so, se = xval("campaign", str(f), "--out", str(tmp_path / "o"), "--json")
    assert rc == 0, se
    xs = {p["params"]["torque"] for p in json.loads(
        (tmp_path / "o" / "maps" / "m" / "map.json").read_text())["points"]}
    assert {2.5, 3.0, 3.5} <= xs
    f.write_text(body % '"3"')
    rc, so, se = xval("campaign", str(f), "--out", str(tmp_path / "bad"))
    assert rc == 2 and len(se.strip().splitlines()) == 1 and "coarse grid" in se, se
    assert not (tmp_path / "bad").exists()


def test_work_over_the_budget_is_refused_with_one_line(tmp_path):
    rc, _, err = xval("map", "rotor-spinup", "--x", "torque=1:5", "--y", "eccentricity=0:0.02",
                      "--max-jobs", "100", "--out", str(tmp_path / "o"), cwd=tmp_path)
    assert rc == 2 and "exceed the budget of 100 runs" in err
    assert len(err.strip().splitlines()) == 1 and not (tmp_path / "o").exists()
    f = tmp_path / "big.toml"
    f.write_text('[[cases]]\nscene = "rotor-spinup"\n'
                 'sweep = { torque = { start = 1.0, stop = 4.0, num = 1000000 } }\n')
    rc, _, err = xval("campaign", str(f), "--out", str(tmp_path / "o"), cwd=tmp_path)
    assert rc == 2 and "4000000 jobs" in err and "max_jobs" in err
    assert len(err.strip().splitlines()) == 1


def test_map_json_has_the_contract_fields(tmp_path):
    """contract.md's `xval map --json`: x with its unit, points with regime and value, the
    boundaries, the pairwise comparisons, each solver's points per second, the map's image."""
    rc, out, err = xval("map", "rotor-spinup", "--x", "torque=2.5:3.5", "--set",
                        "eccentricity=0.005", "--solver", "quaternion", "--solver",
                        "euler-vector", "--resolution", "0.05", "--coarse", "3", "--json",
                        "--out", str(tmp_path), cwd=tmp_path)
    assert rc == 0, err
    obj = json.loads(out)
    assert obj["scene"] == "rotor-spinup" and obj["y"] is None
    assert obj["x"] == {"name": "torque", "lo": 2.5, "hi": 3.5, "unit": "N·m"}
    for p in obj["points"]:
        assert {"params", "solver", "regime", "value", "status", "error_estimate"} <= set(p)
        assert p["value"] is None and p["regime"] in ("capture", "passage")
    for s in ("quaternion", "euler-vector"):
        (c,) = obj["boundaries"][s]
        assert {"x", "y", "bracket", "from", "to"} <= set(c) and c["y"] is None
        n = sum(p["solver"] == s for p in obj["points"])
        assert obj["points_per_s"][s] == pytest.approx(obj["runs"][s] / obj["run_wall_s"][s])
        assert obj["runs"][s] >= n > 0
    (v,) = obj["comparisons"]
    assert {v["a"], v["b"]} == {"quaternion", "euler-vector"} and v["verdict"] == "agree"
    assert obj["map"].endswith("map.png") and (tmp_path / obj["map"]).exists()
    for f in ("plot", "report", "recording"):
        assert (tmp_path / obj["files"][f]).exists()


def test_a_script_without_the_main_guard_maps_in_this_process(tmp_path):
    """`xval.map()` at a plain script's top level: spawned workers would import the script
    again and die (BrokenProcessPool); it runs in-process with one line saying what to add."""
    script = tmp_path / "plain.py"
    script.write_text(
        "import sys\nimport xval\n\n"
        "r = xval.map('rotor-spinup', 'torque=1:5', solvers=['quaternion'], resolution=0.2,\n"
        "             coarse=3, workers=2, record=False, t_end=0.5, out=sys.argv[1])\n"
        "print(*sorted(p['params']['torque'] for p in r['points'] if p['status'] == 'ok'))\n")
    r = subprocess.run([sys.executable, str(script), str(tmp_path / "o")], cwd=tmp_path,
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    assert r.stdout.split() == ["1.0", "3.0", "5.0"]          # the 3 coarse points, all ok
    (line,) = [ln for ln in r.stderr.splitlines() if ln.startswith("xval:")]
    assert str(script) in line and 'if __name__ == "__main__":' in line


def test_the_main_guard_is_read_from_the_scripts_source(tmp_path):
    """Where the call sits: at the top level (also through a function) it is unguarded; under
    `if __name__ == "__main__":` (either way round) it is not."""
    script = tmp_path / "s.py"
    script.write_text(
        "from compare.workflows.executors import unguarded_script\n"
        "def f():\n    return unguarded_script()\n"
        "print(unguarded_script() is not None, f() is not None)\n"
        "if __name__ == '__main__':\n    print(f() is not None)\n"
        "if '__main__' == __name__:\n    print(unguarded_script() is not None)\n")
    r = subprocess.run([sys.executable, str(script)], capture_output=True, text=True,
                       timeout=120)
    assert r.returncode == 0 and r.stdout.split() == ["True", "True", "False", "False"], r.stderr


def test_bench_points_runs_the_map_batch_path(tmp_path):
    """`xval bench --points N` runs N points per solver through the map's batch path and writes
    its report (the batch path's values are checked against single runs above)."""
    from compare.api import bench
    s = bench("rotor-spinup", ["quaternion"], points=4, out=tmp_path)
    (row,) = s["rows"]
    assert row["solver"] == "quaternion" and row["points"] == 4 and row["points_per_second"] > 0
    assert s.report.parent == tmp_path and (tmp_path / "bench.json").exists()


@pytest.mark.parametrize("args, words", [
    (["--x", "nope=1:2"], "nope: unknown parameter"),
    (["--x", "torque=3:1"], "LO must be below HI"),
    (["--x", "torque=1:5", "--y", "torque=0:1"], "same parameter"),
    (["--x", "torque"], "expected NAME=LO:HI"),
    (["--x", "torque=1:5", "--observable", "ripple"], "not a map observable"),
    (["--x", "torque=1:5", "--coarse", "1"], "at least 2 points"),
])
def test_bad_map_input_is_one_line_and_exit_2(tmp_path, args, words):
    rc, _, err = xval("map", "rotor-spinup", *args, "--out", str(tmp_path / "o"), cwd=tmp_path)
    assert rc == 2 and words in err, err
    assert len(err.strip().splitlines()) == 1 and not (tmp_path / "o").exists()


def test_sail_deployment_time_observable_is_the_payout_closed_form():
    """The whole blade is out at L/(r·ω) (the payout law), to the output step."""
    sc = get_scene("sail-deploy")
    s = solvers.get_solver("thread-spool-conservative")
    base = {"L": 0.5, "t_end": 30, "output_dt": 0.01}
    p = sc.resolve(base)
    st = solvers.settings_for(s, sc.name, t_out=sc.output_grid(p))
    rows = maps.evaluate_chunk(sc.name, s.name, base, [{"omega_spool": 3.5}, {"omega_spool": 7}],
                               st, "deployment_time")
    for row, w in zip(rows, (3.5, 7.0)):
        assert row["status"] == "ok"
        assert abs(row["value"] - 0.5 / (0.01 * w)) <= 0.01 + 1e-9     # one output step


def test_a_crossing_that_vanishes_at_the_tighter_setting_is_unconfirmed_not_wider():
    """Two crossings 3.5e-9 apart with error bars of 1e-12: disagree; the same pair where one
    crossing vanished at its tighter setting (no error bar) is `unconfirmed` — before, its
    error was 2·span, a window wide enough to agree with anything."""
    def crossing(x, **more):
        return {"x": x, "y": None, "from": "capture", "to": "passage",
                "bracket": [x - 1e-12, x + 1e-12], **more}
    a = [crossing(2.0, error=1e-12)]
    far = maps.compare_boundaries({"a": a, "b": [crossing(2.0 + 3.5e-9, error=2e-12)]}, 1e-12)
    assert far[0]["verdict"] == "disagree"
    gone = maps.compare_boundaries({"a": a, "b": [crossing(2.0 + 1e-13, error=None,
                                                           unconfirmed=True)]}, 1e-12)
    assert gone[0]["verdict"] == "unconfirmed" and "vanishes" in gone[0]["why"][0]


def _quaternion_and_mujoco(monkeypatch, mujoco_points=None):
    """rotor-spinup over torque 2.5–3.5 by quaternion and MuJoCo, run in this process (so a
    test can change what MuJoCo is given): the map's result and its printed summary."""
    from compare.results import MapResult
    if mujoco_points:                  # MuJoCo given other parameters, through the scene's own
        orig = maps.evaluate_chunk

        def chunk(scene, solver, base, points, settings, what):
            return orig(scene, solver, base, [mujoco_points(p) for p in points]
                        if solver == "mujoco" else points, settings, what)
        monkeypatch.setattr(map_run, "evaluate_chunk", chunk)   # where Runner calls it
    plan = maps.plan_map("rotor-spinup", "torque=2.5:3.5", overrides=BASE,
                         solver_names=["quaternion", "mujoco"], resolution=0.05, coarse=(3, 1))
    res = maps.run_map(plan)
    return res, str(MapResult(res))


def test_a_crossing_the_other_solver_does_not_find_is_disagree_never_dropped(monkeypatch):
    """MuJoCo given half the torque (1.25–1.75 N·m, all below the passage at ~3.05 N·m) finds
    no crossing where quaternion finds capture → passage: the pair disagrees, MuJoCo's own
    runs around quaternion's crossing say why, and the map's status counts it. Unchanged, the
    same map agrees (the control: the verdict can go both ways)."""
    res, text = _quaternion_and_mujoco(monkeypatch)
    (v,) = res["verdicts"]
    assert v["verdict"] == "agree" and res["status"]["status"] == "agree", v
    res, text = _quaternion_and_mujoco(monkeypatch, lambda p: {**p, "torque": 0.5 * p["torque"]})
    assert res["boundaries"]["mujoco"] == [] and len(res["boundaries"]["quaternion"]) == 1
    (v,) = res["verdicts"]
    assert v["verdict"] == "disagree" and "no counterpart in mujoco" in v["why"][0], v
    assert "mujoco reads capture" in v["why"][0]
    assert v["unmatched"] == [{"solver": "quaternion", "x": res["boundaries"]["quaternion"][0]
                               ["x"], "y": None, "outcome": "disagree"}]
    assert res["status"] == {"status": "disagree", "pairs": 1, "disagree": 1, "incomplete": 0,
                             "unconfirmed": 0, "no data": 0, "agree": 0}
    assert "quaternion vs mujoco: disagree" in text
    assert "0 of 1 solver pairs agree; 1 disagree (status: disagree)" in text
    from compare.output.map_plot import markdown
    assert "| quaternion ~ mujoco | disagree |" in "\n".join(markdown(res))


def test_a_solver_that_fails_makes_the_map_incomplete(monkeypatch):
    """Every MuJoCo run raising (alone and in its batch): its runs around quaternion's crossing
    failed, so the pair is `incomplete` (never agree, never left out), with the reason."""
    import reference_models.mujoco.rotor as leaf

    def boom(*args):
        raise RuntimeError("injected")
    monkeypatch.setattr(leaf, "simulate", boom)
    monkeypatch.setattr(leaf, "regimes", boom)
    res, text = _quaternion_and_mujoco(monkeypatch)
    (v,) = res["verdicts"]
    assert v["verdict"] == "incomplete" and "RuntimeError: injected" in v["why"][0], v
    assert res["status"]["status"] == "incomplete" and res["status"]["incomplete"] == 1
    assert "quaternion vs mujoco: incomplete" in text


def test_a_points_store_key_is_the_digest_of_its_whole_task():
    """The Runner builds its keys from a batch's shared parts serialised once; a stored point
    must keep the key it had when the whole task dict was serialised (campaigns resume on
    it): the same digest, for several solvers, settings and points in one batch."""
    sc = get_scene("rotor-spinup")
    runner = maps.Runner(sc, {"t_end": 10, "spin0": 5.0}, None, salt="s1")
    st_a, st_b = {"integrator": "dop853", "rtol": 1e-4, "atol": None}, {"rtol": 1e-11}
    tasks = [("quaternion", st_a, {"torque": 1.5, "eccentricity": 0.01}),
             ("euler-vector", st_b, {"torque": 2.0}), ("quaternion", st_b, {"torque": 2.0})]
    assert runner._keys(tasks) == [
        maps._digest({"scene": sc.name, "base": runner.base, "solver": s, "settings": st,
                      "point": pt, "what": None, "salt": "s1"}) for s, st, pt in tasks]


def test_a_chunk_resolves_its_points_as_resolve_does():
    """`Scene.resolve_many` (a map chunk's points against one resolved base) gives what
    `resolve({**base, **point})` gives, and refuses what it refuses."""
    from compare.errors import BadInput
    sc = get_scene("rotor-spinup")
    base = {"t_end": 2, "eccentricity": 0.01}
    points = [{"torque": 1.5}, {"torque": "2.5", "eccentricity": 0.0}, {"t_end": 4},
              {"gravity": "0,0,-1"}]
    for got, point in zip(sc.resolve_many(base, points), points):
        want = sc.resolve({**base, **point})
        assert got.keys() == want.keys()
        assert all(np.array_equal(got[k], want[k]) for k in want), point
    for bad in ({"torque": -1e9}, {"t_end": 0.015}, {"spin": 1.0}):
        with pytest.raises(BadInput):
            sc.resolve({**base, **bad})
        with pytest.raises(BadInput):
            sc.resolve_many(base, [{"torque": 1.0}, bad])


class _Regimes:
    """A stand-in runner: capture below a boundary, passage above it — at 2.0 for the accurate
    settings, at 2.0 + `shift` for the tighter ones (what the map's own runner answers)."""
    def __init__(self, shift):
        self.shift, self.tight = shift, {}

    def _key(self, solver, settings, pt):
        return (solver, repr(settings), repr(pt))

    def run(self, tasks):
        return [{"label": "capture" if pt["torque"] < 2.0 + (self.shift if st.get("tight")
                                                              else 0.0) else "passage"}
                for _, st, pt in tasks]


@pytest.mark.parametrize("shift, why", [(0.0, None), (0.0015, None), (0.003, "moves 0.0025"),
                                        (0.05, "vanishes")])
def test_a_crossing_moved_past_its_bracket_at_the_tighter_setting_is_unconfirmed(shift, why):
    """The bracket [1.9995, 2.0005] (resolution 1e-3) rerun at the tighter setting: a boundary
    there at 2.0015 is the location's own error (1.5e-3, within two brackets); at 2.003, or
    beyond the search at 2.05, the tighter setting answers otherwise — an error bar that wide
    is a window that agrees with anything, so the crossing is `unconfirmed` (seeded: a regime
    flip at the tighter setting)."""
    width = 1e-3
    found = [{"x": 2.0, "y": None, "bracket": [2.0 - width / 2, 2.0 + width / 2],
              "from": "capture", "to": "passage"}]
    maps.crossing_errors(_Regimes(shift), "s", {}, {"tight": True}, None, found,
                         maps.Axis("torque", 1.0, 5.0, "N·m"), width, None)
    (c,) = found
    if why is None:
        assert not c.get("unconfirmed") and c["error"] == pytest.approx(shift, abs=width / 2)
        return
    assert c["unconfirmed"] and c["error"] is None and why in c["unconfirmed_why"], c
    got = maps.compare_boundaries({"a": found, "b": [{**found[0], "unconfirmed": False,
                                                      "error": 0.0}]}, width)
    assert got[0]["verdict"] == "unconfirmed" and why in got[0]["why"][0]


def test_a_map_without_out_is_held_in_memory_until_saved(tmp_path, monkeypatch):
    """The API's map without `out` writes nothing (no temporary folder, nothing under the
    working folder) and `save` writes what `out=` writes: the same crossings as a map made
    into a folder."""
    from compare.api import map as api_map
    monkeypatch.chdir(tmp_path)
    kw = dict(solvers=["quaternion"], resolution=0.25, t_end=2, record=False)
    held = api_map("rotor-spinup", "torque=1:5", **kw)
    assert held.out_dir is None and held.report is None and not any(tmp_path.iterdir())
    made = api_map("rotor-spinup", "torque=1:5", out=tmp_path / "made", **kw)
    saved = held.save(tmp_path / "saved")
    assert {p.name for p in saved.iterdir()} >= {"map.json", "report.md", "map.png"}
    assert held.report == saved / "report.md"
    assert held["boundaries"] == made["boundaries"] and held["boundaries"]["quaternion"]

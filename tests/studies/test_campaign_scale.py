"""Campaign scale-out and durability: Dask gives the process pool's numbers; a campaign killed
(SIGKILL to its process group) while running jobs or while writing its reports loses nothing
that finished, leaves no cut file, and the rerun completes the report.

The numbers compared are the trajectories themselves (bit-identical: the same compiled model
with the same settings on any executor) and the recordings against the trajectory files.
"""
import json
import os
import signal
import subprocess
import sys
import time
import warnings
from pathlib import Path

import numpy as np

from compare.analysis.trajectory import Trajectory
from compare.output.recording import load_scalar_series
from tests.conftest import wait_for, xval

SPIN = {"name": "spin", "scene": "rotor-spinup", "set": {"t_end": 0.5},
        "solvers": ["euler-vector", "quaternion"]}


def _write(tmp_path, cases, name="c"):
    f = tmp_path / f"{name}.json"
    f.write_text(json.dumps({"name": name, "cases": cases}))
    return str(f)


def _trajectories(camp_dir):
    return {p.relative_to(camp_dir).as_posix(): Trajectory.load(p)
            for p in sorted(Path(camp_dir).rglob("*.npz")) if "jobs" not in p.parts}


def _children():
    import psutil
    return {p.pid for p in psutil.Process().children(recursive=True) if p.is_running()
            and p.status() != psutil.STATUS_ZOMBIE}


def test_dask_local_cluster_gives_the_process_pools_results(tmp_path):
    import distributed  # noqa: F401  (the test extra installs it: missing must fail, not skip)
    camp = _write(tmp_path, [{**SPIN, "solvers": ["euler-vector"],
                              "sweep": {"torque": [1.5, 3.0]}}])
    runs = {}
    for executor in ("local", "dask"):
        before = _children()                   # the local pool's parked workers among them
        out = tmp_path / executor
        rc, so, se = xval("campaign", camp, "--executor", executor, "--workers", "2",
                          "--out", str(out), "--json")
        assert rc == 0, se
        s = json.loads(so)
        assert s["n_jobs"] == 2 and s["n_run"] == 2 and s["n_crashed"] == 0
        runs[executor] = _trajectories(out)
    # the campaign's LocalCluster ended with it: its worker processes are gone (a Client
    # closes only a cluster it made: one passed in kept running in this process)
    wait_for(lambda: not (_children() - before), timeout=10, poll=0.05,
             what="the Dask cluster's processes outlived the campaign")
    assert sorted(runs["local"]) == sorted(runs["dask"]) and len(runs["local"]) == 2
    for name, a in runs["local"].items():
        b = runs["dask"][name]
        assert a.status == b.status == "ok"
        for ch in a.channels:
            np.testing.assert_array_equal(a.channels[ch], b.channels[ch], err_msg=name)
    assert (tmp_path / "dask" / "spin" / "sweep.png").stat().st_size > 0


def test_two_local_clusters_at_once_warn_nothing():
    """A second LocalCluster while one runs (two campaigns, or two xdist workers): its
    scheduler's HTTP routes must not ask for the taken port 8787 and warn."""
    from compare.workflows.executors import make_executor
    clusters = []
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        try:
            for _ in range(2):
                clusters.append(make_executor("dask", None, 1))
            assert [ex.submit(sum, [i, 1]).result() for i, (ex, _) in
                    enumerate(clusters)] == [1, 2]
        finally:
            for _, owned in clusters:
                for x in owned:
                    x.close()


def _start(camp, out):
    # one worker: killing mid-run is the check, not parallel jobs
    return subprocess.Popen([sys.executable, "-m", "compare", "campaign", camp, "--out", out,
                             "--json", "--workers", "1"], stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL, start_new_session=True)  # own group


def _kill_group(p):
    os.killpg(p.pid, signal.SIGKILL)
    p.wait(timeout=30)


def _wait_for(predicate, p, timeout=120.0, poll=0.001):
    t0 = time.perf_counter()
    while time.perf_counter() - t0 < timeout:
        if predicate():
            return True
        if p.poll() is not None:
            return False
        time.sleep(poll)
    return False


def _check_intact(camp_dir):
    """Every file that exists under its final name is complete: trajectories load, JSON
    parses, a recording holds every sample of every solver's channels."""
    for f in camp_dir.rglob("*.npz"):
        if not f.name.startswith("."):
            Trajectory.load(f)
    for f in camp_dir.rglob("*.json"):
        if not f.name.startswith("."):        # a killed writer's temporary is not a record
            json.loads(f.read_text())
    for rrd in camp_dir.rglob("run.rrd"):
        for npz in rrd.parent.glob("[!.]*.npz"):
            tr = Trajectory.load(npz)
            t, v = load_scalar_series(rrd, f"/omega_norm/{tr.solver}")
            assert len(t) == len(tr.t), f"{rrd} cut: {len(t)} of {len(tr.t)} samples"
            np.testing.assert_array_equal(v, tr.channels["omega_norm"])


def _case_complete(camp_dir, case):
    d = camp_dir / case
    return all((d / f).exists() for f in ("report.md", "run.rrd", "result.json", "case.json"))


def test_killed_while_running_jobs_resumes_without_loss(tmp_path):
    """Kill the campaign (and its workers) once the first job is stored: the rerun reuses the
    stored jobs, runs the rest, and the report lists every case."""
    slow = {"name": "slow", "scene": "rotor-spinup", "set": {"t_end": 2},
            "solvers": ["mujoco"]}
    camp = _write(tmp_path, [SPIN, slow])
    out = tmp_path / "logs"
    camp_dir = out
    p = _start(camp, str(out))
    stored = lambda: len(list((camp_dir / "jobs").glob("[!.]*.npz"))) >= 1   # noqa: E731
    assert _wait_for(stored, p, poll=0.01), "no job finished before the campaign ended"
    _kill_group(p)
    n_stored = len(list((camp_dir / "jobs").glob("[!.]*.npz")))
    assert not (camp_dir / "summary.json").exists()      # it really was stopped mid-way
    _check_intact(camp_dir)
    rc, so, se = xval("campaign", camp, "--out", str(out), "--json")
    assert rc == 0, se
    s = json.loads(so)
    assert s["n_reused"] == n_stored and s["n_run"] == 3 - n_stored
    assert {c["case"] for c in s["cases"]} == {"spin", "slow"}
    _check_intact(camp_dir)
    left = [f.name for f in camp_dir.rglob(".*") if f.name != ".lock"]
    assert not left, f"temporary files of the killed campaign left behind: {left}"
    assert _case_complete(camp_dir, "spin") and _case_complete(camp_dir, "slow")
    report = (camp_dir / "report.md").read_text()
    assert "## spin" in report and "## slow" in report


def test_killed_while_writing_a_recording_leaves_no_cut_file(tmp_path):
    """Kill the campaign while it writes a case's recording (its temporary file exists): the
    final name holds a complete recording or nothing, and the rerun completes the case."""
    case = {**SPIN, "set": {"t_end": 10}}              # 1001 samples: a write worth catching
    camp = _write(tmp_path, [case])
    out = tmp_path / "logs"
    case_dir = out / "spin"
    for _attempt in range(3):                           # the write lasts a fraction of a second
        p = _start(camp, str(out))
        writing = lambda: case_dir.is_dir() and any(     # noqa: E731
            e.name.startswith(".run.") for e in os.scandir(case_dir))
        caught = _wait_for(writing, p)
        if caught:
            _kill_group(p)
            break
        p.wait(timeout=60)
        (case_dir / "case.json").unlink(missing_ok=True)    # report again on the next try
        (case_dir / "run.rrd").unlink(missing_ok=True)
    assert caught, "never caught the recording being written"
    _check_intact(out)
    rc, so, se = xval("campaign", camp, "--out", str(out), "--json")
    assert rc == 0, se
    assert json.loads(so)["n_reused"] == 2
    _check_intact(out)
    assert _case_complete(out, "spin")

"""`kill -9` and `kill -TERM` of a running `xval campaign` / `xval map`: no process is left
behind (the pool's workers and the multiprocessing resource tracker die with the main process),
TERM takes the Ctrl-C path (one line saying how to resume, the lock released), and the rerun
resumes from what was stored. Provoked for real: each command runs in its own session, and
every process of that session is looked for in /proc after the kill."""
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from test_faults import SLOW

from tests.conftest import wait_for, xval

CAMPAIGN = SLOW % 4         # four ~3-s jobs: long enough to be killed mid-run
# the rotor's capture boundary along the torque over a long horizon: ~0.1 s a point
MAP = ["map", "rotor-spinup", "--x", "torque=1:5", "--solver", "euler-vector",
       "--set", "t_end=200", "--coarse", "9", "--resolution", "0.05", "--no-record"]


def _session(sid):
    """Live (not zombie) processes of session `sid`: the command and all it started."""
    out = []
    for d in Path("/proc").iterdir():
        if not d.name.isdigit():
            continue
        try:
            fields = (d / "stat").read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if int(fields[3]) == sid and fields[0] != "Z":
            out.append(int(d.name))
    return out


@pytest.mark.slow            # 4 × (start, kill, rerun to the end): ~2 min each on 2 busy cores
@pytest.mark.parametrize("sig", [signal.SIGKILL, signal.SIGTERM], ids=["KILL", "TERM"])
@pytest.mark.parametrize("what", ["campaign", "map"])
def test_a_killed_run_leaves_no_process_and_the_rerun_resumes(tmp_path, what, sig):
    out = tmp_path / "out"
    if what == "campaign":
        f = tmp_path / "slow.toml"
        f.write_text(CAMPAIGN)
        args = ["campaign", str(f), "--out", str(out)]
        store, pattern = out / "jobs", "*.npz"
    else:
        args = [*MAP, "--out", str(out)]
        store, pattern = out / "points", "*.json"
    p = subprocess.Popen([sys.executable, "-m", "compare", *args], stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, text=True, start_new_session=True)
    try:
        wait_for(lambda: list(store.glob(pattern)) or p.poll() is not None)
        assert p.poll() is None, p.communicate()[1]
        assert len(_session(p.pid)) >= 3          # main, workers, resource tracker
        os.kill(p.pid, sig)                       # the main process only, as `kill` does
        so, se = p.communicate(timeout=60)
        left = []
        for _ in range(50):                       # workers notice within WATCH_S
            left = [q for q in _session(p.pid) if q != p.pid]
            if not left:
                break
            time.sleep(0.1)
        assert not left, f"processes left: {left}"
    finally:
        if p.poll() is None:
            os.killpg(p.pid, signal.SIGKILL)
            p.communicate()
        for q in _session(p.pid):
            os.kill(q, signal.SIGKILL)
    kept = len(list(store.glob(pattern)))
    assert kept >= 1
    if sig == signal.SIGTERM:
        assert p.returncode == 130, se
        assert "Traceback" not in se
        lines = [ln for ln in se.splitlines() if "interrupted" in ln]
        assert len(lines) == 1 and f"resume with: xval {what}" in lines[0], se
        if what == "campaign":
            assert not (store.parent / ".lock").exists()
    else:
        assert p.returncode == -signal.SIGKILL
    rc, so, se = xval(*args, "--json")
    assert rc == 0, se
    obj = json.loads(so)
    assert obj["n_reused" if what == "campaign" else "reused"] >= kept

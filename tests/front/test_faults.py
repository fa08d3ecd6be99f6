"""Records that survive faults: a disk that fills during `xval run`, two campaigns on one
folder, Ctrl-C in a campaign. Each is provoked for real (a writer that raises ENOSPC after
writing part of its file; two real processes; SIGINT to a real process group)."""
import errno
import json
import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from compare.cli import main
from compare.output import guard
from tests.conftest import wait_for, xval


def _case(name, t_end, sweep):
    """One euler-vector case of the rotor spin-up at dt 1e-5 (RK4) over `t_end` s of spin."""
    return (f'[[cases]]\nname = "{name}"\nscene = "rotor-spinup"\nsolvers = ["euler-vector"]\n'
            f"dt = 1e-5\nset = {{ t_end = {t_end} }}\n" + (f"sweep = {sweep}\n" if sweep else ""))


# one job of euler-vector at dt 1e-5 over 20 s (RK4, error estimate at half the step) takes
# ~3 s on this machine (12 s under a load of 5): long enough to be killed mid-run (test_kill)
SLOW = 'name = "slow"\n' + _case("spin", 20, "{ torque = { start = 1.0, stop = 2.0, num = %d } }")
# two jobs of 0.2 s of spin: the campaign that owns the folder is held (SIGSTOP) while others
# try it, so the check does not race the jobs' length
TWO_QUICK = SLOW.replace("t_end = 20", "t_end = 0.2") % 2
# to interrupt: a quick job (0.2 s of spin), dispatched first, finishes while two slow ones (2 s
# of spin: ~0.4 s each, ~3 s under a load of 4) still run: the second has just begun
QUICK_AND_SLOW = ('name = "slow"\n' + _case("quick", 0.2, None)
                  + _case("spin", 2, "{ torque = [1.0, 2.0] }"))


@pytest.fixture
def popen():
    """Start `xval ARGS` in the background; whatever still runs at the end is killed (with its
    workers: each gets its own process group)."""
    started = []

    def start(args):
        # as from a terminal: SIGINT at its default, even where this test run inherited it
        # ignored (a shell's background job: then Python never raises KeyboardInterrupt)
        p = subprocess.Popen([sys.executable, "-m", "compare", *args], stdout=subprocess.PIPE,
                             stderr=subprocess.PIPE, text=True, start_new_session=True,
                             preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
        started.append(p)
        return p
    yield start
    for p in started:
        if p.poll() is None:
            os.killpg(p.pid, signal.SIGKILL)
            p.communicate()


def test_disk_full_during_run_one_line_no_partial_file_folder_marked(tmp_path, monkeypatch,
                                                                     capfd):
    real = np.savez
    calls = []

    def filling_savez(f, **arrays):          # the second file fills the disk half-way
        calls.append(1)
        if len(calls) == 2:
            f.write(b"PK\x03\x04" + b"\0" * 1000)
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        return real(f, **arrays)

    monkeypatch.setattr(np, "savez", filling_savez)
    out = tmp_path / "out"
    rc = main(["run", "rotor-spinup", "--solver", "euler-vector", "--solver", "quaternion",
               "--set", "t_end=0.2", "--no-record", "--out", str(out)])
    err = capfd.readouterr().err
    assert rc == 2                            # the contract's status for an output problem
    lines = [ln for ln in err.splitlines() if ln.startswith("xval: error:")]
    assert len(lines) == 1 and "Traceback" not in err
    assert "quaternion.npz" in lines[0] and os.strerror(errno.ENOSPC) in lines[0]
    run = out                                 # --out names the run's own folder
    names = sorted(p.name for p in run.iterdir())
    assert names == ["INCOMPLETE", "euler-vector.npz"]     # no partial, no temporary file
    assert guard.is_incomplete(run)
    monkeypatch.setattr(np, "savez", real)
    rc = main(["diff", str(run), str(run), "--out", str(tmp_path / "d")])
    err = capfd.readouterr().err
    assert rc == 2 and "incomplete run folder" in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "d").exists()


def test_second_campaign_on_the_same_folder_is_refused_naming_the_owner(tmp_path, popen):
    f = tmp_path / "slow.toml"
    f.write_text(TWO_QUICK)
    out = tmp_path / "out"
    first = popen(["campaign", str(f), "--out", str(out), "--workers", "1"])
    lock = out / ".lock"
    # its job store exists (a campaign folder to `xval diff`) once the first job has begun
    wait_for(lambda: (_owner(lock) and (lock.parent / "jobs").is_dir())
             or first.poll() is not None)
    os.killpg(first.pid, signal.SIGSTOP)      # alive and holding the lock while the others try
    try:
        assert first.poll() is None, first.communicate()
        assert _owner(lock) == first.pid
        rc, so, se = xval("campaign", str(f), "--out", str(out))
        assert rc == 2 and len(se.strip().splitlines()) == 1
        assert f"pid {first.pid}" in se and "in use" in se
        rc, so, se = xval("diff", str(lock.parent), str(lock.parent), "--out",
                          str(tmp_path / "d"))
        assert rc == 2 and f"a campaign is writing this folder (pid {first.pid}" in se
    finally:
        os.killpg(first.pid, signal.SIGCONT)
    so1, se1 = first.communicate(timeout=300)
    assert first.returncode == 0, se1
    assert "2 jobs (2 run, 0 reused)" in so1            # each job ran once, by the first
    assert len(list((out / "jobs").glob("*.npz"))) == 2
    assert not lock.exists()


def _owner(lock):
    """The pid in a lock file once it is written whole, else None."""
    try:
        return json.loads(lock.read_text())["pid"]
    except (OSError, ValueError):
        return None


def test_stale_lock_of_a_dead_process_is_taken_over_a_foreign_one_is_not(tmp_path):
    f = tmp_path / "tiny.toml"
    f.write_text('name = "tiny"\n[[cases]]\nscene = "rotor-spinup"\nsolvers = ["quaternion"]\n'
                 'set = { t_end = 0.2 }\n')
    folder = tmp_path / "out"
    folder.mkdir(parents=True)
    dead = subprocess.Popen(["true"])
    dead.wait()
    lock = folder / ".lock"
    lock.write_text(json.dumps({"pid": dead.pid, "host": "elsewhere.example", "since": "x"}))
    rc, so, se = xval("campaign", str(f), "--out", str(tmp_path / "out"))
    assert rc == 2 and f"pid {dead.pid} on elsewhere.example" in se    # cannot know: refused
    lock.write_text(json.dumps({"pid": dead.pid, "host": socket.gethostname(), "since": "x"}))
    rc, so, se = xval("campaign", str(f), "--out", str(tmp_path / "out"))
    assert rc == 0, se
    assert "stale lock" in se and not lock.exists()


def test_temporaries_of_a_killed_writer_are_removed_once_the_lock_is_held(tmp_path):
    """SIGKILL runs no cleanup: the half-written temporaries (mkstemp names) stay until the
    next process that holds the folder's lock; files that are not ours stay untouched."""
    folder = tmp_path / "campaign"
    (folder / "case").mkdir(parents=True)
    orphans = [folder / "case" / ".euler-vector.kz2ivdu0.npz", folder / ".summary.ab_c1234.json"]
    kept = [folder / ".gitignore", folder / "case" / "result.json", folder / ".lock.stale.77"]
    for f in orphans + kept:
        f.write_text("x")
    said = []
    with guard.folder_lock(folder, log=said.append):
        assert not any(f.exists() for f in orphans) and all(f.exists() for f in kept)
    assert said == [f"{folder}: 2 temporary file(s) of a stopped writer removed"]


def test_ctrl_c_stops_the_workers_keeps_finished_jobs_and_says_how_to_resume(tmp_path, popen):
    n = 3
    f = tmp_path / "slow.toml"
    f.write_text(QUICK_AND_SLOW)
    out = tmp_path / "out"
    store = out / "jobs"
    p = popen(["campaign", str(f), "--out", str(out)])
    # every job started (a worker opens its log first; a finished job's log goes when it stayed
    # empty, its .npz stays) and one finished: the two slow ones run
    # (stored results only: a running job's atomic temporary, `.name.XXXX.npz`, is no result)
    def stored():
        return [f for f in store.glob("*.npz") if not f.name.startswith(".")]
    wait_for(lambda: (len(stored()) >= 1
                      and len({f.stem for f in store.glob("*.log")}
                              | {f.stem for f in stored()}) == n)
             or p.poll() is not None)
    assert p.poll() is None
    workers = _children_of(p.pid)
    assert workers
    t0 = time.time()
    os.killpg(p.pid, signal.SIGINT)           # what a terminal's Ctrl-C does: the whole group
    so, se = p.communicate(timeout=60)
    stopped_in = time.time() - t0
    assert p.returncode == 130, se
    assert "Traceback" not in se and "KeyboardInterrupt" not in se
    lines = [ln for ln in se.splitlines() if "interrupted" in ln]
    assert len(lines) == 1 and "resume with: xval campaign" in lines[0]
    assert stopped_in < 15                    # the running jobs were ended, not waited for
    kept = len(stored())                      # waited for, the two running ones would be kept
    assert 1 <= kept < n and not list(store.glob(".*"))
    assert not (store.parent / ".lock").exists()
    rc, so, se = xval("diff", str(store.parent), str(store.parent), "--out", str(tmp_path / "d"))
    assert rc == 2 and "incomplete campaign folder" in se
    time.sleep(1)
    alive = [w for w in workers if _running(w)]
    assert not alive, f"workers left running: {alive}"
    rc, so, se = xval("campaign", str(f), "--out", str(out))
    assert rc == 0, se
    assert f"{n} jobs ({n - kept} run, {kept} reused)" in so


def _running(pid):
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


def _children_of(pid):
    """Processes whose parent is `pid` (the pool's workers outlive a careless parent)."""
    out = []
    for d in Path("/proc").iterdir():
        if d.name.isdigit():
            try:
                stat = (d / "stat").read_text()
            except OSError:
                continue
            if int(stat.rsplit(")", 1)[1].split()[1]) == pid:
                out.append(int(d.name))
    return out


def test_disk_full_on_a_real_300k_tmpfs(tmp_path):
    """The issue's reproduction: `xval run rotor-spinup` into a 300 KB tmpfs (root only)."""
    small = tmp_path / "small"
    small.mkdir()
    if os.geteuid() != 0 or subprocess.run(["mount", "-t", "tmpfs", "-o", "size=300k", "tmpfs",
                                            str(small)], capture_output=True).returncode:
        pytest.skip("cannot mount a tmpfs here (needs root)")
    try:
        rc, so, se = xval("run", "rotor-spinup", "--out", str(small))
        assert rc == 2
        (line,) = [ln for ln in se.splitlines() if ln.startswith("xval: error:")]
        assert os.strerror(errno.ENOSPC) in line and ".npz" in line and "Traceback" not in se
        run = small                                               # --out is the run's folder
        written = {p.name for p in run.iterdir()}
        assert "INCOMPLETE" in written and "result.json" not in written
        assert not [n for n in written if n.startswith(".")]     # no temporary left
        for n in written - {"INCOMPLETE"}:                        # what is there is whole
            with np.load(run / n) as z:
                assert len(z["t"]) == len(z["omega_norm"])
    finally:
        subprocess.run(["umount", str(small)], check=True)


def test_a_live_lock_found_stale_by_a_racing_process_is_put_back(tmp_path):
    """Two processes found the same dead owner; the first took over — the second, moving the
    lock aside, finds a live owner in it and puts it back instead of removing it."""
    mine = json.dumps({"pid": os.getpid(), "host": socket.gethostname(), "since": "now"})
    (tmp_path / ".lock").write_text(mine)
    guard._remove_stale(tmp_path / ".lock", None)
    assert (tmp_path / ".lock").read_text() == mine and len(list(tmp_path.iterdir())) == 1
    with pytest.raises(guard.BadInput, match=f"pid {os.getpid()} on"):
        with guard.folder_lock(tmp_path):
            pass

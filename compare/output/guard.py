"""Records that survive faults: a run folder marked incomplete until its result is in, a
campaign folder locked by the process writing it, and one line for a disk that fills up.

- `incomplete(folder)`: the marker `INCOMPLETE` is written before anything else and removed
  after the last file (result.json); a folder that still has it was stopped (disk full, kill,
  crash) and `xval diff` / `xval baseline save` refuse it with one line.
- `folder_lock(folder)`: `.lock` holds the owner's pid, host and start time, created with
  O_EXCL (two processes cannot both create it). A second campaign on the same folder is
  refused (BadInput, exit 2) naming the owner; a lock whose pid is dead on this host is stale
  and taken over (a lock from another host is never guessed stale: its pid means nothing here).
  Once the lock is held, the temporary files a killed writer left behind are removed.
- `write_failure(e)`: the one line for an OSError from writing (ENOSPC, EDQUOT, EFBIG, EROFS),
  naming the file (`atomic_path` sets `filename` to the target) and the cause.
"""
import datetime
import errno
import json
import os
import socket
from contextlib import contextmanager
from pathlib import Path

from ..atomic import remove_orphans
from ..errors import BadInput

MARKER = "INCOMPLETE"
LOCK = ".lock"
DISK_ERRNOS = (errno.ENOSPC, errno.EDQUOT, errno.EFBIG, errno.EROFS)


def mark_incomplete(folder, what="run"):
    """Write the marker (first, before any other file of the folder); returns its path, which
    the writer unlinks after its last file."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    marker = folder / MARKER
    marker.write_text(f"xval {what} started {_now()} by pid {os.getpid()} on "
                      f"{socket.gethostname()}; this file is removed when result.json is "
                      f"written: while it is here the folder is incomplete\n")
    return marker


@contextmanager
def incomplete(folder, what="run"):
    """Mark `folder` incomplete while the block writes it; the mark stays if the block fails."""
    marker = mark_incomplete(folder, what)
    yield Path(folder)
    marker.unlink(missing_ok=True)


def is_incomplete(folder):
    return (Path(folder) / MARKER).exists()


def write_failure(e: OSError):
    """One line for a failed write, or None when `e` is not a full/read-only disk."""
    if getattr(e, "errno", None) not in DISK_ERRNOS:
        return None
    return f"cannot write {e.filename or 'a file'}: {e.strerror or os.strerror(e.errno)}"


def _now():
    return datetime.datetime.now().astimezone().isoformat(timespec="seconds")


_PROC = os.path.isdir("/proc/self")


def alive(pid):
    """Process `pid` exists and is not a zombie. A zombie has ended: a killed command stays
    unreaped while its caller still reads the pipes its pool's workers hold open."""
    if pid > 0 and _PROC:
        try:
            with open(f"/proc/{pid}/stat", "rb") as f:
                state = f.read().rsplit(b")", 1)[1].split()[0]
        except FileNotFoundError:
            return False
        except OSError:
            pass                      # unreadable: ask the kernel below
        else:
            return state not in (b"Z", b"X")
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:           # exists, owned by someone else
        return True
    return True


def lock_owner(folder):
    """The lock's content ({pid, host, since}) when a live process holds it, else None."""
    path = Path(folder) / LOCK
    try:
        owner = json.loads(path.read_text())
    except FileNotFoundError:
        return None
    except (OSError, ValueError):
        return {"pid": None, "host": "?", "since": "?"}   # being written: treat as held
    if owner.get("host") == socket.gethostname() and not alive(int(owner.get("pid", 0))):
        return None
    return owner


def _remove_stale(path, log):
    """Move the stale lock aside (a rename: of two processes that found it stale only one
    gets it) and check it was the stale one, not a lock just taken by another process."""
    aside = path.with_name(f"{LOCK}.stale.{os.getpid()}")
    try:
        os.rename(path, aside)
    except FileNotFoundError:
        return                                 # another process moved it first
    try:
        owner = json.loads(aside.read_text())
        stale = owner.get("host") == socket.gethostname() and not alive(int(owner["pid"]))
    except (OSError, ValueError, KeyError, TypeError):
        stale = False
    if not stale:                              # a live lock: put it back, then refuse
        os.rename(aside, path)
        return
    aside.unlink()
    if log:
        log(f"{path}: stale lock of pid {owner['pid']} (no such process) taken over")


@contextmanager
def folder_lock(folder, command="xval campaign", log=None):
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / LOCK
    me = {"pid": os.getpid(), "host": socket.gethostname(), "since": _now(),
          "command": command}
    for _ in range(3):
        try:
            fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o644)
        except FileExistsError:
            owner = lock_owner(folder)
            if owner is not None:
                raise BadInput(f"{folder} is in use by {owner.get('command', 'xval')} (pid "
                               f"{owner.get('pid')} on {owner.get('host')} since "
                               f"{owner.get('since')}): wait for it to finish, or remove "
                               f"{path} if that process is gone") from None
            _remove_stale(path, log)
            continue
        with os.fdopen(fd, "w") as f:
            json.dump(me, f)
        break
    else:
        raise BadInput(f"{path}: could not take the lock (another process keeps creating it)")
    try:
        n = remove_orphans(folder)
        if n and log:
            log(f"{folder}: {n} temporary file(s) of a stopped writer removed")
        yield path
    finally:
        path.unlink(missing_ok=True)

"""Engine chatter goes to the job's log, not to the user's terminal.

Exudyn prints banners and "still under development" notes from C++ straight to file
descriptor 1, MuJoCo warnings go to fd 1/2, numba and numpy raise Python warnings. A job runs
inside `captured(log_path)`: both descriptors and Python's warnings are redirected into the
log file for its duration, and the text is returned so the campaign can put it in the report
(and show it with `--verbose`).
"""
import os
import sys
import warnings
from contextlib import contextmanager
from pathlib import Path


@contextmanager
def captured(log_path):
    """Redirect fd 1, fd 2 and Python warnings into `log_path` (overwritten); yields a list that
    holds the captured text (stripped) once the block has finished. A log that stays empty is
    removed."""
    log_path = Path(log_path)
    log_path.parent.mkdir(parents=True, exist_ok=True)
    out = []
    sys.stdout.flush()
    sys.stderr.flush()
    saved = os.dup(1), os.dup(2)
    with open(log_path, "wb") as f:
        os.dup2(f.fileno(), 1)
        os.dup2(f.fileno(), 2)
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("always")

                def show(message, category, filename, lineno, file=None, line=None):
                    os.write(2, f"{category.__name__}: {message} "
                                f"({Path(filename).name}:{lineno})\n".encode())
                warnings.showwarning = show
                yield out
        finally:
            sys.stdout.flush()
            sys.stderr.flush()
            os.dup2(saved[0], 1)
            os.dup2(saved[1], 2)
            os.close(saved[0])
            os.close(saved[1])
    out.append(log_path.read_bytes().decode(errors="replace").strip())
    if not out[0]:                     # nothing said: no empty log left behind
        log_path.unlink(missing_ok=True)


def distinct_lines(text, limit=20):
    """The log's lines once each, in order of first appearance (banners repeat per run)."""
    seen = dict.fromkeys(line.rstrip() for line in text.splitlines() if line.strip())
    lines = list(seen)
    return lines[:limit] + ([f"… {len(lines) - limit} more lines"] if len(lines) > limit else [])

"""Campaign progress on the terminal: a live bar on a TTY, plain lines otherwise.

The bar (rich) shows jobs done / total, the jobs running now, elapsed time and an ETA; it is
drawn on standard error, so `--json` output on standard output stays one object. When standard
error is not a terminal (a pipe, a CI log) each finished job is one line with a counter.
"""
import os
import sys
import time


def _fmt_s(s):
    return f"{s:.0f} s" if s < 120 else f"{s / 60:.1f} min"


class PlainProgress:
    """One line per event, each with the counter: `[3/12] case solver: ok in 1.2 s`."""

    def __init__(self, stream=None):
        self.stream = stream or sys.stderr
        self.total = self.done = 0
        self.t0 = time.perf_counter()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        return False

    def log(self, msg):
        print(msg, file=self.stream, flush=True)

    def start(self, total, reused):
        self.total, self.done = total, reused

    def running(self, names):
        pass

    def note(self, text):
        """What the main process is doing between jobs (e.g. writing a case's report)."""
        self.log(text)

    def finished(self, label, status, wall_s=None):
        self.done += 1
        wall = f" in {wall_s:.3g} s" if wall_s is not None else ""
        self.log(f"[{self.done}/{self.total}] {label}: {status}{wall} "
                 f"({_fmt_s(time.perf_counter() - self.t0)} elapsed)")


class RichProgress(PlainProgress):
    """A live bar: `campaign ━━━━━━╺━━━ 5/12 jobs · running: rotor/exudyn, press/mujoco
    0:00:41 ETA 0:01:10`; finished jobs scroll above it."""

    def __init__(self, stream=None):
        super().__init__(stream)
        from rich.console import Console
        from rich.progress import (
            BarColumn,
            MofNCompleteColumn,
            Progress,
            TextColumn,
            TimeElapsedColumn,
            TimeRemainingColumn,
        )
        from rich.table import Column
        self.console = Console(file=self.stream)
        self.bar = Progress(TextColumn("[bold]campaign"), BarColumn(bar_width=24),
                            MofNCompleteColumn(), TextColumn("jobs ·"), TimeElapsedColumn(),
                            TextColumn("elapsed · ETA"), TimeRemainingColumn(),
                            TextColumn("{task.description}", table_column=Column(
                                no_wrap=True, overflow="ellipsis", ratio=1)),
                            console=self.console, transient=False, refresh_per_second=4,
                            expand=True)
        self.task = None

    def __enter__(self):
        self.bar.start()
        return self

    def __exit__(self, *exc):
        self.bar.stop()
        return False

    def log(self, msg):
        self.bar.console.print(msg, markup=False, highlight=False)

    def start(self, total, reused):
        super().start(total, reused)
        self.task = self.bar.add_task("", total=total, completed=reused)

    def running(self, names):
        self.bar.update(self.task, description=f"· running {len(names)}: {', '.join(names)}"
                        if names else "· waiting for a worker")

    def note(self, text):
        self.bar.update(self.task, description=f"· {text}")

    def finished(self, label, status, wall_s=None):
        self.done += 1
        self.bar.update(self.task, completed=self.done)
        wall = f" in {wall_s:.3g} s" if wall_s is not None else ""
        self.log(f"{label}: {status}{wall}")      # finished jobs scroll above the bar


def busy(text, stream=None):
    """A spinner with `text` on a TTY (e.g. while models load and the plan is checked);
    nothing otherwise."""
    import contextlib
    stream = stream or sys.stderr
    if not stream.isatty():
        return contextlib.nullcontext()
    from rich.console import Console
    return Console(file=stream).status(text)


def progress_view(stream=None):
    """The bar or the plain lines, written to a duplicate of standard error: jobs and report
    phases redirect descriptors 1 and 2 into their logs, the user's terminal stays ours."""
    if stream is None:
        sys.stderr.flush()
        stream = os.fdopen(os.dup(sys.stderr.fileno()), "w", buffering=1,
                           encoding=sys.stderr.encoding, errors="replace")
    return RichProgress(stream) if stream.isatty() else PlainProgress(stream)

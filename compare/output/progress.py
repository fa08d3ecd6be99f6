"""Campaign progress on the terminal: a live bar on a TTY, plain lines otherwise.

The bar (rich) shows jobs done / total, the jobs running now, elapsed time and an ETA; it is
drawn on standard error, so `--json` output on standard output stays one object. When standard
error is not a terminal (a pipe, a CI log) each finished job is one line with a counter and
an ETA. Below: the counters of a study's own work (a map's runs, a response's speeds, …)
that workflows advance and the front door shows (`task`, `reporting`).
"""
import os
import sys
import time

# off a terminal, a counter's plain line comes every EVERY_S seconds or every EVERY_FRAC of
# its total (and at the end)
EVERY_S = 10.0
EVERY_FRAC = 0.1


def _fmt_s(s):
    return f"{s:.0f} s" if s < 120 else f"{s / 60:.1f} min"


class PlainProgress:
    """One line per event, each with the counter: `[3/12] case solver: ok in 1.2 s`."""

    def __init__(self, stream=None):
        self.stream = stream or sys.stderr
        self.total = self.done = self.reused = 0
        self.t0 = time.perf_counter()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        return False

    def log(self, msg):
        print(msg, file=self.stream, flush=True)

    def start(self, total, reused):
        self.total, self.done, self.reused = total, reused, reused

    def running(self, names):
        pass

    def note(self, text):
        """What the main process is doing between jobs (e.g. writing a case's report)."""
        self.log(text)

    def finished(self, label, status, wall_s=None):
        self.done += 1
        wall = f" in {wall_s:.3g} s" if wall_s is not None else ""
        elapsed = time.perf_counter() - self.t0
        # the jobs run now set the pace, not the reused ones
        eta = eta_s(self.done - self.reused, self.total - self.reused, elapsed)
        self.log(f"[{self.done}/{self.total}] {label}: {status}{wall} "
                 f"({_fmt_s(elapsed)} elapsed"
                 + (f", ETA {_fmt_s(eta)}" if eta is not None and self.done < self.total
                    else "") + ")")


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


class busy:
    """While the main process works before any job runs (models load, the plan is checked): a
    spinner with `text` on a TTY, counters (`task`) opened meanwhile shown in it (`text
    planning: 12/40 cases, ETA 9 s`). Off a terminal the text and the counters' plain lines
    start once the work has lasted `quiet_s`: bad input found before then stays the one line
    the contract promises (docs/contract.md), a long start-up is not silent."""

    def __init__(self, text, stream=None, quiet_s=EVERY_S, clock=time.monotonic):
        self.text, self.stream = text, stream or sys.stderr
        self.quiet_s, self.clock = quiet_s, clock
        self.status = None

    def __enter__(self):
        if self.stream.isatty():
            from rich.console import Console
            self.status = Console(file=self.stream).status(self.text)
            self.status.__enter__()
            view = _StatusView(self.status, self.text)
        else:
            view = _Deferred(self.stream, self.text, self.quiet_s, self.clock)
        self.reporting = reporting(view=view)
        self.reporting.__enter__()
        return self

    def __exit__(self, *exc):
        self.reporting.__exit__(*exc)
        if self.status is not None:
            self.status.__exit__(*exc)
        return False


class _Deferred(PlainProgress):
    """Plain lines that start `quiet_s` after it was made, the heading `text` first."""

    def __init__(self, stream, text, quiet_s, clock):
        super().__init__(stream)
        self.text, self.quiet_s, self.clock, self.t_start = text, quiet_s, clock, clock()
        self.said = False

    def log(self, msg):
        if self.clock() - self.t_start < self.quiet_s:
            return                     # a later line carries the count
        if not self.said:
            self.said = True
            super().log(self.text)
        super().log(msg)


class _StatusView(RichProgress):
    """A spinner standing in for the campaign's bar: notes become its text."""

    def __init__(self, status, text):          # no bar of its own: RichProgress.__init__ skipped
        self.status, self.text = status, text

    def note(self, text):
        self.status.update(f"{self.text} {text}")


def progress_view(stream=None):
    """The bar or the plain lines, written to a duplicate of standard error: jobs and report
    phases redirect descriptors 1 and 2 into their logs, the user's terminal stays ours."""
    if stream is None:
        sys.stderr.flush()
        stream = os.fdopen(os.dup(sys.stderr.fileno()), "w", buffering=1,
                           encoding=sys.stderr.encoding, errors="replace")
    return RichProgress(stream) if stream.isatty() else PlainProgress(stream)


# --- counted work inside a study: maps, response, power, calibration ---------------------------
# A workflow asks `task(label, total, unit)` for a counter and advances it; the front door
# decides where it shows (`reporting`): nothing by default (the Python API stays silent), a rich
# bar with count and ETA on a terminal, else a plain line every EVERY_S seconds or EVERY_FRAC of
# the total. Workflows never print: they only count.

def eta_s(done, total, elapsed):
    """Seconds left at the mean rate so far (elapsed / done per unit); None before the first."""
    if done <= 0 or total is None:
        return None
    return max(total - done, 0) * elapsed / done


def count_text(label, done, total, unit, elapsed):
    """`map: 120/780 runs, ETA 40 s` (ETA once a unit is done, `done` at the end)."""
    eta = eta_s(done, total, elapsed)
    tail = (f", done in {_fmt_s(elapsed)}" if total is not None and done >= total else
            f", ETA {_fmt_s(eta)}" if eta is not None else "")
    return f"{label}: {done}/{total if total is not None else '?'} {unit}{tail}".rstrip()


class Counter:
    """Counted work shown as plain lines through `emit`: at most one every `every_s` seconds,
    and one at each further `every_frac` of the total and at the end. `clock` is injectable
    (tests use a fake)."""

    def __init__(self, label, total, unit="", emit=None, clock=time.monotonic,
                 every_s=EVERY_S, every_frac=EVERY_FRAC):
        self.label, self.total, self.unit = label, total, unit
        self.emit = emit or (lambda text: None)
        self.clock, self.every_s, self.every_frac = clock, every_s, every_frac
        self.done = 0
        self.t0 = self.last = clock()
        self.step = max(1, int(round(every_frac * total))) if total else None
        self.mark = self.step

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False

    def text(self):
        return count_text(self.label, self.done, self.total, self.unit, self.clock() - self.t0)

    def advance(self, n=1, total=None):
        """n more units done; `total` where the work turned out larger (a map refines)."""
        if total is not None and total != self.total:
            self.total = total
            self.step = max(1, int(round(self.every_frac * total)))
            self.mark = (self.done // self.step + 1) * self.step
        self.done += n
        now = self.clock()
        at_mark = self.mark is not None and self.done >= self.mark
        final = self.total is not None and self.done >= self.total
        if at_mark or final or now - self.last >= self.every_s:
            self.emit(self.text())
            self.last = now
            if at_mark:
                self.mark = (self.done // self.step + 1) * self.step

    def close(self):
        pass


class RichCounter(Counter):
    """The same count as a live bar on a terminal:
    `map ━━━━╺━━ 120/780 runs 0:00:41 ETA 0:00:40`."""

    def __init__(self, label, total, unit="", stream=None, **kw):
        super().__init__(label, total, unit, **kw)
        from rich.console import Console
        from rich.progress import (
            BarColumn,
            MofNCompleteColumn,
            Progress,
            TextColumn,
            TimeElapsedColumn,
            TimeRemainingColumn,
        )
        self.bar = Progress(TextColumn("{task.description}"), BarColumn(),
                            MofNCompleteColumn(), TextColumn(unit), TimeElapsedColumn(),
                            TextColumn("ETA"), TimeRemainingColumn(),
                            console=Console(file=stream or sys.stderr), transient=False,
                            refresh_per_second=4)
        self.task = self.bar.add_task(label, total=total)
        self.bar.start()

    def advance(self, n=1, total=None):
        if total is not None:
            self.total = total
        self.done += n
        self.bar.update(self.task, completed=self.done, total=self.total)

    def close(self):
        self.bar.stop()                     # stopping twice is harmless


_SINKS = []          # the innermost `reporting` context: (stream, view) or nothing


class reporting:
    """Where `task` counters show while this context is active: on `stream` (default standard
    error) as a rich bar when it is a terminal, else plain lines; inside a campaign, through its
    `view` (the bar's description on a terminal, a plain line otherwise), one live display."""

    def __init__(self, stream=None, view=None):
        self.sink = (stream, view, [])       # the live bars opened here, stopped at exit

    def __enter__(self):
        _SINKS.append(self.sink)
        return self

    def __exit__(self, *exc):
        _SINKS.remove(self.sink)
        for bar in self.sink[2]:            # a study that raised left its bar running
            bar.close()
        return False


def task(label, total, unit=""):
    """A counter for `total` units of work called `label` (see `reporting`); silent outside a
    `reporting` context."""
    if not _SINKS:
        return Counter(label, total, unit)
    stream, view, live = _SINKS[-1]
    if view is not None:              # the campaign's bar: its description follows each unit
        if isinstance(view, RichProgress):
            return Counter(label, total, unit, emit=view.note, every_s=0.0)
        return Counter(label, total, unit, emit=view.log,
                       clock=getattr(view, "clock", time.monotonic))
    stream = stream or sys.stderr
    if stream.isatty():
        live.append(RichCounter(label, total, unit, stream=stream))
        return live[-1]
    return Counter(label, total, unit,
                   emit=lambda text: print(text, file=stream, flush=True))

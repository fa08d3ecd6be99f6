"""Progress of counted work (compare/output/progress.py): the plain lines' cadence (one every
10 s or every 10 % of the total, and one at the end) and the ETA arithmetic, on a fake clock."""
import io

from compare.output import progress


class Clock:
    def __init__(self):
        self.t = 0.0

    def __call__(self):
        return self.t


def test_eta_is_the_mean_rate_times_what_is_left():
    # 120 of 780 runs in 40 s: 1/3 s a run, 660 left -> 220 s = 3.7 min (by hand)
    assert progress.eta_s(120, 780, 40.0) == 220.0
    assert progress.eta_s(0, 780, 5.0) is None
    assert progress.count_text("map", 120, 780, "runs", 40.0) == "map: 120/780 runs, ETA 3.7 min"
    assert progress.count_text("map", 780, 780, "runs", 300.0) == "map: 780/780 runs, done in " \
        "5.0 min"


def test_plain_lines_every_tenth_and_every_ten_seconds():
    clock, lines = Clock(), []
    c = progress.Counter("map", 100, "runs", emit=lines.append, clock=clock)
    for _ in range(25):             # 25 runs, 0.1 s each: the 10 % marks only (10, 20)
        clock.t += 0.1
        c.advance()
    assert lines == ["map: 10/100 runs, ETA 9 s", "map: 20/100 runs, ETA 8 s"]
    clock.t += 10.0                 # one slow run: 10 s since the last line -> a line
    c.advance()
    assert lines[-1] == "map: 26/100 runs, ETA 36 s"      # 12.5 s / 26 runs × 74 left = 35.6 s
    for _ in range(74):
        clock.t += 0.1
        c.advance()
    assert lines[-1].startswith("map: 100/100 runs, done in ")
    # one line per further 10 % (30 … 100) after the timed one, none in between
    assert len(lines) == 2 + 1 + 8


def test_total_raised_keeps_counting():
    clock, lines = Clock(), []
    c = progress.Counter("map", 10, "runs", emit=lines.append, clock=clock)
    for _ in range(10):
        clock.t += 1.0
        c.advance()
    c.advance(5, total=20)          # the estimate fell short: 15 of 20 now
    assert c.total == 20 and c.done == 15


def test_silent_outside_reporting_and_plain_on_a_pipe():
    assert progress.task("x", 3, "runs").emit("anything") is None       # no sink: nothing
    out = io.StringIO()                                                  # not a terminal
    with progress.reporting(stream=out):
        c = progress.task("calibrate", 2, "parameter sets")
        c.advance()
        c.advance()
    assert out.getvalue().splitlines()[-1].startswith("calibrate: 2/2 parameter sets, done")


def test_campaign_start_up_says_what_it_does_off_a_terminal():
    """Off a terminal the start-up's lines begin after 10 s (bad input found sooner stays one
    line), the heading first, then the counter's lines."""
    out, clock = io.StringIO(), Clock()
    with progress.busy("checking the campaign …", stream=out, clock=clock):
        c = progress.task("planning", 40, "cases")
        for _ in range(8):                  # 8 cases in 8 s: quiet
            clock.t += 1.0
            c.advance()
        assert out.getvalue() == ""
        for _ in range(32):                 # the rest, 1 s each
            clock.t += 1.0
            c.advance()
    lines = out.getvalue().splitlines()
    assert lines[0] == "checking the campaign …"
    # the 10 % marks from 12 on (4 cases each), the first past the quiet 10 s
    assert lines[1] == "planning: 12/40 cases, ETA 28 s"        # 12 s / 12 × 28 left
    assert lines[-1] == "planning: 40/40 cases, done in 40 s"


def test_a_campaigns_job_lines_carry_an_eta_from_the_jobs_run_now():
    import time
    out = io.StringIO()
    v = progress.PlainProgress(out)
    v.start(5, 1)                   # one job reused: it took no time, it sets no pace
    v.t0 = time.perf_counter() - 10.0
    v.finished("a", "ok")
    v.finished("b", "ok")           # 2 of 4 run in 10 s: 2 left, 10 s
    assert out.getvalue().splitlines()[-1] == "[3/5] b: ok (10 s elapsed, ETA 10 s)"

"""Bad arguments: one line on standard error, exit 2, in well under a second of work, nothing
written — for paths, worker counts, repeats and work that would not fit (the size budget)."""
import subprocess
import sys
import time

import pytest

from tests.conftest import xval


@pytest.mark.parametrize("args, words", [
    (("run", "rotor-spinup", "--out", "/proc/x"), ["--out /proc/x"]),
    (("campaign", "--out", "/proc/x"), ["--out /proc/x"]),
    (("run", "rotor-spinup", "--out", "FILE"), ["exists and is not a folder"]),
    (("campaign", "--out", "FILE"), ["exists and is not a folder"]),
    (("bench", "rotor-spinup", "--out", "FILE"), ["exists and is not a folder"]),
    (("campaign", "--workers", "-1"), ["--workers", "at least 1"]),
    (("campaign", "--workers", "0"), ["--workers"]),
    (("bench", "rotor-spinup", "--repeats", "0", "--out", "OUT"), ["--repeats"]),
    (("campaign", "--scheduler", "tcp://x:1", "--out", "OUT"), ["--scheduler"]),
    (("run", "rotor-spinup", "--dt", "1e-12", "--out", "OUT"), ["--dt", "steps", "--max-steps"]),
])
def test_bad_argument_is_one_line_exit_2_and_writes_nothing(tmp_path, args, words):
    afile = tmp_path / "afile"
    afile.write_text("keep me\n")
    args = [str(afile) if a == "FILE" else str(tmp_path / "o") if a == "OUT" else a
            for a in args]
    rc, so, se = xval(*args)
    assert rc == 2 and so == ""
    lines = se.strip().splitlines()
    assert len(lines) == 1, se
    for w in words:
        assert w in lines[0]
    assert afile.read_text() == "keep me\n" and not (tmp_path / "o").exists()


@pytest.mark.parametrize("sets", [["output_dt=1e-9"], ["t_end=1", "output_dt=1e-9"]])
def test_a_runaway_output_grid_is_refused_before_anything_is_allocated(tmp_path, sets):
    """1e10 (1e9) samples × 8 arrays × 4 solvers × 8 bytes = 2.3 TiB (238 GiB): refused from
    t_end and output_dt alone; the process never grows past what the imports take (the
    MemoryError asked for 74.5 GiB, the kernel killed the t_end=1 run at 24 GB)."""
    rss = tmp_path / "maxrss"
    argv = ["run", "rotor-spinup", "--out", str(tmp_path / "o")]
    for s in sets:
        argv += ["--set", s]
    # the command line as `xval` runs it, plus its own peak resident size (VmHWM, kB) written to
    # a file — not getrusage's ru_maxrss, which a child started by fork/vfork + exec inherits
    # from its parent (this pytest worker's peak: 1046 MiB seen in one run)
    code = ("import sys; from compare.cli import main; rc = main(sys.argv[2:]); "
            "open(sys.argv[1], 'w').write(next(l.split()[1] for l in open('/proc/self/status')"
            " if l.startswith('VmHWM'))); sys.exit(rc)")
    t0 = time.perf_counter()
    p = subprocess.run([sys.executable, "-c", code, str(rss), *argv], capture_output=True,
                       text=True, timeout=120)
    wall = time.perf_counter() - t0
    peak_mib = int(rss.read_text()) / 1024
    assert p.returncode == 2 and p.stdout == ""
    assert len(p.stderr.strip().splitlines()) == 1 and "--max-output-gib" in p.stderr
    expect = "2.33 TiB" if len(sets) == 1 else "238 GiB"
    assert expect in p.stderr
    assert peak_mib < 1024, peak_mib          # imports only (~100 MiB measured)
    assert wall < 30                          # ~0.6 s alone; the imports under shared load
    assert not (tmp_path / "o").exists()


def test_every_option_of_every_subcommand_has_a_help_line():
    import argparse

    from compare.cli import build_parser
    sub = next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction))
    missing = [f"{name} {a.dest}" for name, p in sub.choices.items() for a in p._actions
               if not isinstance(a, argparse._HelpAction) and not (a.help or "").strip()]
    assert missing == []
    assert {c.dest for c in sub._choices_actions} == set(sub.choices)   # each command too
    assert all(c.help for c in sub._choices_actions)


def test_version_is_the_one_in_pyproject():
    """`xval --version`: exit 0, the version pyproject.toml declares (read here, not by xval)."""
    import tomllib
    from pathlib import Path
    declared = tomllib.loads((Path(__file__).parents[2] / "pyproject.toml").read_text())
    rc, so, se = xval("--version")
    assert rc == 0 and so.strip() == f"xval {declared['project']['version']}", se


def test_level_without_an_observable_is_refused(tmp_path):
    """--level of which observable? (rotor-spinup maps its regime: a level must not be
    dropped without a word)."""
    rc, so, se = xval("map", "rotor-spinup", "--x", "torque=1:5", "--level", "40",
                      "--out", str(tmp_path / "o"))
    assert rc == 2 and so == "" and len(se.strip().splitlines()) == 1, se
    assert "--level needs --observable" in se and not (tmp_path / "o").exists()


@pytest.mark.parametrize("command", ["map", "campaign"])
def test_more_workers_than_cores_is_one_warning_line_and_goes_on(command, monkeypatch, capsys,
                                                                  tmp_path):
    import importlib
    import os

    from compare.cli import main
    cores = len(os.sched_getaffinity(0))

    class Ran(Exception):
        pass

    def started(*a, workers=None, **kw):       # the study starts, with the workers asked for
        raise Ran(workers)
    monkeypatch.setattr(importlib.import_module(f"compare.commands.{command}"), command, started)
    argv = [command] + (["rotor-spinup", "--x", "torque=1:5"] if command == "map" else [])
    for n, warned in ((cores, False), (cores + 1, True)):
        with pytest.raises(Ran) as ran:
            main(argv + ["--workers", str(n), "--out", str(tmp_path / "o")])
        err = capsys.readouterr().err
        assert ran.value.args == (n,)
        assert err.count("\n") == warned and (f"more than the {cores} cores" in err) == warned


def test_to_pandas_without_pandas_names_the_extra(monkeypatch):
    """The message names an extra that pyproject.toml declares, pinned like the others."""
    import re
    import tomllib
    from pathlib import Path
    from types import SimpleNamespace

    import pyarrow as pa

    from compare.results import ModesResult, TimeResult
    extras = tomllib.loads((Path(__file__).parents[2] / "pyproject.toml").read_text())[
        "project"]["optional-dependencies"]
    arrow = pa.table({"t": [0.0]})                             # before pandas is hidden
    table = SimpleNamespace(to_arrow=lambda what: arrow)
    monkeypatch.setitem(sys.modules, "pandas", None)          # as if not installed
    for cls in (TimeResult, ModesResult):
        with pytest.raises(ImportError) as e:
            cls.to_pandas(table)
        extra = re.search(r"pip install 'xval\[(\w+)\]'", str(e.value)).group(1)
        assert re.fullmatch(r"pandas==[\d.]+", " ".join(extras[extra]))

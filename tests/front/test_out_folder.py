"""`--out DIR` is the result's folder (issue 49, item 6): a run's files land in DIR itself, a
campaign's too; `xval diff` takes the folders the user named; a non-empty DIR that holds
something else is refused (one line, exit 2, nothing written) unless --force; without --out the
default places under logs/ stay."""
import json

import pytest

from tests.conftest import xval

RUN = ("run", "rotor-spinup", "--solver", "quaternion", "--set", "t_end=0.3", "--no-record")


def test_two_runs_into_named_folders_then_diff_those_folders(tmp_path):
    for name, torque in (("A", "3.2"), ("B", "3.2")):
        rc, so, se = xval(*RUN, "--set", f"torque={torque}", "--out", str(tmp_path / name),
                          "--json")
        assert rc == 0, se
        assert json.loads(so)["runs"][0]["trajectory"] == str(tmp_path / name / "quaternion.npz")
        assert (tmp_path / name / "result.json").exists()
        assert not (tmp_path / name / "runs").exists()
    rc, so, se = xval("diff", str(tmp_path / "A"), str(tmp_path / "B"), "--json", "--out",
                      str(tmp_path / "d"))
    assert rc == 0, se
    assert json.loads(so)["summary"]["unchanged"] == 1


def test_the_same_command_again_writes_over_its_own_result(tmp_path):
    out = tmp_path / "A"
    for torque in ("3.2", "2.5"):
        rc, so, se = xval(*RUN, "--set", f"torque={torque}", "--out", str(out))
        assert rc == 0, se
    assert json.loads((out / "result.json").read_text())["params"]["torque"] == 2.5


@pytest.mark.parametrize("setup, says", [
    (lambda d: (d / "notes.txt").write_text("mine"), "holds other files"),
    (lambda d: (d / "runs" / "x").mkdir(parents=True), "earlier xval results under runs/"),
])
def test_a_folder_of_other_things_is_refused_unless_forced(tmp_path, setup, says):
    out = tmp_path / "o"
    out.mkdir()
    setup(out)
    before = sorted(p.relative_to(out) for p in out.rglob("*"))
    rc, so, se = xval(*RUN, "--out", str(out))
    assert rc == 2 and not so
    (line,) = se.strip().splitlines()
    assert says in line and "--force" in line
    assert sorted(p.relative_to(out) for p in out.rglob("*")) == before   # nothing written
    rc, so, se = xval(*RUN, "--out", str(out), "--force")
    assert rc == 0, se
    assert (out / "result.json").exists() and all((out / p).exists() for p in before)


def test_a_result_of_another_kind_is_refused(tmp_path):
    out = tmp_path / "o"
    assert xval("modes", "rotor-whirl", "--solver", "closed-form", "--out", str(out))[0] == 0
    rc, so, se = xval(*RUN, "--out", str(out))
    assert rc == 2 and "an xval modes result" in se and len(se.strip().splitlines()) == 1


def test_without_out_the_run_goes_under_logs_runs(tmp_path):
    rc, so, se = xval(*RUN, "--json", cwd=tmp_path)
    assert rc == 0, se
    (folder,) = (tmp_path / "logs" / "runs").iterdir()
    assert folder.name.startswith("rotor-spinup-")
    assert json.loads(so)["runs"][0]["trajectory"].startswith(str(folder.relative_to(tmp_path)))


def test_a_campaign_lands_in_the_folder_named(tmp_path):
    f = tmp_path / "tiny.toml"
    f.write_text('name = "tiny"\n[[cases]]\nscene = "rotor-spinup"\nsolvers = ["quaternion"]\n'
                 'set = { t_end = 0.2 }\n')
    out = tmp_path / "c"
    rc, so, se = xval("campaign", str(f), "--out", str(out), "--json")
    assert rc == 0, se
    assert (out / "summary.json").exists() and not (out / "campaign").exists()
    rc, so, se = xval("campaign", str(f), "--out", str(out), "--json")     # resumed in place
    assert rc == 0, se
    assert json.loads(so)["n_reused"] == 1


# bench, map, extremes, diff: --out DIR is their result's folder too; without it they keep
# their places under logs/ (logs/bench/<scene>-<stamp>/, logs/maps/…, logs/extremes/…,
# logs/diff/<time>-<pid>/)
STUDIES = {
    "bench": (("bench", "rotor-spinup", "--solver", "quaternion", "--repeats", "1", "--set",
               "t_end=0.1"), "bench.json", "bench"),
    "map": (("map", "rotor-spinup", "--x", "torque=2.5:3.5", "--solver", "quaternion",
             "--resolution", "0.2", "--coarse", "3", "--no-record", "--set", "t_end=0.5"),
            "map.json", "maps"),
    "extremes": (("extremes", "rotor-spinup", "--solver", "quaternion"), "result.json",
                 "extremes"),
    "diff": (("diff", "A", "A"), "diff.json", "diff"),
}


@pytest.mark.parametrize("name", STUDIES)
def test_each_study_lands_in_the_folder_named(tmp_path, name):
    args, json_name, old = STUDIES[name]
    if name == "diff":                   # two folders the user named: one run, diffed with itself
        assert xval(*RUN, "--out", str(tmp_path / "A"))[0] == 0
        args = ("diff", str(tmp_path / "A"), str(tmp_path / "A"))
    rc, so, se = xval(*args, "--json", cwd=tmp_path)              # no --out: under logs/
    assert rc == 0, se
    (folder,) = (tmp_path / "logs" / old).glob(f"*/{json_name}")
    assert json.loads((folder).read_text())["result"] == name
    out = tmp_path / "o"
    for _ in range(2):                   # the second writes over (a map reuses its points)
        rc, so, se = xval(*args, "--out", str(out), "--json")
        assert rc == 0, se
        obj = json.loads(so)
        assert obj["result"] == name and (out / json_name).exists()
        assert json.loads((out / json_name).read_text())["result"] == name
        assert obj["report"] == str(out / "report.md") and (out / "report.md").exists()
        assert not (out / old).exists()
    if name == "map":
        assert obj["reused"] > 0 and sum(obj["runs"].values()) == 0
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "notes.txt").write_text("mine")
    rc, so, se = xval(*args, "--out", str(mine))
    assert rc == 2 and not so
    (line,) = se.strip().splitlines()
    assert "holds other files" in line and "--force" in line
    assert [p.name for p in mine.iterdir()] == ["notes.txt"]      # nothing written


def test_a_stopped_study_and_an_old_root_are_told_apart(tmp_path):
    """A map stopped before its map.json (its points/ alone) and a bench before its bench.json
    (its reference trajectories) are that command's: the rerun resumes or writes over. An old
    `--out` root (DIR/bench/, DIR/maps/, …) is refused, naming what it holds."""
    from compare.errors import BadInput
    from compare.output.folders import claim_out
    (tmp_path / "m" / "points").mkdir(parents=True)
    (tmp_path / "b").mkdir()
    (tmp_path / "b" / "reference-quaternion.npz").write_bytes(b"")
    claim_out(tmp_path / "m", "map")
    claim_out(tmp_path / "b", "bench")
    with pytest.raises(BadInput, match="an xval map result .this command writes a bench"):
        claim_out(tmp_path / "m", "bench")
    (tmp_path / "root" / "maps" / "x").mkdir(parents=True)
    (tmp_path / "root" / "extremes").mkdir()
    with pytest.raises(BadInput, match="earlier xval results under maps/, extremes/ "):
        claim_out(tmp_path / "root", "map")


def test_an_identification_lands_in_the_folder_named(tmp_path):
    rec = tmp_path / "rec.csv"
    rc, so, se = xval("identify", "bearing-rotor", "--synthesise", str(rec), "--solver",
                      "quaternion", "--set", "t_end=0.5")
    assert rc == 0, se
    fit = ("identify", "bearing-rotor", "--data", str(rec), "--solver", "quaternion",
           "--unknown", "defect_height", "--no-profile", "--set", "t_end=0.5")
    for _ in range(2):                  # again into its own earlier result: written over
        rc, so, se = xval(*fit, "--out", str(tmp_path / "o"))
        assert rc == 0, se
    assert (tmp_path / "o" / "identify.json").exists()
    assert not (tmp_path / "o" / "runs").exists()
    rc, so, se = xval(*fit, "--out", str(tmp_path))           # holds rec.csv and o/
    assert rc == 2 and len(se.strip().splitlines()) == 1 and "--force" in se

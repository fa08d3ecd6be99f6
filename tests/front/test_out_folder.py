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

"""`xval diff` and baselines on a tiny campaign (2 cases × 2 rotor solvers, 0.5 s each) run
three times: twice as is (A, B) and once with the drive torque of one case changed by 1e-6
relative (C, from a copy of A: only that case's jobs run again). One worker per campaign: a
second would only add its start-up (imports, kernels loaded) to jobs of a fraction of a second."""
import json
import shutil

import numpy as np
import pytest

from compare.results import Result
from compare.results.records import RunRec
from compare.scenes import get_scene
from compare.workflows import diff as diff_mod
from compare.workflows import sides
from tests.conftest import xval

TORQUE = 2.0
TINY = """name = "tiny"
[[cases]]
name = "spin"
scene = "rotor-spinup"
solvers = ["euler-vector", "quaternion"]
set = { t_end = 0.5 }
[[cases]]
name = "drive"
scene = "rotor-spinup"
solvers = ["euler-vector", "quaternion"]
set = { t_end = 0.5, torque = %r }
"""


@pytest.fixture(scope="module")
def folders(tmp_path_factory):
    root = tmp_path_factory.mktemp("diff")
    (root / "tiny.toml").write_text(TINY % TORQUE)
    (root / "moved.toml").write_text(TINY % (TORQUE * (1 + 1e-6)))
    for name in ("A", "B"):
        rc, so, se = xval("campaign", str(root / "tiny.toml"), "--out", str(root / name),
                          "--workers", "1")
        assert rc == 0, se
    shutil.copytree(root / "A", root / "C")
    rc, so, se = xval("campaign", str(root / "moved.toml"), "--out", str(root / "C"),
                      "--workers", "1")
    assert rc == 0, se
    assert "2 run, 2 reused" in so            # only the changed case ran again
    return {k: root / k for k in "ABC"} | {"root": root}


def _diff(old, new, out):
    rc, so, se = xval("diff", str(old), str(new), "--json", "--out", str(out))
    return rc, (json.loads(so) if so.strip() else None), se


def _channels(obj, case, solver):
    c = next(c for c in obj["cases"] if c["case"] == case)
    return {ch["channel"]: ch for r in c["runs"] if r["solver"] == solver
            for ch in r["channels"]}


def test_same_campaign_twice_nothing_changed(folders, tmp_path):
    rc, obj, se = _diff(folders["A"], folders["B"], tmp_path)
    assert rc == 0, se
    n_channels = len(get_scene("rotor-spinup").channels)
    assert obj["summary"]["changed"] == 0 and obj["summary"]["unchanged"] == 4
    assert obj["summary"]["channels_unchanged"] == 4 * n_channels
    assert obj["lines"] == []


def test_torque_moved_by_1e_6_only_that_case_changed(folders, tmp_path):
    rc, obj, se = _diff(folders["A"], folders["C"], tmp_path)
    assert rc == 1, se
    states = {c["case"]: c["state"] for c in obj["cases"]}
    assert states == {"spin": "unchanged", "drive": "changed"}
    drive = next(c for c in obj["cases"] if c["case"] == "drive")
    assert drive["inputs"] == [f"torque 2 → {TORQUE * (1 + 1e-6):.10g}"]
    assert len(obj["lines"]) == 2 and all(ln.startswith("torque 2 → 2.000002: drive ")
                                          for ln in obj["lines"])
    # before resonance the spin obeys I_p dω_z/dt = τ: Δω_z(t_end) = Δτ t_end / (m R²/2)
    sc = get_scene("rotor-spinup")
    p = sc.resolve({"t_end": 0.5})
    expect = TORQUE * 1e-6 * 0.5 / (p["m"] * p["R"] ** 2 / 2)
    for solver in ("euler-vector", "quaternion"):
        ch = _channels(obj, "drive", solver)
        assert ch["spin_rate"]["state"] == "changed"
        # 1.0e-3 below it measured: the 5 mm eccentricity tilts the disk, and the torque
        # about the fixed z axis drives the spin about the tilted body axis a little less
        assert ch["spin_rate"]["max_abs"] == pytest.approx(expect, rel=3e-3)
        # the size and its error bars, recomputed here from the two stored trajectories
        a = np.load(folders["A"] / "drive" / f"{solver}.npz")
        c = np.load(folders["C"] / "drive" / f"{solver}.npz")
        for name in ("spin_rate", "omega_norm"):
            d = c[name] - a[name]
            scale = max(np.abs(a[name]).max(), np.abs(c[name]).max())
            bound = np.abs(a[f"error.{name}"]) + np.abs(c[f"error.{name}"]) + 1e-9 * scale
            k = np.argmax(np.abs(d) / bound)
            assert ch[name]["max_abs"] == pytest.approx(np.abs(d).max(), rel=1e-12)
            assert ch[name]["bound"] == pytest.approx(bound[k], rel=1e-12)
            assert ch[name]["t"] == pytest.approx(a["t"][k])
    report = tmp_path / "report.md"                  # --out is the report's own folder
    assert (tmp_path / "diff.json").exists() and not (tmp_path / "diff").exists()
    text = report.read_text()
    assert text.index("| runs (case × solver) | changed | unchanged | new | gone |") \
        < text.index("## spin")
    assert len(list(report.parent.glob("drive__*.png"))) == obj["summary"]["channels_changed"]
    saved = Result.load(report.parent)                   # the diff folder reads back
    assert type(saved).__name__ == "DiffResult" and saved.data == obj


def test_a_campaign_folder_loads_as_a_campaign_result(folders):
    """2 cases × 2 solvers: 4 jobs, every case with its two runs."""
    c = Result.load(folders["A"])
    assert type(c).__name__ == "CampaignResult" and c["n_jobs"] == 4
    assert {k: len(v.runs) for k, v in c.side().cases.items()} == {"spin": 2, "drive": 2}
    assert str(c).splitlines()[-1] == f"report: {folders['A'] / 'report.md'}"


def _rewrite(npz, edit):
    """Rewrite a stored trajectory in place with `edit(arrays, meta)` applied."""
    with np.load(npz) as z:
        arrays = {k: z[k] for k in z.files}
    meta = json.loads(str(arrays["meta"]))
    edit(arrays, meta)
    arrays["meta"] = np.array(json.dumps(meta))
    npz.unlink()                              # a hard link into jobs/: break it
    with open(npz, "wb") as f:
        np.savez(f, **arrays)


def test_a_faked_package_version_is_named_with_both_versions(folders, tmp_path):
    d = tmp_path / "D"
    shutil.copytree(folders["B"], d)
    npz = d / "spin" / "quaternion.npz"
    real = json.loads(str(np.load(npz)["meta"]))["versions"]["numpy"]
    _rewrite(npz, lambda a, m: m["versions"].update(numpy="9.9.9"))
    rc, obj, se = _diff(folders["B"], d, tmp_path / "o1")
    assert rc == 0, se                        # the same numbers: nothing moved
    assert obj["notes"] == [f"numpy {real} → 9.9.9: spin quaternion unchanged within its "
                            f"error bars"]

    def moved(a, m):                          # and now the numbers moved from mid-run on
        half = len(a["t"]) // 2
        a["omega_norm"][half:] *= 1 + 1e-6
    _rewrite(npz, moved)
    rc, obj, se = _diff(folders["B"], d, tmp_path / "o2")
    assert rc == 1, se
    (line,) = obj["lines"]
    assert line.startswith(f"numpy {real} → 9.9.9: spin quaternion omega_norm moved")


def test_baseline_is_compact_and_catches_a_1e_6_change_mid_trajectory(folders, tmp_path):
    base = tmp_path / "base.npz"
    rc, so, se = xval("baseline", "save", str(folders["A"]), str(base), "--json")
    assert rc == 0, se
    raw = sum(f.stat().st_size for f in folders["A"].glob("*/*.npz"))
    assert base.stat().st_size < raw
    rc, obj, se = _diff(base, folders["B"], tmp_path / "o1")
    assert rc == 0 and obj["summary"]["changed"] == 0, se
    rc, obj, se = _diff(base, folders["C"], tmp_path / "o2")
    assert rc == 1 and {c["case"]: c["state"] for c in obj["cases"]} == \
        {"spin": "unchanged", "drive": "changed"}
    d = tmp_path / "D"
    shutil.copytree(folders["A"], d)
    t_mid = []

    def bump(a, m):                           # tilt × (1 + 1e-6) over 10 samples mid-run
        i = len(a["t"]) // 2 + 3
        a["tilt"][i:i + 10] *= 1 + 1e-6
        t_mid.append(a["t"][i])
    _rewrite(d / "spin" / "euler-vector.npz", bump)
    rc, obj, se = _diff(base, d, tmp_path / "o3")
    assert rc == 1, se
    ch = _channels(obj, "spin", "euler-vector")
    assert [k for k, v in ch.items() if v["state"] == "changed"] == ["tilt"]
    assert t_mid[0] <= ch["tilt"]["t"] <= t_mid[0] + 10 * 0.01


def test_float32_would_not_do_for_a_baseline(folders):
    """The reason baselines keep float64: float32's rounding (6e-8 relative) is larger than
    the solvers' own error bars, so a float32 baseline would flag unchanged runs."""
    side = Result.load(folders["A"]).side()
    worst = 0.0
    for c in side.cases.values():
        for r in c.runs.values():
            for s in r.series().values():
                rounded = s.x.astype(np.float32).astype(float)
                scale = np.abs(s.x).max()
                bound = 2 * np.abs(s.err) + diff_mod.FLOOR_REL * scale
                worst = max(worst, float(np.max(np.abs(rounded - s.x) / bound)))
    assert worst > 10


def test_bad_input_one_line_exit_2(folders, tmp_path):
    rc, _, se = _diff(tmp_path, folders["A"], tmp_path / "o")
    assert rc == 2 and "not a campaign folder" in se and len(se.strip().splitlines()) == 1
    d = tmp_path / "D"
    shutil.copytree(folders["A"], d)
    summary = json.loads((d / "summary.json").read_text())
    summary["cases"][0]["scene"] = "press"
    (d / "summary.json").write_text(json.dumps(summary))
    rc, _, se = _diff(folders["A"], d, tmp_path / "o")
    assert rc == 2 and "different scenes" in se and len(se.strip().splitlines()) == 1
    assert not (tmp_path / "o").exists()
    (d / "summary.json").unlink()
    rc, _, se = _diff(folders["A"], d, tmp_path / "o")
    assert rc == 2 and "incomplete campaign folder" in se


def test_an_empty_or_cut_file_is_one_line_exit_2(folders, tmp_path, capsys):
    """An empty file, a baseline cut short, a run folder whose result.json or trajectory is
    cut: one line naming the file, exit 2 (a traceback's exit 1 would read as "changed")."""
    from compare.cli import main
    base = tmp_path / "base.npz"
    sides.save_baseline(folders["A"], base)
    run = tmp_path / "run"
    shutil.copytree(folders["A"] / "spin", run)
    for name in ("cut-json", "cut-npz"):
        shutil.copytree(run, tmp_path / name)
    result = tmp_path / "cut-json" / "result.json"
    result.write_text(result.read_text()[:200])
    npz = next((tmp_path / "cut-npz").glob("*.npz"))
    npz.write_bytes(npz.read_bytes()[:1000])
    (tmp_path / "empty.npz").write_bytes(b"")
    (tmp_path / "cut.npz").write_bytes(base.read_bytes()[:base.stat().st_size // 2])
    for old, new, bad, what in [
            ("empty.npz", folders["A"], "empty.npz", "empty file"),
            ("cut.npz", folders["A"], "cut.npz", "not a complete .npz"),
            ("cut-json", run, result, "broken JSON"),
            (run, "cut-npz", npz, "cannot be read")]:
        capsys.readouterr()
        rc = main(["diff", str(tmp_path / old), str(tmp_path / new), "--out",
                   str(tmp_path / "o")])
        so, se = capsys.readouterr()
        assert rc == 2 and so == "", se
        assert len(se.strip().splitlines()) == 1 and f"{tmp_path / bad}: " in se, se
        assert what in se, se
    assert main(["diff", str(base), str(folders["A"]), "--out", str(tmp_path / "o")]) == 0


def test_campaign_with_baseline_exits_1_when_results_moved(folders, tmp_path):
    base = tmp_path / "base.npz"
    sides.save_baseline(folders["A"], base)
    shutil.copytree(folders["root"] / "C", tmp_path / "C")
    rc, so, se = xval("campaign", str(folders["root"] / "moved.toml"), "--out",
                      str(tmp_path / "C"), "--baseline", str(base), "--workers", "1")
    assert rc == 1, se
    assert "torque 2 → 2.000002: drive euler-vector" in so
    assert (tmp_path / "C" / "diff" / "report.md").exists()


def test_pytest_helper_fails_with_the_diff_table(folders, tmp_path):
    from xval import assert_matches_baseline as check
    base = tmp_path / "base.npz"
    with pytest.raises(AssertionError, match="is missing"):
        check(folders["A"], base)                       # missing: fails, writes nothing
    assert not base.exists()
    with pytest.raises(AssertionError, match="baseline written"):
        check(folders["A"], base, create=True)          # asked: written
    assert base.exists()
    check(folders["B"], base)                           # same numbers: passes
    with pytest.raises(AssertionError) as e:
        check(folders["C"], base)
    assert "torque 2 → 2.000002: drive euler-vector" in str(e.value)
    assert "spin_rate" in str(e.value)


def test_frequencies_and_critical_speeds_against_the_relative_floor():
    f = [1.0, 10.0, 100.0]
    old = RunRec("mstmm", frequencies=f, labels=["a", "b", "c"])
    new = RunRec("mstmm", frequencies=[1.0, 10.0 * (1 + 2e-8), 100.0 * (1 + 5e-9)],
                       labels=["a", "b", "c"])
    rows = diff_mod.compare_modes(old, new, {"fw": 40.0}, {"fw": 40.0 * (1 + 3e-8)})
    assert [r["state"] for r in rows] == ["unchanged", "changed", "unchanged", "changed"]
    assert rows[1]["max_abs"] == pytest.approx(2e-7, rel=1e-6)
    fewer = RunRec("mstmm", frequencies=f[:2], labels=["a", "b"])
    assert diff_mod.compare_modes(old, fewer, {}, {})[0] == \
        {"channel": "number of modes", "state": "changed", "old": 3, "new": 2,
         "ratio": np.inf}


def test_map_boundaries_move_only_beyond_their_brackets(folders, tmp_path):
    def with_map(name, x):
        d = tmp_path / name
        shutil.copytree(folders["A"], d)
        (d / "capture-map").mkdir()
        (d / "capture-map" / "map.json").write_text(json.dumps(
            {"scene": "rotor-spinup", "boundaries": {"quaternion": [
                {"x": x, "y": None, "bracket": [x - 0.002, x + 0.002], "from": "capture",
                 "to": "passage"}]}}))
        return d
    a = with_map("a", 3.05)
    rc, obj, se = _diff(a, with_map("b", 3.0535), tmp_path / "o1")   # 3.5e-3 < 2e-3 + 2e-3
    assert rc == 0, se
    assert obj["maps"][0]["state"] == "unchanged"
    rc, obj, se = _diff(a, with_map("c", 3.0545), tmp_path / "o2")   # 4.5e-3 > 4e-3
    assert rc == 1, se
    assert obj["lines"] == ["map capture-map quaternion crossing 1 capture→passage: 3.05 → "
                            "3.0545 (moved 0.0045 against brackets 0.004)"]


def test_gone_cases_flipped_verdicts_and_statuses_count_as_changes(folders, tmp_path):
    d = tmp_path / "D"
    shutil.copytree(folders["A"], d)
    summary = json.loads((d / "summary.json").read_text())
    spin = next(c for c in summary["cases"] if c["case"] == "spin")
    summary["cases"] = [spin]                                    # "drive" is gone
    spin["comparisons"][0]["verdict"] = "disagree" if spin["comparisons"][0]["verdict"] \
        == "agree" else "agree"
    spin["runs"][1]["status"] = "diverged"
    (d / "summary.json").write_text(json.dumps(summary))
    rc, obj, se = _diff(folders["A"], d, tmp_path / "o")
    assert rc == 1, se
    assert obj["summary"]["cases_gone"] == 1
    c0 = spin["comparisons"][0]
    assert f"spin: verdict {c0['a']}–{c0['b']} {c0['channel']} " in "\n".join(obj["lines"])
    solver = spin["runs"][1]["solver"]
    assert f"same inputs digest: spin {solver} status ok → diverged" in obj["lines"]
    assert "drive (rotor-spinup): case gone" in obj["lines"]


def test_two_run_folders(tmp_path):
    runs = []
    for k in range(2):
        rc, so, se = xval("run", "rotor-spinup", "--solver", "quaternion", "--set", "t_end=0.3",
                          "--no-record", "--out", str(tmp_path / f"r{k}"), "--json")
        assert rc == 0, se
        runs.append(tmp_path / f"r{k}")                 # --out names the run's folder
    rc, obj, se = _diff(runs[0], runs[1], tmp_path / "o")
    assert rc == 0 and obj["summary"]["unchanged"] == 1, se
    assert obj["old_kind"] == obj["new_kind"] == "run"


def test_baseline_must_not_be_the_folder_the_campaign_writes(folders):
    rc, so, se = xval("campaign", str(folders["root"] / "tiny.toml"), "--out",
                      str(folders["root"] / "A"), "--baseline", str(folders["A"]))
    assert rc == 2 and "is the folder this campaign writes" in se
    assert len(se.strip().splitlines()) == 1


def test_a_frequency_case_moved_by_1e_6_in_stiffness(tmp_path):
    """rotor-whirl at rest: ω² = k_eff / I_t with k_eff = k − m g l, so k × (1 + 1e-6) moves
    each whirl frequency by ½ · 1e-6 · k / k_eff relative — beyond the 1e-8 floor."""
    outs = []
    for k, stiff in enumerate((2000.0, 2000.0 * (1 + 1e-6))):
        f = tmp_path / f"w{k}.toml"
        f.write_text(f'name = "w"\n[[cases]]\nname = "whirl"\nscene = "rotor-whirl"\n'
                     f'solvers = ["closed-form"]\nset = {{ k = {stiff!r} }}\n')
        rc, so, se = xval("campaign", str(f), "--out", str(tmp_path / f"o{k}"))
        assert rc == 0, se
        outs.append(tmp_path / f"o{k}")
    rc, obj, se = _diff(outs[0], outs[1], tmp_path / "d")
    assert rc == 1, se
    rows = _channels(obj, "whirl", "closed-form")
    p = get_scene("rotor-whirl").resolve({})
    k_eff = 2000.0 - p["m"] * abs(p["gravity"][2]) * p["l"]
    for name, row in rows.items():
        assert row["state"] == "changed", name
        assert row["max_rel"] == pytest.approx(0.5e-6 * 2000.0 / k_eff, rel=1e-3), name
    assert {n.split(" (")[0] for n in rows} >= {"mode 1", "mode 2"}


def test_two_map_folders_and_a_baseline_of_one(tmp_path):
    """`xval map` folders (map.json: boundaries per solver as {x, y, bracket, from, to})."""
    def folder(name, x):
        d = tmp_path / name
        d.mkdir()
        (d / "map.json").write_text(json.dumps(
            {"scene": "rotor-spinup", "boundaries": {"quaternion": [
                {"x": x, "y": None, "bracket": [x - 1e-3, x + 1e-3], "from": "capture",
                 "to": "passage"}]}}))
        return d
    a, b, c = folder("a", 3.0), folder("b", 3.0015), folder("c", 3.0025)
    assert _diff(a, b, tmp_path / "o")[0] == 0          # 1.5e-3 within 1e-3 + 1e-3
    rc, obj, se = _diff(a, c, tmp_path / "o")
    assert rc == 1 and obj["maps"][0]["map"] == "rotor-spinup", se
    base = tmp_path / "base.npz"
    sides.save_baseline(a, base)
    assert _diff(base, c, tmp_path / "o")[0] == 1

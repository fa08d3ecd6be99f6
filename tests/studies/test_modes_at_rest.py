"""Numbers a rotor engineer can quote (issue 49, item 8): at rest a whirl pair has no sense of
whirl (forward and backward are one degenerate pair: no forward/backward label), and no number
is printed or written as −0."""
import json
import re

from compare.atomic import num, write_json
from tests.conftest import xval

MINUS_ZERO = re.compile(r"(?<![\w.])-0(\.0*)?(?![\d.e])")


def test_at_rest_no_whirl_sense_and_no_minus_zero(tmp_path):
    """rotor-whirl at Ω = 0: its two tilt modes are one frequency, √(k_eff/I_t), whirl '—';
    the undamped closed form's ζ of the second root is −0.0 in floating point (its real part),
    which neither the text, the JSON printed nor the JSON written shows."""
    rc, so, se = xval("modes", "rotor-whirl", "--solver", "closed-form", "--set", "spin=0",
                      "--out", str(tmp_path / "t"))
    assert rc == 0, se
    lines = [ln for ln in so.splitlines() if " Hz (" in ln]
    assert len(lines) == 2 and not any("forward" in ln or "backward" in ln for ln in lines)
    assert not MINUS_ZERO.search(so), so
    rc, so, se = xval("modes", "rotor-whirl", "--solver", "closed-form", "--set", "spin=0",
                      "--json", "--out", str(tmp_path / "j"))
    (run,) = json.loads(so)["runs"]
    assert run["whirl"] == ["—", "—"] and run["zeta"] == [0.0, 0.0]
    assert not MINUS_ZERO.search(so) and not MINUS_ZERO.search(
        (tmp_path / "j" / "result.json").read_text())
    assert "forward" not in (tmp_path / "j" / "report.md").read_text().split("## ")[0]


def test_spinning_the_senses_come_back():
    rc, so, se = xval("modes", "rotor-whirl", "--solver", "closed-form", "--set", "spin=41.3",
                      "--json")
    (run,) = json.loads(so)["runs"]
    assert run["whirl"] == ["backward", "forward"]


def test_the_format_helper_and_the_json_writer_drop_the_sign_of_zero(tmp_path):
    assert num(-0.0, ".3g") == "0" and num(-1e-20, ".3g") == "-1e-20"
    write_json(tmp_path / "z.json", {"a": [-0.0, 0.0, -1.5]})
    assert (tmp_path / "z.json").read_text().split() == ['{', '"a":', '[', '0.0,', '0.0,',
                                                         '-1.5', ']', '}']

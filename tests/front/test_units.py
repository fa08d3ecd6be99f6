"""Units on input (issue 49, item 7): `--set spin=400rpm`, `--set l=60cm` through pint, converted
to the parameter's declared unit; a plain number keeps meaning that unit; the JSON keeps it."""
import json
import math
import subprocess
import sys

import pytest

import xval
from compare.errors import BadInput
from compare.scenes import SCENES, get_scene
from compare.scenes.units import unit_of
from tests.conftest import xval as cli

WHIRL = get_scene("rotor-whirl")
SPINUP = get_scene("rotor-spinup")


@pytest.mark.parametrize("name", sorted(SCENES))
def test_every_declared_unit_reads_in_pint(name):
    """Every numeric parameter's unit string is one pint reads, and a value given in it comes
    back unchanged (1 of the unit is 1 of the unit)."""
    for p in SCENES[name].params:
        if p.kind in ("float", "int", "vector"):
            unit_of(p.unit)
            if p.kind == "float" and p.unit:
                assert p._number(f"1 {p.unit.replace('·', '*')}") == pytest.approx(1.0), p.name


def test_quantities_convert_to_the_declared_unit():
    """Conversions written out here: 400 rpm = 400·2π/60 rad/s, 60 cm = 0.6 m, 3° = π/60 rad,
    2 rev/s = 4π rad/s, 2 kN·m/rad = 2000 N·m/rad, −981 cm/s² = −9.81 m/s²."""
    p = WHIRL.resolve({"spin": "400rpm", "l": "60cm", "k": "2 kN*m/rad"})
    assert p["spin"] == pytest.approx(400 * 2 * math.pi / 60, rel=1e-15)
    assert p["l"] == pytest.approx(0.6, rel=1e-15)
    assert p["k"] == pytest.approx(2000.0, rel=1e-15)
    assert WHIRL.resolve({"spin": "2 rev/s"})["spin"] == pytest.approx(4 * math.pi, rel=1e-15)
    q = SPINUP.resolve({"tilt0": "3 deg", "gravity": "0,0,-981cm/s^2", "l": "0.5"})
    assert q["tilt0"] == pytest.approx(math.pi / 60, rel=1e-15)
    assert list(q["gravity"]) == pytest.approx([0, 0, -9.81], rel=1e-15)
    assert q["l"] == 0.5                                     # a plain number: the declared unit


@pytest.mark.parametrize("value, says", [
    ("3m", "'3m' is in m ([length]), which does not convert to the parameter's unit rad/s"),
    ("10Hz", "Hz (1 / [time])"),                # cycles or radians a second? refused, not guessed
    ("4 parsecs/fortnight x", "cannot read"),
])
def test_a_unit_of_another_dimension_is_one_line_exit_2(value, says):
    rc, so, se = cli("modes", "rotor-whirl", "--set", f"spin={value}", "--json")
    assert rc == 2 and not so
    (line,) = se.strip().splitlines()
    assert line.startswith("xval: error: spin: ") and says in line


def test_the_range_is_checked_after_conversion():
    with pytest.raises(BadInput, match="outside the admissible range"):
        SPINUP.resolve({"l": "-5 cm"})
    with pytest.raises(BadInput, match="not a whole number"):
        WHIRL.resolve({"n_spin": "3.5"})


def test_the_json_keeps_the_declared_unit_and_the_api_takes_the_same_strings(tmp_path):
    rc, so, se = cli("modes", "rotor-whirl", "--solver", "closed-form", "--set", "spin=400rpm",
                     "--json", "--out", str(tmp_path / "m"))
    assert rc == 0, se
    assert json.loads(so)["params"]["spin"] == pytest.approx(400 * math.pi / 30, rel=1e-15)
    r = xval.modes("rotor-whirl", ["closed-form"], spin="400rpm", l="60cm")
    assert r.params["spin"] == pytest.approx(400 * math.pi / 30, rel=1e-15)
    assert r.params["l"] == pytest.approx(0.6, rel=1e-15)


def test_pint_is_imported_only_for_a_value_with_a_unit():
    code = ("import sys\nfrom compare.scenes import get_scene\n"
            "s = get_scene('rotor-whirl')\ns.resolve({'spin': '41.3'})\n"
            "assert 'pint' not in sys.modules, 'pint imported for a plain number'\n"
            "s.resolve({'spin': '400rpm'})\nassert 'pint' in sys.modules\n")
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert p.returncode == 0, p.stderr

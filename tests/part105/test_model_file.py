"""part105/model_file.py: a model file read once, checked and lenient access."""

from __future__ import annotations

from pathlib import Path

import pytest

from p105cli.part105.model_file import MISSING, ModelFile
from p105cli.schema.population import Population
from p105cli.step import read_step
from p105cli.step.errors import ModelError

ROOT = Path(__file__).resolve().parents[2]
FOUR_BAR = ROOT / "examples" / "four_bar_ap242.stp"
SLIDER_1996 = ROOT / "examples" / "slider_crank_p105_1996_ap214.stp"


@pytest.fixture(scope="module")
def mf():
    return ModelFile.of(read_step(FOUR_BAR.read_text(), str(FOUR_BAR)))


def test_profile_and_population_once(mf):
    assert mf.profile == "ap242" and mf.layout == "ap242"
    assert ModelFile.of(mf) is mf
    assert ModelFile.of(mf.pop).pop is mf.pop
    lenient = mf.lenient()
    assert lenient.pop is mf.pop and lenient.is_lenient and lenient.checked() is mf
    assert mf.cached("k", lambda: [1]) is lenient.cached("k", lambda: [2])


def test_ap214_with_su_parameters_is_read_as_p105():
    text = SLIDER_1996.read_text()
    doc = read_step(text, "x")
    mf = ModelFile.of(doc)
    has_su = "SU_PARAMETERS" in text
    assert mf.profile == ("p105" if has_su else "ap214") and mf.layout == "1996"
    assert ModelFile.of(doc, "ap214").profile == "ap214"


def test_checked_access_names_the_instance_and_attribute(mf):
    with pytest.raises(ModelError) as e:
        mf.ref(174, "name")  # a string, not a reference
    assert e.value.message.startswith("#174:") and "name" in e.value.message and e.value.instance_id == 174
    with pytest.raises(ModelError) as e:
        mf.get(174, "no_such_attribute")
    assert "#174" in str(e.value) and "no_such_attribute" in str(e.value)
    with pytest.raises(ModelError) as e:
        mf.number(174, "name")
    assert "not a finite number" in str(e.value)
    with pytest.raises(ModelError) as e:
        mf.ref(174, "represented_link", types=("kinematic_joint",))
    assert "which is no kinematic_joint" in str(e.value)
    with pytest.raises(ModelError):
        mf.get(999999, "name")
    assert mf.ref(174, "represented_link") == 129
    assert mf.string(174, "name") == "frame"


def test_lenient_access_never_raises(mf):
    k = mf.lenient()
    assert k.get(174, "no_such_attribute") is MISSING
    assert k.get(999999, "name") is MISSING
    assert k.ref(174, "name") is None
    assert k.ref(174, "represented_link", types=("kinematic_joint",)) is None
    assert k.ref(174, "represented_link") == 129
    assert k.number(174, "name") is None
    assert k.refs(174, "name") == []
    assert k.first_ref(174, "edge_start", "represented_link") == 129


def test_scale_of_a_link_representation(mf):
    s = mf.scale(174)
    assert s.length == 0.001 and s.angle == 0.0174532925199433  # millimetre, degree
    assert s.units().length_name == "millimetre"
    assert mf.scale(174) is s


def test_a_population_is_accepted():
    pop = Population(read_step(FOUR_BAR.read_text(), "x"))
    assert ModelFile.of(pop).profile == "ap242"


def test_readers_given_one_population_share_one_model_file():
    pop = Population(read_step(FOUR_BAR.read_text(), "x"))
    mf = ModelFile.of(pop)
    assert ModelFile.of(pop) is mf and ModelFile.of(pop, lenient=True) is mf.lenient()
    from p105cli.part105 import layout
    assert layout.mechanisms(ModelFile.of(pop)) is layout.mechanisms(mf)


def test_the_validator_loads_no_numpy():
    """The lenient walk needs no placement maths: validate starts without numpy."""
    import subprocess
    import sys
    code = "import sys, p105cli.rules.validate; print('numpy' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT)
    assert out.stdout.strip() == "False", out.stderr

"""part105.convert: a source rewritten in the other layout.

Independent truth: the same conversion of the unmodified corpus file (a rotation given as
rotation_about_direction instead of the equal ypr_rotation converts to the same values), and
the mechanism reader run on the converted file (the base placement an AP242 reader finds is
what the converter says about it).
"""

from __future__ import annotations

import re

import numpy as np
import pytest

from conftest import ROOT
from p105cli.kinematics.reader import read_mechanisms
from p105cli.part105.write_mechanism import write_mechanism
from p105cli.step import read_step

CORPUS = ROOT / "tests" / "data" / "corpus"


def _convert(text, profile, name="t.stp"):
    doc = read_step(text, name)
    (mech,) = read_mechanisms(doc)
    out, diags = write_mechanism(mech, profile, source=doc)
    return mech, out, diags


def _orientations(out):
    """The yaw, pitch, roll of every point_on_planar_curve_pair_value of a converted file."""
    return sorted(tuple(r["args"][3]["value"]) for r in out.data
                  if r.get("type") == "point_on_planar_curve_pair_value")


def test_a_1996_rotation_about_direction_in_a_configuration_is_converted_like_the_equal_ypr():
    """The 1996 rotation_about_direction has no name (direction_of_axis, rotation_angle): read
    by attribute name, the configuration converts; its orientation is the ypr it equals."""
    text = (CORPUS / "cam_follower_ap214.stp").read_text()
    line = "#182=POINT_ON_PLANAR_CURVE_PAIR_VALUE(#157,#181,YPR_ROTATION((-120.,0.,0.)));"
    assert line in text
    changed = text.replace(line, "#182=POINT_ON_PLANAR_CURVE_PAIR_VALUE(#157,#181,#9001);\n"
                                 "#9001=ROTATION_ABOUT_DIRECTION(#9002,-120.);\n"
                                 "#9002=DIRECTION('',(0.,0.,1.));")
    _, want, want_diags = _convert(text, "ap242")
    _, got, got_diags = _convert(changed, "ap242")
    assert got_diags == want_diags
    assert not [d for d in got_diags if d.startswith(("#182", "#9001", "#9002"))]
    assert len(_orientations(got)) == len(_orientations(want)) == 3
    assert np.allclose(_orientations(got), _orientations(want), rtol=0.0, atol=1e-9)


@pytest.mark.parametrize("source, moved, verdict", [
    ("four_bar_ap214.stp", False, "carried"),
    ("slider_crank_p105.stp", False, "carried"),
    ("four_bar_ap214.stp", True, "lost"),
])
def test_the_base_placement_verdict_is_what_an_ap242_reader_finds_in_the_converted_file(source, moved, verdict):
    text = (CORPUS / source).read_text()
    if moved:  # the mechanism's base placement no longer where the assembly places the base link
        line = "#194=CARTESIAN_POINT('',(150.,100.,0.));"
        assert line in text
        text = text.replace(line, "#194=CARTESIAN_POINT('',(150.,100.,25.));")
    mech, out, diags = _convert(text, "ap242")
    said = [d for d in diags if "mechanism_base_placement does not exist in AP242" in d]
    assert len(said) == 1
    (back,) = read_mechanisms(out)
    found = np.allclose(back.T_world_base, mech.T_world_base, rtol=0.0, atol=1e-9 * max(1.0, mech.size()))
    assert ("carried by the assembly" in said[0]) == found
    assert re.search("carried by the assembly" if verdict == "carried" else "is lost", said[0])

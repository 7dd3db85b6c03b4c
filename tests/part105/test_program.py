"""part105/program.py: a model's own motion program, sampled."""

from __future__ import annotations

import numpy as np
import pytest

from conftest import ROOT
from p105cli.part105.read_mechanism import read_mechanism
from p105cli.part105.program import ProgramError, motion_program
from p105cli.step import read_any

CORPUS = ROOT / "tests" / "data" / "corpus"


def _model(path):
    doc = read_any(path.read_text(), str(path))
    return doc, read_mechanism(doc)


def test_a_configuration_sequence_drives_the_actuated_pairs():
    doc, mech = _model(CORPUS / "four_bar_ap214.stp")
    kind, t, driven = motion_program(doc, mech, 5, None, "f.stp")
    assert kind == "values" and len(t) == 5 and t[0] < t[-1]
    actuated = [p.name for p in mech.pairs if p.actuated]
    assert list(driven) == actuated and all(np.shape(v) == (5,) for v in driven.values())


def test_a_prescribed_path_is_poses_of_a_link_frame():
    doc, mech = _model(CORPUS / "four_bar_ap242.stp")
    kind, t, poses, link, frame, frame_name = motion_program(doc, mech, None, None, "f.stp")
    assert kind == "path" and link in mech.link_names and poses.shape == (len(t), 4, 4)
    assert np.allclose(poses[:, 3], [0, 0, 0, 1])


def test_no_program_is_an_error_naming_the_file():
    from p105cli.formats.dh_table import read_csv
    from p105cli.kinematics import dh
    from p105cli.part105.write_mechanism import write_mechanism

    table = read_csv((ROOT / "examples" / "puma560_dh.csv").read_text(), "standard")
    doc, _ = write_mechanism(dh.to_mechanism(table, "ap242"), "ap242")   # a mechanism, no program
    with pytest.raises(ProgramError, match=r"^p\.stp: the model has no kinematic_control \(motion program\)"):
        motion_program(doc, read_mechanism(doc), None, None, "p.stp")


def test_a_sampling_request_that_cannot_be_met_names_the_file():
    doc, mech = _model(CORPUS / "four_bar_ap214.stp")
    with pytest.raises(ProgramError, match=r"^f\.stp: "):
        motion_program(doc, mech, None, 1e-300, "f.stp")

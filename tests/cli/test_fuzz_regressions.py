"""Inputs ``tests/fuzz_commands.py`` found ending in an internal error (exit 3): each one now
a clear message naming its ``#id`` (or FILE:LINE:COL) and exit 2, the same for every command
that reads the broken part."""

from __future__ import annotations

import json

import pytest

from conftest import EXAMPLES, SHARED

CORPUS = EXAMPLES.parent / "tests" / "data" / "corpus"


def _no_crash(r):
    text = r.stderr.decode()
    assert r.returncode in (0, 1, 2) and "internal error" not in text and "Traceback" not in text, text
    return text


def _edited(tmp_path, stem, old, new, name="input.stp"):
    text = (CORPUS / f"{stem}.stp").read_text()
    assert old in text
    path = tmp_path / name
    path.write_text(text.replace(old, new, 1))
    return path


@pytest.mark.parametrize("command", [["solve", "--program"], ["interpolate"]], ids=" ".join)
def test_a_dangling_configuration_in_a_1996_sequence_is_named(p105, tmp_path, command):
    # was KeyError: 999 (read_configuration_sequences looked the reference up unchecked)
    path = _edited(tmp_path, "four_bar_ap214", "#224=CONFIGURATION_INTERPOLATION(#217,#222,",
                   "#224=CONFIGURATION_INTERPOLATION(#217,#999,")
    r = p105(*command, path)
    assert r.returncode == 2
    assert (f"{path}: #224: next_configuration_definition of configuration_interpolation refers to #999, "
            "which is not in the file") in _no_crash(r)


@pytest.mark.parametrize("command", [["solve", "--program"], ["interpolate"]], ids=" ".join)
def test_a_configuration_reference_to_the_wrong_entity_is_named(p105, tmp_path, command):
    # was SchemaError (exit 3): #1 is no configuration_definition, it has no t_parameter
    path = _edited(tmp_path, "four_bar_ap214", "#224=CONFIGURATION_INTERPOLATION(#217,#222,",
                   "#224=CONFIGURATION_INTERPOLATION(#217,#1,")
    r = p105(*command, path)
    assert r.returncode == 2
    assert "#1: " in _no_crash(r) and "has no attribute 't_parameter'" in r.stderr.decode()


def test_a_dangling_state_in_an_ap242_sequence_is_named(p105, tmp_path):
    # was KeyError: 9999 (exit 3)
    path = _edited(tmp_path, "four_bar_ap242", "#223=INTERPOLATED_CONFIGURATION_SEGMENT(#211,",
                   "#223=INTERPOLATED_CONFIGURATION_SEGMENT(#9999,")
    r = p105("interpolate", path)
    assert r.returncode == 2
    assert (f"{path}: #223: state of interpolated_configuration_segment refers to #9999, which is not in "
            "the file") in _no_crash(r)


def test_a_json_instance_id_beyond_64_bits_is_malformed_input(p105, tmp_path):
    # was OverflowError (exit 3) in every command but parse, which accepted it
    doc = json.loads(p105("parse", CORPUS / "four_bar_ap242.stp").stdout)
    doc["data"][0]["id"] = 2**63
    path = tmp_path / "big_id.json"
    path.write_text(json.dumps(doc))
    for command in (["parse"], ["graph"], ["solve"], ["export", "--schema", "ap214"], ["interpolate"]):
        r = p105(*command, path)
        assert r.returncode == 2, command
        assert r.stderr.decode() == (f"p105: error: {path}:/data/0: instance id 9223372036854775808 is too "
                                     "large (at most 9223372036854775807)\n"), command
    v = p105("validate", path)
    assert v.returncode == 2 and "is too large" in v.stdout.decode()


@pytest.mark.skipif(not (SHARED / "external" / "crashes" / "D08.json").is_file(), reason="no shared files")
def test_the_shared_d08_is_refused_cleanly(p105):
    r = p105("graph", SHARED / "external" / "crashes" / "D08.json")
    assert r.returncode == 2 and "is too large" in _no_crash(r)


@pytest.mark.skipif(not (SHARED / "external" / "crashes" / "D05.stp").is_file(), reason="no shared files")
def test_a_pair_parameter_its_motion_refuses_is_malformed_input_for_solve(p105, tmp_path):
    # was ValueError (exit 3) from the universal pair's motion: its skew angle (2 rad) breaks
    # WR1; graph, lenient, says the pair has no motion and goes on
    d05 = (SHARED / "external" / "crashes" / "D05.stp").read_text()
    assert "UNIVERSAL_PAIR(1.E300)" in d05
    path = tmp_path / "skew.stp"
    path.write_text(d05.replace("UNIVERSAL_PAIR(1.E300)", "UNIVERSAL_PAIR(2.)"))
    r = p105("solve", "--to", "jsonl", path)
    assert r.returncode == 2
    assert _no_crash(r).splitlines()[-1] == (
        f"p105: error: {path}: #142: mechanism 'sph_univ': pair 'J2': universal pair: WR1 requires "
        "cos(skew_angle) > 0 (the axes' offset from a right angle must be acute)")
    g = p105("graph", path)
    assert g.returncode == 0 and "pair 'J2' (universal): no motion available" in g.stderr.decode()
    # the shared file itself: a skew angle of 1e300 is beyond what is computed with
    r = p105("solve", "--to", "jsonl", SHARED / "external" / "crashes" / "D05.stp")
    assert r.returncode == 2 and "#142: input_skew_angle of" in _no_crash(r)


@pytest.mark.skipif(not (SHARED / "external" / "defects" / "four_bar_low_order_pair.stp").is_file(),
                    reason="no shared files")
@pytest.mark.parametrize("schema", ["ap214", "ap242", "p105"])
def test_a_sequence_holding_values_of_a_pair_left_out_is_converted_without_them(p105, tmp_path, schema):
    # was KeyError: 'B' (exit 3): pair B (a low_order_kinematic_pair, not written then) is left
    # out, but the configuration sequence still named its values. Low-order pairs are written
    # now; a kind still left out is the spherical pair with pin, which the generic pair is
    # with the flags r_y, r_z (its motion at these values is still the pin's rotation about z)
    text = (SHARED / "external" / "defects" / "four_bar_low_order_pair.stp").read_text()
    src = tmp_path / "pin_as_spherical_with_pin.stp"
    src.write_text(text.replace("#134,.F.,.F.,.F.,.F.,.F.,.T.);", "#134,.F.,.F.,.F.,.F.,.T.,.T.);"))
    r = p105("export", "--schema", schema, src)
    assert r.returncode == 0
    assert "#183: pair 'B': spherical_with_pin pairs are not written by p105 yet" in _no_crash(r)
    out = tmp_path / "out.stp"
    out.write_bytes(r.stdout)
    assert "INTERPOLATED_CONFIGURATION_SEQUENCE" in r.stdout.decode()
    v = p105("validate", out)
    assert v.returncode == 0, v.stdout.decode()


@pytest.mark.skipif(not (SHARED / "external" / "crashes" / "D06.stp").is_file(), reason="no shared files")
def test_a_pair_without_a_motion_here_is_an_input_error_for_solve(p105):
    # was UnsupportedPairError (exit 3) from the loop closure: a gear pair with a helical angle
    path = SHARED / "external" / "crashes" / "D06.stp"
    r = p105("solve", "--to", "jsonl", path)
    assert r.returncode == 2
    assert _no_crash(r).splitlines()[-1].startswith(
        f"p105: error: {path}: #210: mechanism 'gear_train': pair 'mesh 1-2': gear pair: helical_angle = ")


@pytest.mark.parametrize("command", [["solve"], ["export", "--schema", "ap214"], ["export", "--schema", "ap242"]],
                         ids=" ".join)
def test_a_unit_factor_whose_inverse_overflows_is_named(p105, tmp_path, command):
    # shared crashes/D09: a degree of 5e-324 rad; values divided by it were inf/nan, and
    # writing them was an internal error (exit 3)
    path = _edited(tmp_path, "four_bar_ap242", "PLANE_ANGLE_MEASURE(0.0174532925199433)",
                   "PLANE_ANGLE_MEASURE(5.E-324)")
    r = p105(*command, path)
    assert r.returncode == 2
    assert "cannot convert plane-angle values (it or its inverse is beyond the range of reals)" in _no_crash(r)
    v = p105("validate", path)
    assert v.returncode == 1 and "error[KIN-UNITS] conversion-based unit" in v.stdout.decode()


@pytest.mark.parametrize("command", [["solve", "--program"], ["interpolate"]], ids=" ".join)
def test_a_dangling_path_segment_is_named(p105, tmp_path, command):
    # was KeyError: 999 (exit 3): the path's segments were looked up unchecked
    path = _edited(tmp_path, "gear_train_ap242", "('gear_3 marker path',(#263,#268),",
                   "('gear_3 marker path',(#263,#999),")
    r = p105(*command, path)
    assert r.returncode == 2
    assert (f"{path}: #269: segments of kinematic_path_defined_by_nodes refers to #999, which is not in the "
            "file") in _no_crash(r)


@pytest.mark.parametrize("command", [["graph"], ["solve"], ["export", "--schema", "ap214"]], ids=" ".join)
def test_a_coordinate_beyond_what_can_be_computed_with_is_named(p105, tmp_path, command):
    # shared crashes/D02, D03, D21: a point of a pair frame at 1e308 mm; the analysis overflowed
    # (LinAlgError "SVD did not converge", inf in JSON: exit 3; or Infinity written, exit 0)
    path = _edited(tmp_path, "four_bar_ap242", "#138=CARTESIAN_POINT('',(0.,0.,0.));",
                   "#138=CARTESIAN_POINT('',(1.E308,0.,0.));")
    r = p105(*command, path)
    assert r.returncode == 2
    assert ("#138: coordinates of cartesian_point is [1e+308, 0.0, 0.0], beyond the magnitudes p105 "
            "computes with (1e+100)") in _no_crash(r)


@pytest.mark.parametrize("schema", ["ap214", "ap242"])
def test_a_configuration_with_a_number_among_its_pair_values_is_left_out_of_the_conversion(p105, tmp_path,
                                                                                            schema):
    # shared crashes/D10j, D11c: was TypeError (int < None, exit 3) comparing the value lists
    path = _edited(tmp_path, "four_bar_ap214", "#217=CONFIGURATION_DEFINITION((#213,",
                   "#217=CONFIGURATION_DEFINITION((7,")
    r = p105("export", "--schema", schema, path)
    assert r.returncode == 0
    err = _no_crash(r)
    if schema == "ap242":  # (ap214 to ap214 keeps the file's own sequence as it is)
        assert f"{path}: #217: configuration_definition does not exist in ap242; left out" in err
        assert "INTERPOLATED_CONFIGURATION_SEQUENCE" not in r.stdout.decode()


def test_a_context_naming_a_partial_entity_twice_is_named_by_export(p105, tmp_path):
    # shared crashes/D10k: was ValueError from the builder (exit 3) copying the world context
    # into the motion context; the error names the file too (it said <input>)
    head = "#7=(GEOMETRIC_REPRESENTATION_CONTEXT(3)GLOBAL_UNCERTAINTY_ASSIGNED_CONTEXT((#6))"
    path = _edited(tmp_path, "four_bar_ap214", head, head + "GLOBAL_UNCERTAINTY_ASSIGNED_CONTEXT((#6))")
    r = p105("export", "--schema", "ap242", path)
    assert r.returncode == 2
    assert _no_crash(r).splitlines()[-1] == (
        f"p105: error: {path}: #7: complex instance names global_uncertainty_assigned_context more than once")


@pytest.mark.skipif(not (SHARED / "external" / "defects" / "four_bar_low_order_pair.stp").is_file(),
                    reason="no shared files")
@pytest.mark.parametrize("drive", [["--set", "A=0.5"], ["--set", "C=0.5"], ["--program", "--count", "3"]],
                         ids=" ".join)
def test_a_low_order_pair_in_a_loop_solves_with_its_locked_values_at_roundoff(p105, drive):
    # was ValueError (exit 3): the loop closure left 2.8e-19 on a locked translation of pair B
    r = p105("solve", *drive, "--no-timings", "--to", "jsonl",
             SHARED / "external" / "defects" / "four_bar_low_order_pair.stp")
    assert r.returncode == 0, _no_crash(r)
    summary = json.loads(r.stdout.splitlines()[-1])
    assert summary["type"] == "summary" and set(summary["status"]) == {"ok"}


@pytest.mark.parametrize("command", [["graph"], ["solve"], ["export", "--schema", "ap214"]], ids=" ".join)
def test_a_pair_whose_transform_item_is_itself_is_named(p105, tmp_path, command):
    # a fuzz variant of shared crashes/D07: RecursionError (exit 3) placing the pair's frames
    path = _edited(tmp_path, "four_bar_ap242", "#183=REVOLUTE_PAIR('B',*,'crank-coupler pin',#149,",
                   "#183=REVOLUTE_PAIR('B',*,'crank-coupler pin',#183,")
    r = p105(*command, path)
    assert r.returncode == 2
    assert _no_crash(r).splitlines()[-1] == (
        f"p105: error: {path}: #183: revolute_pair refers back to itself through its transform items: it places "
        "nothing")

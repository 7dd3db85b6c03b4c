"""p105 solve --to model: resulting paths among the analysis results.

Independent truth: the four-bar's closed form (the coupler's frame at the
crank pin B, a(cos t2, sin t2) from the crank pivot), the UR5 program's own
prescribed path (an inverse analysis puts the flange on its nodes), the
1996 kinematic_analysis_result WR1 as the validator evaluates it (a
resulting path with undefined interpolations is an error), and the same
run's --to jsonl link placements.
"""

from __future__ import annotations

import json
import math
import re

import numpy as np
import pytest

from conftest import EXAMPLES, ROOT
from p105cli.kinematics.spatial import inverse
from p105cli.part105.read_mechanism import read_mechanism
from p105cli.part105.motion import read_paths
from p105cli.rules.validate import validate_document
from p105cli.step import read_step

FOUR_BAR_242 = EXAMPLES / "four_bar_ap242.stp"
FOUR_BAR_214 = ROOT / "tests" / "data" / "corpus" / "four_bar_ap214.stp"
UR5 = ROOT / "tests" / "data" / "corpus" / "ur5_arm_ap242.stp"
SWEEP = ("--sweep", "A=0.5:2.5:9")


@pytest.fixture
def cli(p105):
    """Run ``p105 ARGS`` in this process (conftest.p105)."""
    return p105


def _solve(cli, tmp_path, *args):
    """The model output (-o FILE, parsed) and the jsonl records of the same run."""
    out = tmp_path / "out.stp"
    r = cli("solve", *args, "-o", out)
    assert r.returncode == 0, r.stderr.decode()
    # --resulting-path is model output: with --to jsonl it would do nothing (a usage error)
    table_args = [a for k, a in enumerate(args) if a != "--resulting-path" and (k == 0 or args[k - 1] != "--resulting-path")]
    j = cli("solve", *table_args, "--to", "jsonl", "--no-timings")
    assert j.returncode == 0, j.stderr.decode()
    recs = [json.loads(x) for x in j.stdout.decode().splitlines()]
    text = out.read_text()
    return read_step(text, str(out)), text, [x for x in recs if x["type"] == "configuration"]


def _problems(doc):
    res = validate_document(doc, doc.source)
    return [f"{d.rule} #{d.entity}: {d.message[:160]}" for d in res.diagnostics
            if d.severity in ("error", "warning")]


def _resulting(doc):
    return [p for p in read_paths(doc).paths if p.role == "resulting"]


def _nodes(path):
    """(t, 4x4 SI) at the start and at every segment end."""
    seg = path.segments
    return [seg[0].t_start] + [s.t_end for s in seg], [seg[0].T_start] + [s.T_end for s in seg]


def _close(A, B, scale, rtol=1e-12):
    A, B = np.asarray(A), np.asarray(B)
    assert np.abs(A[..., :3, :3] - B[..., :3, :3]).max() <= rtol
    assert np.abs(A[..., :3, 3] - B[..., :3, 3]).max() <= rtol * scale


# ---------------------------------------------------------------- AP242

def test_ap242_four_bar_link_frame_path_is_the_solved_coupler_and_the_closed_form(cli, tmp_path):
    doc, text, conf = _solve(cli, tmp_path, FOUR_BAR_242, *SWEEP, "--resulting-path", "coupler")
    assert _problems(doc) == []
    (path,) = _resulting(doc)
    assert path.link == "coupler"
    t, nodes = _nodes(path)
    assert t == list(range(9))  # no t given: the configuration index
    solved = np.array([c["links"]["coupler"] for c in conf])
    frame = np.array([c["links"]["frame"] for c in conf])
    _close(nodes, solved, scale=0.2)
    # closed form: the coupler frame sits on the crank pin B, 20 mm from the crank pivot A (the
    # frame link's origin) at the crank angle
    for T, F, t2 in zip(nodes, frame, np.linspace(0.5, 2.5, 9)):
        d = (inverse(F) @ T)[:3, 3]
        assert np.linalg.norm(d[:2]) == pytest.approx(0.020, rel=1e-12) and abs(d[2]) < 1e-15
        assert abs(math.remainder(math.atan2(d[1], d[0]) - t2, 2 * math.pi)) < 1e-12
    # controlling joints: every pair of the loop (the coupler's pose depends on all four)
    ids = re.search(r"RESULTING_PATH\('coupler link frame resulting path',\(#\d+\),#\d+,\(([^)]*)\)\)", text).group(1)
    assert len(ids.split(",")) == 4
    # the path is one more kinematic_analysis_result (AP242's result is a single kinematic_result)
    assert len(re.findall(r"=KINEMATIC_ANALYSIS_RESULT\(", text)) == 2


def test_ap242_named_frame_path_uses_the_frame_item(cli, tmp_path):
    doc, text, conf = _solve(cli, tmp_path, FOUR_BAR_242, *SWEEP, "--resulting-path", "coupler:coupler point P")
    assert _problems(doc) == []
    (path,) = _resulting(doc)
    assert (path.link, path.frame) == ("coupler", "coupler point P")
    mech = read_mechanism(doc)
    F = mech.link("coupler").frames["coupler point P"]
    _, nodes = _nodes(path)
    _close(nodes, np.array([c["links"]["coupler"] for c in conf]) @ F, scale=0.2)
    # the existing frame instance is reused, no placement added to the link representation
    before = read_step(FOUR_BAR_242.read_text(), "in.stp")
    assert dict(read_mechanism(before).link("coupler").frames).keys() == dict(mech.link("coupler").frames).keys()


def test_ap242_ur5_inverse_analysis_writes_the_target_path_by_default(cli, tmp_path):
    doc, text, conf = _solve(cli, tmp_path, UR5, "--program")
    assert _problems(doc) == []
    paths = read_paths(doc).paths
    (res,) = [p for p in paths if p.role == "resulting"]
    (pre,) = [p for p in paths if p.role == "prescribed"]
    assert res.link == pre.link == "wrist_3" and res.frame == pre.frame
    t, nodes = _nodes(res)
    assert t == [c["t"] for c in conf]
    # the same run's solved placements, through the frame the prescribed path names
    mech = read_mechanism(doc)
    F = mech.link("wrist_3").frames.get(pre.frame)
    F = np.eye(4) if F is None else F
    _close(nodes, np.array([c["links"]["wrist_3"] for c in conf]) @ F, scale=1.0)
    # and the prescribed path's nodes (what the inverse analysis was asked to reach)
    tp, want = _nodes(pre)
    assert tp == t
    _close(nodes, want, scale=1.0, rtol=1e-8)
    six = re.search(r"RESULTING_PATH\('[^']*',\(#\d+\),#\d+,\(([^)]*)\)\)", text).group(1)
    assert len(six.split(",")) == 6


def test_interpolate_samples_the_resulting_path(cli, tmp_path):
    doc, text, conf = _solve(cli, tmp_path, FOUR_BAR_242, *SWEEP, "--resulting-path", "rocker")
    r = cli("interpolate", "--what", "paths", tmp_path / "out.stp")
    assert r.returncode == 0, r.stderr.decode()
    frames = [json.loads(x) for x in r.stdout.decode().splitlines()]
    mine = [f for f in frames if f.get("path") == "rocker link frame resulting path"]
    assert len(mine) == 9 and all(f["link"] == "rocker" for f in mine)
    # the file is in millimetres; the sampled frames in metres, as the jsonl output
    for f, c in zip(mine, conf):
        _close(np.array(f["matrix"]), np.array(c["links"]["rocker"]), scale=0.2)


# ---------------------------------------------------------------- 1996 layout

def test_1996_resulting_path_with_linear_interpolation_validates(cli, tmp_path):
    doc, text, _ = _solve(cli, tmp_path, FOUR_BAR_214, *SWEEP, "--resulting-path", "coupler")
    assert _problems(doc) == []
    new = text[text.index("KINEMATIC_CONTROL"):]
    assert len(re.findall(r"CONFIGURATION_INTERPOLATION\(#\d+,#\d+,\.LINEAR\.\)", new)) == 8
    m = re.search(r"#(\d+)=RESULTING_PATH\('coupler link frame resulting path',\$,#(\d+),#(\d+),#(\d+),"
                  r"\(([^)]*)\)\)", text)
    assert m, text[-2000:]
    assert len(m.group(5).split(",")) == 4  # the four joints of the loop
    assert re.search(rf"=KINEMATIC_ANALYSIS_RESULT\(#\d+,\(#\d+,#{m.group(1)}\)\)", text)
    assert re.search(rf"#{m.group(2)}=FOUNDED_KINEMATIC_PATH\(", text)
    # WR1 of kinematic_analysis_result: with a resulting path, undefined interpolations are wrong
    bad = read_step(text.replace(".LINEAR.)", ".UNDEFINED.)"), "bad.stp")
    assert any("kinematic_analysis_result.wr1" in p for p in _problems(bad))


def test_1996_without_resulting_path_stays_undefined(cli, tmp_path):
    doc, text, _ = _solve(cli, tmp_path, FOUR_BAR_214, *SWEEP)
    assert _problems(doc) == []
    assert "RESULTING_PATH" not in text
    new = text[text.index("KINEMATIC_CONTROL"):]
    assert len(re.findall(r"CONFIGURATION_INTERPOLATION\(#\d+,#\d+,\.UNDEFINED\.\)", new)) == 8
    # WR1 the other way: without a resulting path a defined interpolation is wrong
    head, tail = text[:text.index("KINEMATIC_CONTROL")], new
    bad = read_step(head + tail.replace(".UNDEFINED.)", ".LINEAR.)"), "bad.stp")
    assert any("kinematic_analysis_result.wr1" in p for p in _problems(bad))


# ---------------------------------------------------------------- errors

@pytest.mark.parametrize("args, words", [
    (("--resulting-path", "nope"), "not a link"),
    (("--resulting-path", "coupler:nope"), "no frame"),
    (("--resulting-path", "frame"), "does not move"),
])
def test_resulting_path_errors(cli, args, words):
    r = cli("solve", FOUR_BAR_242, *SWEEP, *args)
    assert r.returncode == 2
    assert words in r.stderr.decode() and r.stdout == b""


def test_tables_refuse_the_path_that_is_model_output(cli):
    # an option that would do nothing is a usage error (issue 11): the tables have the placements
    r = cli("solve", FOUR_BAR_242, *SWEEP, "--resulting-path", "coupler", "--to", "csv")
    assert r.returncode == 2 and "--to model only" in r.stderr.decode() and r.stdout == b""


def test_one_configuration_writes_no_path_and_says_so(cli, tmp_path):
    out = tmp_path / "one.stp"
    r = cli("solve", FOUR_BAR_242, "--set", "A=0.5", "--resulting-path", "coupler", "-o", out)
    assert r.returncode == 0
    assert "RESULTING_PATH" not in out.read_text() and "two or more" in r.stderr.decode()


# ---------------------------------------------------------------- a link frame no item places yet

@pytest.mark.parametrize("profile", ["ap242", "ap214"])
def test_link_frame_without_an_item_gets_one(cli, tmp_path, profile):
    """An arm whose only frame item is its pair frame 0.1 m from its origin: the link frame is added
    to its representation, and (AP242) the path is the closed form (0.1 cos q, 0.1 sin q)."""
    import io

    from p105cli.kinematics.model import Link, Mechanism, Pair
    from p105cli.kinematics.spatial import rot_z, trans_x
    from p105cli.part105.write_mechanism import write_mechanism
    from p105cli.step import write_step

    m = Mechanism("arm", [Link("ground"), Link("arm")],
                  [Pair("J", "revolute", "ground", "arm", np.eye(4), trans_x(-0.1), actuated=True)], "ground",
                  initial={"J": (0.0,)})
    doc, _ = write_mechanism(m, profile)
    buf = io.StringIO()
    write_step(doc, buf)
    src = tmp_path / "arm.stp"
    src.write_text(buf.getvalue())
    out, _, conf = _solve(cli, tmp_path, src, "--sweep", "J=0:1.5:4", "--resulting-path", "arm")
    assert _problems(out) == []
    back = read_mechanism(out)
    assert np.abs(back.link("arm").frames["arm link frame"] - np.eye(4)).max() == 0.0
    if profile == "ap242":
        (path,) = _resulting(out)
        _, nodes = _nodes(path)
        want = np.array([rot_z(q) @ trans_x(0.1) for q in np.linspace(0.0, 1.5, 4)])
        _close(nodes, want, scale=0.1)
        _close(nodes, np.array([c["links"]["arm"] for c in conf]), scale=0.1)

"""formats/poses.py: one reader of pose files for solve --path and solve --keypoints."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from p105cli.cable.workflow import KeypointError, load_keypoints
from p105cli.formats.poses import FormatError, parse_poses, read_poses
from p105cli.kinematics.spatial import compose, rot_z, trans_x

T0 = compose(rot_z(0.3), trans_x(2.0))
T1 = compose(rot_z(-0.2), trans_x(1.0))
M12 = [f"m{i}{j}" for i in range(3) for j in range(4)]
M16 = [f"m{i}{j}" for i in range(4) for j in range(4)]


def _cells(T, k):
    return [repr(float(x)) for x in T.ravel()[:k]]


#: The six inputs of REDESIGN P7, each with the times it means (None: no t given).
SIX = {
    "csv header": ("\n".join([",".join(["t"] + M12)] + [",".join([t] + _cells(T, 12)) for t, T in
                                                        (("0.5", T0), ("1.5", T1))]) + "\n", [0.5, 1.5]),
    "csv no header": ("\n".join(",".join([t] + _cells(T, 12)) for t, T in (("0.5", T0), ("1.5", T1))) + "\n",
                      [0.5, 1.5]),
    "csv 16 columns": ("\n".join([",".join(["t"] + M16)] + [",".join([t] + _cells(T, 16)) for t, T in
                                                           (("0.5", T0), ("1.5", T1))]) + "\n", [0.5, 1.5]),
    "csv header without t": ("\n".join([",".join(M12)] + [",".join(_cells(T, 12)) for T in (T0, T1)]) + "\n", None),
    "jsonl 3x4": ("".join(json.dumps({"t": t, "pose": T[:3].tolist()}) + "\n" for t, T in ((0.5, T0), (1.5, T1))),
                  [0.5, 1.5]),
    "jsonl without t": ("".join(json.dumps({"pose": T.tolist()}) + "\n" for T in (T0, T1)), None),
}


@pytest.mark.parametrize("name", SIX)
def test_the_six_inputs_read_alike(name, tmp_path):
    text, times = SIX[name]
    s = parse_poses(text, "p")
    assert np.allclose(s.poses, [T0, T1], atol=1e-15, rtol=0)
    assert (s.t is None) if times is None else s.t.tolist() == times
    assert s.times().tolist() == (times or [0.0, 1.0])
    path = tmp_path / "k.txt"
    path.write_text(text)
    keys = load_keypoints(path)
    assert [k["t"] for k in keys] == (times or [0.0, 1.0])
    assert np.array_equal(np.array([k["pose"] for k in keys]), s.poses)


def test_lengths_scale_translations_only():
    t1, P1 = read_poses(SIX["csv header"][0], "p.csv", length=1e-3)
    t2, P2 = read_poses(SIX["jsonl 3x4"][0], "p.jsonl", length=1e-3)
    assert list(t1) == list(t2) == [0.5, 1.5]
    assert np.abs(P1 - P2).max() == 0.0 and abs(P1[0, 0, 3] - 2e-3 * math.cos(0.3)) < 1e-15


BAD = [
    ('{"pose": ' + json.dumps((T0 * [[2], [1], [1], [1]]).tolist()) + "}\n",
     "p:1:1: the pose is not a rigid placement"),
    ("t," + ",".join(M16) + "\n0," + ",".join(_cells(T0, 15)) + ",2\n", "p:2:"),   # column checked below
    ("t," + ",".join(M12) + "\n0.5,1,0,0\n", "p:2:1: 4 fields, the header has 13"),
    (",".join(["0"] + _cells(T0, 12)) + "\n" + "0.5,1,0,0\n", "p:2:1: 4 fields, line 1 has 13"),
    ("0,1,2\n", "p:1:1: 3 fields; a pose row has 13"),
    ("t,a,b\n", "p:1:1: expected the columns t,m00,m01,...,m23 (or to m33)"),
    ("t," + ",".join(M12) + "\n0,x" + ",0" * 11 + "\n", "p:2:3: 'x' is not a number"),
    ('{"t": 0, "pose": [[1,0,0,0]\n', "p:1:"),
    (json.dumps({"t": 0, "pose": T0.tolist()}) + "\n" + json.dumps({"pose": T0.tolist()}) + "\n",
     "p:2:1: 't' must be given on every line or on none"),
    (json.dumps({"t": "x", "pose": T0.tolist()}) + "\n", "p:1:1: t must be a finite number"),
    ('{"t": 0}\n', 'p:1:1: expected {"t": ..., "pose": 4x4 matrix}'),
    ('{"pose": ' + "[" * 5000 + "]" * 5000 + "}\n", "p:1:1: JSON nested too deeply"),
    ("# only a comment\n", "p:1:1: no pose"),
    ("t," + ",".join(M12) + "\n", "p:2:1: no pose after the header"),
]


@pytest.mark.parametrize("text, message", BAD)
def test_errors_name_the_place_and_are_the_same_for_both_options(text, message, tmp_path):
    with pytest.raises(FormatError) as err:
        parse_poses(text, "p")
    assert str(err.value).startswith(message)
    path = tmp_path / "p"
    path.write_text(text)
    with pytest.raises(KeypointError) as kerr:
        load_keypoints(path)
    assert str(kerr.value) == str(err.value).replace("p", str(path), 1)


def test_a_16_column_bottom_row_must_be_0001_and_the_cell_is_named():
    text = "t," + ",".join(M16) + "\n0," + ",".join(_cells(T0, 15)) + ",2\n"
    with pytest.raises(FormatError, match=r"^p:2:\d+: the last row of a pose must be 0 0 0 1 \(m33 is 2\)"):
        parse_poses(text, "p")
    col = len("0," + ",".join(_cells(T0, 15)) + ",")   # 1-based column of the last cell
    with pytest.raises(FormatError, match=rf"^p:2:{col + 1}:"):
        parse_poses(text, "p")


def test_key_points_must_not_go_back_in_time(tmp_path):
    path = tmp_path / "k.jsonl"
    path.write_text(json.dumps({"t": 1, "pose": T0.tolist()}) + "\n\n" + json.dumps({"t": 0.5, "pose": T0.tolist()}))
    with pytest.raises(KeypointError, match=rf"^{path}:3:1: t = 0\.5 goes back in time \(previous 1\)"):
        load_keypoints(path)

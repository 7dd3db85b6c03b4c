"""p105 solve in process: the pose files of --path and --keypoints, read by one reader."""

from __future__ import annotations

import json

import numpy as np
import pytest

from conftest import EXAMPLES

M12 = [f"m{i}{j}" for i in range(3) for j in range(4)]
M16 = [f"m{i}{j}" for i in range(4) for j in range(4)]


def _cells(T, k):
    return [repr(float(x)) for x in np.asarray(T, dtype=float).ravel()[:k]]


def six_inputs(samples) -> dict:
    """The six pose files of REDESIGN P7 for ``samples`` [(t, 4x4)]: name -> (file name, text, has t)."""
    return {
        "csv header": ("a.csv", "\n".join([",".join(["t"] + M12)]
                                          + [",".join([repr(t)] + _cells(T, 12)) for t, T in samples]) + "\n", True),
        "csv no header": ("b.csv", "".join(",".join([repr(t)] + _cells(T, 12)) + "\n" for t, T in samples), True),
        "csv 16 columns": ("c.csv", "\n".join([",".join(["t"] + M16)]
                                              + [",".join([repr(t)] + _cells(T, 16)) for t, T in samples]) + "\n",
                           True),
        "csv header without t": ("d.csv", "\n".join([",".join(M12)] + [",".join(_cells(T, 12)) for _, T in samples])
                                 + "\n", False),
        "jsonl 3x4": ("e.jsonl", "".join(json.dumps({"t": t, "pose": np.asarray(T)[:3].tolist()}) + "\n"
                                         for t, T in samples), True),
        "jsonl without t": ("f.jsonl", "".join(json.dumps({"pose": np.asarray(T).tolist()}) + "\n"
                                               for _, T in samples), False),
    }


def _samples(path, n):
    recs = [json.loads(line) for line in path.read_text().splitlines() if line.strip()][:n]
    return [(r["t"], r["pose"]) for r in recs]


def _records(r):
    return [json.loads(line) for line in r.stdout.decode().splitlines()]


@pytest.fixture(scope="module")
def puma(tmp_path_factory):
    """The Puma 560 of examples/ as a model (convert-dh-su, in a subprocess-free way)."""
    from io import StringIO
    from p105cli.formats.dh_table import read_csv
    from p105cli.kinematics import dh
    from p105cli.part105.write_mechanism import write_mechanism
    from p105cli.step import write_step

    table = read_csv((EXAMPLES / "puma560_dh.csv").read_text(), "standard")
    doc, _ = write_mechanism(dh.to_mechanism(table, "ap242"), "ap242")
    buf = StringIO()
    write_step(doc, buf)
    path = tmp_path_factory.mktemp("puma") / "puma.stp"
    path.write_text(buf.getvalue())
    return path


def test_path_reads_the_six_pose_inputs_alike(p105, puma, tmp_path):
    samples = _samples(EXAMPLES / "puma560_tool_path.jsonl", 3)
    results = {}
    for name, (fname, text, has_t) in six_inputs(samples).items():
        f = tmp_path / fname
        f.write_text(text)
        r = p105("solve", puma, "--path", f, "--target-link", "link6", "--to", "jsonl", "--no-timings")
        assert r.returncode == 0, (name, r.stderr)
        conf = [x for x in _records(r) if x["type"] == "configuration"]
        assert [c["t"] for c in conf] == ([t for t, _ in samples] if has_t else [None] * len(samples)), name
        results[name] = [c["pairs"] for c in conf]
    first = next(iter(results.values()))
    assert all(v == first for v in results.values())


def test_keypoints_read_the_six_pose_inputs_alike(p105, tmp_path):
    scene = json.loads((EXAMPLES / "cable_scene.json").read_text())
    scene["cables"][0]["numerics"]["segments"] = 8
    scene_path = tmp_path / "scene.json"
    scene_path.write_text(json.dumps(scene))
    samples = _samples(EXAMPLES / "cable_keypoints.jsonl", 2)
    nodes = {}
    for name, (fname, text, has_t) in six_inputs(samples).items():
        f = tmp_path / fname
        f.write_text(text)
        r = p105("solve", "--scene", scene_path, "--keypoints", f)
        assert r.returncode == 0, (name, r.stderr)
        states = [x for x in _records(r) if x["type"] == "cable_state"]
        # a key point without t is at its index
        assert [s["t"] for s in states] == ([t for t, _ in samples] if has_t else [0.0, 1.0]), name
        nodes[name] = [s["nodes"] for s in states]
    first = next(iter(nodes.values()))
    assert all(v == first for v in nodes.values())


@pytest.mark.parametrize("text, where", [
    ("t," + ",".join(M12) + "\n0.5,1,0,0\n", "2:1: 4 fields, the header has 13"),
    ("t," + ",".join(M12) + "\n0,x" + ",0" * 11 + "\n", "2:3: 'x' is not a number"),
    ("t," + ",".join(M16) + "\n0,1,0,0,0,0,1,0,0,0,0,1,0,0,0,0,2\n",
     "2:33: the last row of a pose must be 0 0 0 1 (m33 is 2)"),
    ('{"t": 0, "pose": [[1,0,0,0],[0,2,0,0],[0,0,1,0]]}\n', "1:1: the pose is not a rigid placement"),
])
def test_pose_file_errors_are_the_same_for_path_and_keypoints(p105, puma, tmp_path, text, where):
    f = tmp_path / "poses.txt"
    f.write_text(text)
    by_path = p105("solve", puma, "--path", f, "--target-link", "link6", "--to", "jsonl")
    by_keys = p105("solve", "--scene", EXAMPLES / "cable_scene.json", "--keypoints", f)
    assert by_path.returncode == by_keys.returncode == 2
    assert by_path.stderr == by_keys.stderr
    assert by_path.stderr.decode().startswith(f"p105: error: {f}:{where}"), by_path.stderr


def test_keypoint_file_is_named_as_given(p105, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    r = p105("solve", "--scene", EXAMPLES / "cable_scene.json", "--keypoints", "missing.jsonl")
    assert r.returncode == 2
    assert r.stderr.decode() == "p105: error: missing.jsonl: cannot read: No such file or directory\n"


def test_unknown_mechanism_is_named(p105):
    r = p105("solve", EXAMPLES / "four_bar_ap242.stp", "--mechanism", "nope", "--to", "jsonl")
    assert r.returncode == 2 and b"nope" in r.stderr


def test_driven_values_rules_are_usage_errors(p105, tmp_path):
    model = EXAMPLES / "four_bar_ap242.stp"
    r = p105("solve", model, "--set", "X=1", "--to", "jsonl")
    assert r.returncode == 2 and r.stderr.decode().startswith("p105: error: 'X' is not a pair of mechanism")
    values = tmp_path / "v.csv"
    values.write_text("A\n0.1\n")
    r = p105("solve", model, "--values", values, "--set", "A=1", "--to", "jsonl")
    assert r.returncode == 2 and r.stderr.decode() == "p105: error: --set A: the pair is in --values too\n"


@pytest.mark.parametrize("model", [[], [EXAMPLES / "four_bar_ap242.stp", "--sweep", "A=0:1.5:3"]],
                         ids=["scene only", "on a model"])
def test_no_timings_leaves_every_time_out_of_a_scene_run(p105, model):
    # the cables' records and the scene's summary said how long they took even with --no-timings
    args = [*model, "--scene", EXAMPLES / "cable_scene.json", "--no-timings", "--to", "jsonl"]
    if not model:
        args += ["--keypoints", EXAMPLES / "cable_keypoints.jsonl"]
    first = p105("solve", *args)
    assert first.returncode == 0, first.stderr
    records = [json.loads(line) for line in first.stdout.splitlines()]
    assert any(r["type"] == "cable_state" for r in records)
    assert not [r for r in records if "time_s" in r]
    assert p105("solve", *args).stdout == first.stdout
    timed = p105("solve", *[a for a in args if a != "--no-timings"])
    assert [r for r in map(json.loads, timed.stdout.splitlines()) if "time_s" in r]

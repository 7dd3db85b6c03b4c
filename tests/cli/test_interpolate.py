"""p105 interpolate in process: formats/samples.py's records and the option rules."""

from __future__ import annotations

import csv
import io
import json

import pytest

from conftest import EXAMPLES

FOUR_BAR = EXAMPLES / "four_bar_ap242.stp"


def test_jsonl_ends_with_a_summary_and_csv_has_the_same_samples(p105):
    r = p105("interpolate", "--what", "paths", "--count", "5", FOUR_BAR)
    assert r.returncode == 0, r.stderr
    recs = [json.loads(line) for line in r.stdout.decode().splitlines()]
    frames = [x for x in recs if x["type"] == "frame"]
    assert recs[-1]["type"] == "summary" and recs[-1]["units"] == {"length": "m", "angle": "rad"}
    c = p105("interpolate", "--what", "paths", "--count", "5", "--to", "csv", FOUR_BAR)
    rows = list(csv.DictReader(io.StringIO(c.stdout.decode())))
    assert len(rows) == len(frames) > 0
    for row, f in zip(rows, frames):
        assert float(row["t"]) == f["t"] and float(row["m03"]) == f["matrix"][0][3]


@pytest.mark.parametrize("args, message", [
    (["--to", "csv"], "--to csv needs --what paths or --what configurations"),
    (["--count", "0"], "must be at least 1"),
    (["--step", "0.1", "--count", "3"], "give at most one of --t, --step and --count"),
    # options that would do nothing with the --what chosen
    (["--what", "configurations", "--ypr"], "--ypr adds to the kinematic paths' frames"),
    (["--what", "configurations", "--quaternion", "wxyz"], "--quaternion adds to the kinematic paths' frames"),
    (["--what", "configurations", "--path", "p"], "--path names a kinematic path"),
    (["--what", "paths", "--sequence", "s"], "--sequence names a configuration sequence"),
])
def test_option_rules(p105, args, message):
    r = p105("interpolate", *args, FOUR_BAR)
    assert r.returncode == 2 and message in r.stderr.decode()

"""p105 convert-dh-su in process: DH tables (formats/dh_table.py) to models and back."""

from __future__ import annotations

import pytest

from conftest import EXAMPLES

PUMA = EXAMPLES / "puma560_dh.csv"


def _rows(text):
    lines = text.strip().splitlines()
    return lines[0], [line.split(",") for line in lines[1:]]


def test_a_table_goes_to_a_model_and_back(p105, tmp_path):
    model = tmp_path / "puma.stp"
    r = p105("convert-dh-su", "--convention", "standard", PUMA, "-o", model)
    assert r.returncode == 0, r.stderr
    back = p105("convert-dh-su", "--to", "dh", "--convention", "standard", model)
    assert back.returncode == 0, back.stderr
    head, rows = _rows(back.stdout.decode())
    assert head == "name,type,a,alpha,d,theta,offset,lower,upper"   # the Puma's joints are limited
    assert [row[:2] for row in rows] == [[f"J{k}", "R"] for k in range(1, 7)]
    j = p105("convert-dh-su", "--to", "dh-json", "--convention", "standard", model)
    assert j.returncode == 0 and j.stdout.startswith(b"{\n")


@pytest.mark.parametrize("args, code, message", [
    (["convert-dh-su", PUMA], 2, "--convention standard|modified is required"),
    (["convert-dh-su", "--convention", "standard", EXAMPLES / "four_bar_ap242.stp"], 2,
     "is a model; convert-dh-su reads a DH table"),
    (["convert-dh-su", "--to", "dh", "--convention", "standard", PUMA], 2, "is a DH table; --to dh/dh-json"),
    (["convert-dh-su", "--to", "dh", "--convention", "standard", EXAMPLES / "four_bar_ap242.stp"], 1,
     "mechanism 'four_bar'"),
])
def test_wrong_inputs(p105, args, code, message):
    r = p105(*args)
    assert r.returncode == code and message in r.stderr.decode(), r.stderr


def test_table_errors_name_line_and_column(p105, tmp_path):
    bad = tmp_path / "bad.csv"
    bad.write_text("name,type,a,alpha,d,theta,offset\nJ1,R,0,x,0,,0\n")
    r = p105("convert-dh-su", "--convention", "standard", bad)
    assert r.returncode == 2 and r.stderr.decode().startswith(f"p105: error: {bad}:2:")

"""p105 graph in process: the four analysis formats (formats/graph.py) and the option rules."""

from __future__ import annotations

import json
import xml.etree.ElementTree as ET

import pytest

from conftest import EXAMPLES

FOUR_BAR = EXAMPLES / "four_bar_ap242.stp"


def test_json_is_the_structure_of_the_four_bar(p105):
    r = p105("graph", FOUR_BAR)
    assert r.returncode == 0, r.stderr
    doc = json.loads(r.stdout)
    assert doc["format"] == "p105-graph/1" and doc["mechanism"] == "four_bar"
    assert len(doc["links"]) == 4 and len(doc["loops"]) == 1   # one independent loop: 4 joints, 4 links
    assert r.stdout.endswith(b"}\n")


def test_dot_graphml_and_mermaid_name_every_link_and_joint(p105):
    links = {x["name"] for x in json.loads(p105("graph", FOUR_BAR).stdout)["links"]}
    dot = p105("graph", FOUR_BAR, "--to", "dot").stdout.decode()
    assert dot.startswith("digraph ") and dot.rstrip().endswith("}")
    assert all(f'"{n}"' in dot or f" {n} " in dot or f"{n} [" in dot for n in links)
    root = ET.fromstring(p105("graph", FOUR_BAR, "--to", "graphml").stdout)
    nodes = [e for e in root.iter() if e.tag.endswith("}node")]
    edges = [e for e in root.iter() if e.tag.endswith("}edge")]
    names = {d.text for n in nodes for d in n if d.get("key") == "n_name"}
    assert names == links and len(nodes) == 4 and len(edges) == 4
    mermaid = p105("graph", FOUR_BAR, "--to", "mermaid").stdout.decode()
    assert mermaid.startswith("flowchart LR\n") and all(n in mermaid for n in links)


@pytest.mark.parametrize("args, message", [
    (["--enrich", "--to", "dot"], "--enrich writes a model: use --to p21 or --to json"),
    (["--to", "p21"], "--to p21 writes a model: use it with --enrich"),
])
def test_option_rules(p105, args, message):
    r = p105("graph", FOUR_BAR, *args)
    assert r.returncode == 2 and message in r.stderr.decode() and r.stdout == b""

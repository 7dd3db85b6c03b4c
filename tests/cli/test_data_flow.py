"""Data flows once (issue 10, item 3): every command that reads a model builds at most one
Population and reads its mechanisms at most once.

Counted in process: ``Population.__init__`` (every population of any file the command reads)
and ``read_mechanism._Reader.mechanisms`` (a walk of the file's mechanisms into Mechanism
objects). ``export --schema`` does not re-read its own output; ``solve --to model`` does not
decode the model again to write the results.
"""

from __future__ import annotations

import pytest

from conftest import EXAMPLES, ROOT

FOUR_BAR = str(EXAMPLES / "four_bar_ap242.stp")
SLIDER_1996 = str(EXAMPLES / "slider_crank_p105_1996_ap214.stp")
UR5 = str(ROOT / "tests" / "data" / "corpus" / "ur5_arm_p105.stp")
PUMA_DH = str(EXAMPLES / "puma560_dh.csv")
TOOL_PATH = str(EXAMPLES / "puma560_tool_path.jsonl")


@pytest.fixture
def counted(p105, monkeypatch):
    """``run(*args, input=...) -> (result, populations, mechanism reads)``."""
    from p105cli.part105 import read_mechanism
    from p105cli.schema.population import Population

    counts = {"pop": 0, "read": 0}
    init, walk = Population.__init__, read_mechanism._Reader.mechanisms

    def counting_init(self, *a, **k):
        counts["pop"] += 1
        return init(self, *a, **k)

    def counting_walk(self):
        counts["read"] += 1
        return walk(self)

    monkeypatch.setattr(Population, "__init__", counting_init)
    monkeypatch.setattr(read_mechanism._Reader, "mechanisms", counting_walk)

    def run(*args, input=None):
        counts["pop"] = counts["read"] = 0
        r = p105(*args, input=input)
        return r, counts["pop"], counts["read"]

    return run


@pytest.fixture(scope="module")
def puma_model(tmp_path_factory):
    """The PUMA 560 of examples/ as an AP242 model (convert-dh-su), for solve --path."""
    from p105cli.cli import main

    out = tmp_path_factory.mktemp("puma") / "puma.stp"
    assert main(["convert-dh-su", "--convention", "standard", "-o", str(out), PUMA_DH]) == 0
    return str(out)


# (command line, at most populations, at most mechanism reads); export --schema has two: the
# source's, and the converted file's, which it validates before writing it
CASES = [
    (["parse", UR5], 0, 0),
    (["export", "--to", "json", UR5], 1, 0),
    (["export", "--schema", "ap242", UR5], 2, 1),
    (["export", "--schema", "ap214", FOUR_BAR], 2, 1),
    (["export", "--schema", "ap242", SLIDER_1996], 2, 1),
    (["validate", UR5], 1, 1),
    (["validate", FOUR_BAR], 1, 1),
    (["graph", UR5], 1, 1),
    (["graph", "--enrich", FOUR_BAR], 1, 1),
    (["solve", "--set", "J2=-1.2", "--to", "jsonl", "--no-timings", UR5], 1, 1),
    (["solve", "--program", "--no-timings", FOUR_BAR], 1, 1),
    (["solve", "--program", "--count", "5", "--no-timings", SLIDER_1996], 1, 1),
    (["solve", FOUR_BAR, "--sweep", "A=0:1.5:4", "--resulting-path", "coupler", "--no-timings"], 1, 1),
    (["interpolate", FOUR_BAR], 1, 1),
    (["interpolate", "--what", "paths", FOUR_BAR], 1, 1),
]


@pytest.mark.parametrize("args, pops, reads", CASES, ids=[" ".join(a[:-1]) for a, _, _ in CASES])
def test_one_population_and_one_mechanism_read_per_command(counted, args, pops, reads):
    r, n_pop, n_read = counted(*args)
    assert r.returncode in (0, 1), r.stderr
    assert n_pop <= pops and n_read <= reads, \
        f"{n_pop} populations, {n_read} mechanism reads"


@pytest.mark.parametrize("to", ["jsonl", "model"])
def test_inverse_analysis_reads_its_model_once(counted, puma_model, to):
    r, n_pop, n_read = counted("solve", puma_model, "--path", TOOL_PATH, "--target-link", "link6",
                               "--no-timings", "--to", to)
    assert r.returncode == 0, r.stderr
    assert n_pop <= 1 and n_read <= 1, f"{n_pop} populations, {n_read} mechanism reads"


@pytest.mark.parametrize("to", ["ap242", "dh"])
def test_convert_dh_su_reads_once(counted, puma_model, to):
    args = ["convert-dh-su", "--convention", "standard", PUMA_DH] if to == "ap242" \
        else ["convert-dh-su", "--convention", "standard", "--to", "dh", puma_model]
    r, n_pop, n_read = counted(*args)
    assert r.returncode == 0, r.stderr
    assert n_pop <= 1 and n_read <= 1, f"{n_pop} populations, {n_read} mechanism reads"


def test_the_counter_counts(counted):
    # the rule is only as good as the count: a command that reads a mechanism is seen doing it
    _, n_pop, n_read = counted("graph", UR5)
    assert n_pop >= 1 and n_read >= 1

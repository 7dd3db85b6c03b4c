# p105 — every target installs what it needs into .venv first, so a fresh
# machine with only Python 3.11+ runs `make demo` and `make test` as they are.

PYTHON ?= python3
VENV   ?= .venv
BIN     = $(VENV)/bin
PY      = $(BIN)/python
P105    = $(BIN)/p105
STAMP   = $(VENV)/.installed
# The compiled schemas (p105cli/schema/data/compiled/): rebuilt when the EXPRESS or its compiler changes
SCHEMAS = $(VENV)/.schemas
SHARED ?= ../shared
FUZZ_SECONDS ?= 120
FUZZ_SEED ?=

.PHONY: all install demo test test-all fuzz fuzz-commands man bench bench-parse bench-validate bench-graph bench-solve \
        bench-solve-scale bench-cable clean

all: test

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e '.[test]'
	touch $(STAMP)

$(SCHEMAS): $(STAMP) $(wildcard p105cli/schema/*.py p105cli/schema/data/*.exp)
	$(PY) -m p105cli.schema.compile
	touch $(SCHEMAS)

install: $(SCHEMAS)

# The main job on shipped examples (outputs in build/): gate a file with validate, prove the
# canonical Part 21 is a fixed point of the JSON round trip, convert a 1996-layout (AP214)
# mechanism to AP242 and gate the result, analyse the four-bar's structure, build a Puma 560
# from its DH table and follow a tool path by inverse analysis, solve the four-bar over a crank
# sweep and sample the results, route a cable along a moving end, validate the whole corpus.
demo: $(SCHEMAS)
	@mkdir -p build
	$(P105) validate --pass examples/four_bar_ap242.stp | $(P105) parse -o build/four_bar.json
	$(P105) export --to p21 build/four_bar.json -o build/four_bar.stp
	$(P105) parse build/four_bar.stp | $(P105) export --to p21 | cmp - build/four_bar.stp
	$(P105) parse --stream examples/slider_crank_p105_1996_ap214.stp | $(P105) export --to p21 > build/slider_crank.stp
	$(P105) -q export --schema ap242 examples/slider_crank_p105_1996_ap214.stp \
	  | $(P105) validate --pass -o build/slider_crank_ap242.report > build/slider_crank_ap242.stp
	$(P105) graph examples/four_bar_ap242.stp -o build/four_bar_graph.json
	$(P105) graph --enrich examples/four_bar_ap242.stp | $(P105) validate --pass -o build/four_bar_enriched.report \
	  > build/four_bar_enriched.stp
	$(P105) convert-dh-su --convention standard examples/puma560_dh.csv \
	  | $(P105) validate --pass -o build/puma560.report > build/puma560.stp
	$(P105) solve build/puma560.stp --path examples/puma560_tool_path.jsonl --target-link link6 --to csv \
	  -o build/puma560_tool_path.csv
	$(P105) solve examples/four_bar_ap242.stp --values examples/four_bar_crank.csv --angle-unit deg --to jsonl \
	  -o build/four_bar_motion.jsonl
	$(P105) solve examples/four_bar_ap242.stp --values examples/four_bar_crank.csv --angle-unit deg \
	  | $(P105) validate --pass -o build/four_bar_solved.report \
	  | $(P105) interpolate --what configurations --count 73 --to csv -o build/four_bar_configurations.csv
	$(P105) solve --scene examples/cable_scene.json --keypoints examples/cable_keypoints.jsonl -o build/cable.jsonl \
	  --plot build/cable_shapes.svg
	$(P105) validate -f sarif -o build/corpus.sarif tests/data/corpus/*_ap214.stp tests/data/corpus/*_ap242.stp
	$(P105) validate --schema p105 tests/data/corpus/*_p105.stp
	@echo "demo: every step passed; outputs in build/"

# two workers: the suite is CPU-bound and the machines have two cores or more
test: $(SCHEMAS)
	$(PY) -m pytest -q -m "not slow" -n 2

test-all: $(SCHEMAS)
	$(PY) -m pytest -q

# Every command in-process on byte, grammar and JSON-model mutations of the corpus, the examples
# and ../shared/external (exit 0, 1 or 2, never 3; no NaN/Infinity; -o untouched on failure),
# after the reader fuzzer for a fifth of FUZZ_SECONDS. FUZZ_SEED repeats a run. docs/fuzzing.md.
fuzz: $(SCHEMAS)
	P105_FUZZ_SECONDS=$(FUZZ_SECONDS) P105_FUZZ_SEED=$(FUZZ_SEED) $(PY) tests/fuzz_commands.py --reader-share 0.2

# The commands only (no reader fuzzer).
fuzz-commands: $(SCHEMAS)
	P105_FUZZ_SECONDS=$(FUZZ_SECONDS) P105_FUZZ_SEED=$(FUZZ_SEED) $(PY) tests/fuzz_commands.py

man: $(SCHEMAS)
	$(PY) -m p105cli.manpages man

bench: bench-parse bench-validate bench-graph bench-solve bench-solve-scale bench-cable
	$(PY) bench/collect_benchmarks.py

bench-parse: $(SCHEMAS)
	$(PY) -m pip install --quiet -e '.[bench]'
	$(PY) bench/bench_parse.py --corpus $(SHARED)/corpus/big --markdown docs/benchmarks-parse.md

bench-validate: $(SCHEMAS)
	$(PY) bench/bench_validate.py --corpus $(SHARED)/corpus/big --external $(SHARED)/external \
		--markdown docs/benchmarks-validate.md

bench-graph: $(SCHEMAS)
	$(PY) bench/bench_graph.py --markdown docs/benchmarks-graph.md

# Cable statics: patent vs rod vs scipy solve_bvp vs PyElastica (installed for this target only).
bench-cable: $(SCHEMAS)
	$(PY) -m pip install --quiet matplotlib pyelastica
	$(PY) bench/bench_cable.py --markdown docs/benchmarks-cable.md --plot docs/cable-accuracy-vs-time.png

# Position analysis: p105 vs roboticstoolbox and Pinocchio (installed for this target only).
bench-solve: $(SCHEMAS)
	$(PY) -m pip install --quiet roboticstoolbox-python pin
	$(PY) bench/bench_solve.py --markdown docs/benchmarks-solve.md

# Long serial chains (1,000, 3,000, 10,000 pairs): graph and solve time, the growth law (its own
# section of docs/benchmarks-solve.md; the 10,000-pair target of issue 11).
bench-solve-scale: $(SCHEMAS)
	$(PY) bench/bench_solve_scale.py --markdown docs/benchmarks-solve.md

clean:
	rm -rf build .pytest_cache .hypothesis

# p105 — every target installs what it needs into .venv first, so a fresh
# machine with only Python 3.11+ runs `make demo` and `make test` as they are.

PYTHON ?= python3
VENV   ?= .venv
BIN     = $(VENV)/bin
PY      = $(BIN)/python
P105    = $(BIN)/p105
STAMP   = $(VENV)/.installed
SHARED ?= ../shared
FUZZ_SECONDS ?= 120

.PHONY: all install demo test test-all fuzz man bench bench-parse bench-validate clean

all: test

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e '.[test]'
	$(PY) -m p105cli.schema.compile
	touch $(STAMP)

install: $(STAMP)

# The main job on shipped examples: gate the files with validate, convert
# Part 21 -> JSON model -> Part 21, and prove that the canonical form is a
# fixed point of the round trip; then validate the whole generated corpus.
demo: $(STAMP)
	@mkdir -p build
	$(P105) validate --pass examples/four_bar_ap242.stp | $(P105) parse -o build/four_bar.json
	$(P105) export --to p21 build/four_bar.json -o build/four_bar.stp
	$(P105) parse build/four_bar.stp | $(P105) export --to p21 | cmp - build/four_bar.stp
	$(P105) parse --stream examples/slider_crank_p105_1996_ap214.stp | $(P105) export --to p21 > build/slider_crank.stp
	$(P105) validate -f sarif -o build/corpus.sarif tests/data/corpus/*_ap214.stp tests/data/corpus/*_ap242.stp
	$(P105) validate --schema p105 tests/data/corpus/*_p105.stp
	@echo "demo: examples validate clean, round trip is byte-stable (build/)"

test: $(STAMP)
	$(PY) -m pytest -q -m "not slow"

test-all: $(STAMP)
	$(PY) -m pytest -q

fuzz: $(STAMP)
	P105_FUZZ_SECONDS=$(FUZZ_SECONDS) $(PY) tests/fuzz_reader.py

man: $(STAMP)
	$(PY) -m p105cli.manpages man

bench: bench-parse bench-validate

bench-parse: $(STAMP)
	$(PY) -m pip install --quiet -e '.[bench]'
	$(PY) bench/bench_parse.py --corpus $(SHARED)/corpus/big --markdown docs/benchmarks.md

bench-validate: $(STAMP)
	$(PY) bench/bench_validate.py --corpus $(SHARED)/corpus/big --markdown docs/benchmarks-validate.md

# Cable statics: patent vs rod vs scipy solve_bvp vs PyElastica (installed for this target only).
bench-cable: $(STAMP)
	$(PY) -m pip install --quiet matplotlib pyelastica
	$(PY) bench/bench_cable.py --markdown docs/benchmarks-cable.md --plot docs/cable-accuracy-vs-time.png

# Position analysis: p105 vs roboticstoolbox and Pinocchio (installed for this target only).
bench-solve: $(STAMP)
	$(PY) -m pip install --quiet roboticstoolbox-python pin
	$(PY) bench/bench_solve.py --markdown docs/benchmarks-solve.md

clean:
	rm -rf build .pytest_cache .hypothesis

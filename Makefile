# gear-diag: `make demo` runs a diagnosis end to end, `make test` runs the tests.
# The venv is created and the pinned dependencies installed on first use.

PYTHON_BOOT ?= python3
# the FMUs build side by side, one per core
MAKEFLAGS += --jobs=$(shell nproc 2>/dev/null || echo 2)
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed
# the effect models: those the Modelica package lists (docs/effects.md)
EFFECTS := $(shell cat modelica/GearDiag/Effects/package.order)
FMUS := build/GearPair.fmu $(patsubst %,build/effects/%.fmu,$(EFFECTS))
MODELICA := $(shell find modelica -name '*.mo')
BRIDGE := $(wildcard fmu_build/*.py)

.PHONY: venv fmu demo lint test test-fast test-e2e test-slow regress bless bench loop loop-real loop-phm09 clean

venv: $(STAMP)

# The checkout is installed as an editable package (pyproject.toml): `.venv/bin/pydiag`
# is its console script, and edits take effect at once.
$(STAMP): requirements.txt pyproject.toml
	$(PYTHON_BOOT) -m venv $(VENV)
	$(PY) -m pip install --quiet --disable-pip-version-check --no-deps -r requirements.txt
	touch $(STAMP)

fmu: $(FMUS)

build/GearPair.fmu: $(MODELICA) $(BRIDGE) $(STAMP)
	$(PY) -m fmu_build modelica/GearDiag/GearPair.mo --model GearDiag.GearPair -o $@

build/effects/%.fmu: $(MODELICA) $(BRIDGE) $(STAMP)
	$(PY) -m fmu_build modelica/GearDiag/Effects/$*.mo --model GearDiag.Effects.$* -o $@

demo: fmu
	$(PY) -m pydiag demo --fmu build/GearPair.fmu

lint: $(STAMP)
	$(VENV)/bin/ruff check .

# after the linter, on every core (pytest-xdist): the unit tests, the FMU builds and the
# evidence (every hidden effect of the independent simulator on three seeds, none on three)
test: fmu lint
	$(PY) -m pytest -q -n auto --dist worksteal --durations=10 --ignore=tests/e2e tests

# the edit-test loop: the linter and the unit tests (a handful of FMU simulations)
test-fast: lint build/GearPair.fmu
	$(PY) -m pytest -q -n auto tests/unit tests/test_layers.py

# the commands end to end (the CLI, the shared real records, the machine's own model, the
# loop); CI runs it after make test (.ci/run)
test-e2e: fmu
	$(PY) -m pytest -q -n auto --dist worksteal --durations=10 tests/e2e

# the slow tier (more seeds, backlash at the mesh resonance, every Table 1 case, a fresh
# install), on every core as make test is
test-slow: fmu
	$(PY) -m pytest -q -m slow -n auto --dist worksteal --durations=10

regress: fmu
	$(PY) -m pydiag regress --fmu build/GearPair.fmu --golden tests/golden/GearPair.json

bless: fmu
	$(PY) -m pydiag regress --fmu build/GearPair.fmu --golden tests/golden/GearPair.json --bless --force

bench: fmu
	$(PY) bench/paper_cases.py

# docs/loop.md, end to end: a measurement with a bearing defect the base model lacks
loop: fmu
	bash docs/loop.sh

# the loop on the shared real records, as bench/RESULTS.md section 10 has it (the GFD
# records in ../shared/data/gfd; GFD_DATA=folder for another set in that layout)
GFD_DATA ?= ../shared/data/gfd
loop-real: fmu
	$(PY) bench/real_loop.py --data "$(GFD_DATA)" --steps 5 --gain curve

# the loop on the machine's own model of the PHM09 gearbox, as section 13 has it (a copy of
# the example machine file in build/ gets the accepted effects: build/phm09.loop.toml);
# another record of the five: PHM09_RECORD="spur 2_30hz_High_1", and for a 45 Hz one
# PHM09_RPM=2700 as well
PHM09_DATA ?= ../shared/data/phm09
PHM09_RECORD ?= spur 1_30hz_High_1
PHM09_RPM ?= 1800
loop-phm09: fmu
	cp examples/phm09_spur.toml build/phm09.toml
	$(PY) -m pydiag loop --machine build/phm09.toml --channel ch1 --sample-rate 66666.67 \
	    --measurement "$(PHM09_DATA)/$(PHM09_RECORD).zip" --rpm $(PHM09_RPM) \
	    --max-steps 6 --force --history build/phm09_loop.sqlite

clean:
	rm -rf build

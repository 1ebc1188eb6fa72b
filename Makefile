# gear-diag: `make demo` runs a diagnosis end to end, `make test` runs the tests.
# The venv is created and the pinned dependencies installed on first use.

PYTHON_BOOT ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed
EFFECTS := GearEccentricity GearToothFault SecondPinionToothFault Backlash BearingOuterRace \
           BearingInnerRace LoadFluctuation
FMUS := build/GearPair.fmu $(patsubst %,build/effects/%.fmu,$(EFFECTS))
MODELICA := $(shell find modelica -name '*.mo')
BRIDGE := $(wildcard fmu_build/*.py)

.PHONY: venv fmu demo test test-slow regress bless bench loop clean

venv: $(STAMP)

# The checkout goes on the venv's path through a .pth file, and `pydiag` is a launcher:
# no build step, edits take effect at once.
$(STAMP): requirements.txt
	$(PYTHON_BOOT) -m venv $(VENV)
	$(PY) -m pip install --quiet --disable-pip-version-check -r requirements.txt
	$(PY) -c 'import site, os; open(os.path.join(site.getsitepackages()[0], "gear_diag.pth"), "w").write(os.getcwd() + "\n")'
	printf '#!/bin/sh\nexec "%s/bin/python" -m pydiag "$$@"\n' "$(abspath $(VENV))" > $(VENV)/bin/pydiag
	chmod +x $(VENV)/bin/pydiag
	touch $(STAMP)

fmu: $(FMUS)

build/GearPair.fmu: $(MODELICA) $(BRIDGE) $(STAMP)
	$(PY) -m fmu_build modelica/GearDiag/GearPair.mo --model GearDiag.GearPair -o $@

build/effects/%.fmu: $(MODELICA) $(BRIDGE) $(STAMP)
	$(PY) -m fmu_build modelica/GearDiag/Effects/$*.mo --model GearDiag.Effects.$* -o $@

demo: fmu
	$(PY) -m pydiag demo --fmu build/GearPair.fmu

test: fmu
	$(PY) -m pytest -q

test-slow: fmu
	$(PY) -m pytest -q -m slow

regress: fmu
	$(PY) -m pydiag regress --fmu build/GearPair.fmu --golden tests/golden/GearPair.json

bless: fmu
	$(PY) -m pydiag regress --fmu build/GearPair.fmu --golden tests/golden/GearPair.json --bless

bench: fmu
	$(PY) bench/paper_cases.py

# docs/loop.md, end to end: a measurement with a bearing defect the base model lacks
loop: fmu
	bash docs/loop.sh

clean:
	rm -rf build

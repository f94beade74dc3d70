# nfmr — one-command setup, run, test and benchmark on a fresh machine (Python 3.10+).
PYTHON ?= python3
VENV   ?= .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.nfmr-installed

.PHONY: setup run test bench clean

setup: $(STAMP)

$(STAMP): setup.py setup.cfg package.xml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[test]'
	touch $(STAMP)

run: setup
	$(BIN)/nfmr-eval --controller dlsmc --trajectory sine --x0 1,4,0 --duration 100

test: setup
	$(BIN)/python -m pytest -q

bench: setup
	$(BIN)/python -m nfmr_dlsmc.benchmarks

clean:
	rm -rf $(VENV) build *.egg-info

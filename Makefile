# nfmr — one-command setup, run, test and benchmark on a fresh machine (Python 3.10+).
PYTHON ?= python3
VENV   ?= .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.nfmr-installed

.PHONY: setup run test bench report clean

setup: $(STAMP)

PKG_LIB   := $(VENV)/lib/nfmr_dlsmc
PKG_SHARE := $(VENV)/share/nfmr_dlsmc
INDEX     := $(VENV)/share/ament_index/resource_index/packages

$(STAMP): setup.py setup.cfg package.xml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[test]'
	# The ament layout that `ros2 run` and ament_index expect, as colcon would install it:
	# executables in lib/<pkg>, the package marker in the index, package.xml and config.
	mkdir -p $(PKG_LIB) $(PKG_SHARE) $(INDEX)
	ln -sf ../../bin/controller $(PKG_LIB)/controller
	ln -sf ../../bin/sim $(PKG_LIB)/sim
	cp resource/nfmr_dlsmc $(INDEX)/nfmr_dlsmc
	ln -sfn $(CURDIR)/package.xml $(PKG_SHARE)/package.xml
	ln -sfn $(CURDIR)/config $(PKG_SHARE)/config
	touch $(STAMP)

run: setup
	$(BIN)/nfmr-run

test: setup
	$(BIN)/python -m pytest -q

bench: setup
	$(BIN)/nfmr-bench --nodes

report: setup
	$(BIN)/nfmr-compare --out report

clean:
	rm -rf $(VENV) build *.egg-info

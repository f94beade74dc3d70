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
	# Relative links: the clone may move; `source .venv/bin/activate` sets AMENT_PREFIX_PATH
	# as a ROS install's setup script does.
	ln -sfn $$(realpath -m --relative-to=$(PKG_SHARE) package.xml) $(PKG_SHARE)/package.xml
	ln -sfn $$(realpath -m --relative-to=$(PKG_SHARE) config) $(PKG_SHARE)/config
	grep -q AMENT_PREFIX_PATH $(BIN)/activate || printf '%s\n' \
	    'export AMENT_PREFIX_PATH="$$VIRTUAL_ENV$${AMENT_PREFIX_PATH:+:$$AMENT_PREFIX_PATH}"' \
	    >> $(BIN)/activate
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

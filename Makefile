# nfmr — one-command setup, run, test and benchmark on a fresh machine (Python 3.10+).
PYTHON ?= python3
VENV   ?= .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.nfmr-installed

.PHONY: setup run test test-fast test-slow test-all bench report results docs clean mutate

setup: $(STAMP)

PKG_LIB   := $(VENV)/lib/nfmr_dlsmc
PKG_SHARE := $(VENV)/share/nfmr_dlsmc
INDEX     := $(VENV)/share/ament_index/resource_index/packages

$(STAMP): setup.py setup.cfg package.xml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	# Everything: the [test] extra takes [plots], [tune] and [cluster] (setup.py).
	$(BIN)/python -m pip install --quiet -e '.[test]'
	# The ament layout that `ros2 run` and ament_index expect, as colcon would install it:
	# executables in lib/<pkg>, the package marker in the index, package.xml and config.
	mkdir -p $(PKG_LIB) $(PKG_SHARE) $(INDEX)
	ln -sf ../../bin/nfmr-controller $(PKG_LIB)/controller
	ln -sf ../../bin/nfmr-sim $(PKG_LIB)/sim
	ln -sf ../../bin/nfmr-wheel-odometry $(PKG_LIB)/wheel_odometry
	cp resource/nfmr_dlsmc $(INDEX)/nfmr_dlsmc
	# Relative links: the clone may move; `source .venv/bin/activate` sets AMENT_PREFIX_PATH
	# as a ROS install's setup script does.
	ln -sfn $$(realpath -m --relative-to=$(PKG_SHARE) package.xml) $(PKG_SHARE)/package.xml
	ln -sfn $$(realpath -m --relative-to=$(PKG_SHARE) config) $(PKG_SHARE)/config
	grep -q AMENT_PREFIX_PATH $(BIN)/activate || printf '%s\n' \
	    'export AMENT_PREFIX_PATH="$$VIRTUAL_ENV$${AMENT_PREFIX_PATH:+:$$AMENT_PREFIX_PATH}"' \
	    >> $(BIN)/activate
	touch $(STAMP)

# This clone's install first, as `source .venv/bin/activate` puts it: with another nfmr
# environment active, its share/ would otherwise be taken for this clone's shipped files.
OWN := AMENT_PREFIX_PATH="$(abspath $(VENV))$${AMENT_PREFIX_PATH:+:$$AMENT_PREFIX_PATH}"

run: setup
	$(OWN) $(BIN)/nfmr-run

# The suite in two tiers: `make test` every test but the whole runs marked slow (faults of
# running processes, benchmarks, comparisons and tunings on the chassis); `make test-all`
# both tiers, as CI runs them.
test: setup
	$(OWN) $(BIN)/python -m pytest -q -m 'not slow'

# The edit loop: no node, no pybullet world, no command started, no long closed loop.
test-fast: setup
	$(OWN) $(BIN)/python -m pytest -q -m 'not ros and not sim and not commands and not long and not slow'

test-slow: setup
	$(OWN) $(BIN)/python -m pytest -q -m slow

test-all: test test-slow

bench: setup
	$(OWN) $(BIN)/nfmr-bench --nodes

report: setup
	$(OWN) $(BIN)/nfmr-compare --out report

# The measured figures the docs quote, each with the command that measured it (doc/results.md;
# test_results_file.py fails on a quote that differs from it or a count of the tree gone
# stale). A few minutes on one core; FIGURES='NAME ...' measures only those.
FIGURES ?=

results: setup
	$(OWN) $(BIN)/python -m nfmr_dlsmc.analysis.results_file doc/results.md $(FIGURES)

# The parameter reference, generated from the schema (test_parameter_schema.py checks it).
docs: setup
	$(BIN)/python -m nfmr_dlsmc.analysis.parameter_reference doc/parameters.md

# Mutation testing of the core laws and guards with the fast tests (doc/mutation.md; the
# [mutmut] section of setup.cfg says which modules and tests). Incremental: mutants/ keeps
# the verdicts and only changed functions are tested again; `rm -rf mutants` starts over.
# MUTANTS narrows the run, e.g. make mutate MUTANTS='nfmr_dlsmc.core.steering.*'.
MUTATE_JOBS ?= 2
MUTANTS     ?=
MUTMUT      := $(BIN)/mutmut

$(MUTMUT): $(STAMP)
	$(BIN)/python -m pip install --quiet -e '.[test,mutate]'

mutate: $(MUTMUT)
	$(MUTMUT) run --max-children $(MUTATE_JOBS) $(MUTANTS)
	$(MUTMUT) export-cicd-stats >/dev/null
	@$(BIN)/python -c 'import json; s = json.load(open("mutants/mutmut-cicd-stats.json")); \
	    c = s["killed"] + s["timeout"]; \
	    print("mutation score: {c} of {total} mutants caught ({p:.1f} %): killed {killed}, timeout {timeout}, " \
	          "survived {survived}, no tests {no_tests}, suspicious {suspicious}".format(c=c, p=100.0 * c / max(1, s["total"]), **s))'
	@echo "not killed (mutmut show NAME for the diff):"
	@$(MUTMUT) results

clean:
	rm -rf $(VENV) build *.egg-info

# Two commands do all the set-up on a fresh machine:
#   make demo   - the main job (virtual machine tool -> real nodes -> summary)
#   make test   - ruff, then the whole test suite
# Both create or refresh .venv, install the pinned wheels, build msg_defs/ into
# the mt_accuracy_msgs interface package and install this package. A second run
# with nothing changed only checks stamps.

PYTHON ?= python3
VENV   ?= .venv
PY      = $(VENV)/bin/python
# Two workers, each taking whole test files (module fixtures run once), the slowest
# files first (test/conftest.py): the suite's wall time on 2 cores, idle or loaded.
PYTEST_ARGS ?= -rs -n 2 --dist loadfile --no-loadscope-reorder

DEPS_STAMP = $(VENV)/.deps-stamp
MSGS_STAMP = $(VENV)/.msgs-stamp
PKG_STAMP  = $(VENV)/.pkg-stamp
BENCH_STAMP = $(VENV)/.bench-stamp
MSG_SOURCES = $(shell find msg_defs -type f)
PKG_SOURCES = $(shell find mt_accuracy_ros resource config -type f -not -name '*.pyc' 2>/dev/null)

.PHONY: setup browser test test-repeat test-loaded demo bench clean

setup: $(PKG_STAMP) browser

# The report test renders in a real headless Chromium (Debian's package). Installed
# here where it can be (root with apt); elsewhere that one test is skipped.
browser:
	@command -v chromium >/dev/null 2>&1 || { test "$$(id -u)" = 0 && command -v apt-get >/dev/null 2>&1 && \
	  { apt-get install -y -q chromium >/dev/null 2>&1 || { apt-get update -q >/dev/null 2>&1 && \
	    apt-get install -y -q chromium >/dev/null 2>&1; }; }; } || \
	  echo "chromium not installed: the browser test of the report will be skipped"

$(DEPS_STAMP): requirements.txt
	test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -r requirements.txt
	touch $@

$(MSGS_STAMP): $(DEPS_STAMP) $(MSG_SOURCES) tools/build_msgs.py
	$(PY) tools/build_msgs.py
	touch $@

# A real (non-editable) install, so data_files land in the prefix: the ament
# index marker, package.xml and config/ under share/.
$(PKG_STAMP): $(MSGS_STAMP) setup.py setup.cfg package.xml $(PKG_SOURCES)
	$(PY) -m pip install --quiet --no-deps --no-build-isolation --force-reinstall .
	rm -rf build/lib build/bdist* mt_accuracy_ros.egg-info
	touch $@

# The linter first (ruff.toml: pyflakes and pycodestyle, lines up to 100), then the suite.
test: setup
	$(VENV)/bin/ruff check .
	$(PY) -m pytest test $(PYTEST_ARGS)

# The suite must pass on any fresh machine, idle or loaded (issue 17).
test-repeat: setup
	tools/repeat_tests.sh 5 0

test-loaded: setup
	tools/repeat_tests.sh 3 2

demo: setup
	$(PY) -m mt_accuracy_ros.cli demo --out demo_output

$(BENCH_STAMP): $(PKG_STAMP) requirements-bench.txt
	$(PY) -m pip install --quiet -r requirements-bench.txt
	touch $@

bench: $(BENCH_STAMP)
	$(PY) -m bench.run_all

clean:
	rm -rf build $(VENV) demo_output *.egg-info

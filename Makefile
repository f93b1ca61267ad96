# Quick start on a fresh machine (Python 3.11): `make run`, then `make test`; `make docs` builds the site.
PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed
TEST_STAMP := $(VENV)/.installed-test
KERNELS_STAMP := $(VENV)/.compiled
DOCS_STAMP := $(VENV)/.installed-docs
# pytest-xdist workers: one per core, at most 4 (each holds its own compiled kernels, about 1.5 GB)
WORKERS ?= $(shell $(PYTHON) -c "import os; print(min(4, len(os.sched_getaffinity(0))))")
PYTEST := $(PY) -m pytest -q -n $(WORKERS) --dist loadfile

.PHONY: run test test-slow docs install clean

run: $(STAMP)
	$(PY) examples/paper_example3.py

# Every test but the long end-to-end ones (marked slow in pyproject.toml); `make test-slow` runs those.
# The tests of one file run in one worker, in order (their module fixtures are made once).
test: $(TEST_STAMP)
	bash scripts/install-chromium.sh
	$(PYTEST) -m "not slow"

test-slow: $(TEST_STAMP)
	bash scripts/install-chromium.sh
	$(PYTEST) -m slow

# The documentation site (Sphinx), warnings as errors; the gallery's scripts run as it builds.
# Then the checks of the built pages (tests/test_docs.py: MathJax served from the site's _static).
docs: $(DOCS_STAMP) $(TEST_STAMP)
	MPLBACKEND=Agg $(PY) -m sphinx -W --keep-going -b html docs docs/_build/html
	$(PY) -m pytest -q tests/test_docs.py

install: $(STAMP) $(KERNELS_STAMP)

$(VENV)/bin/python:
	@echo "making the virtual environment $(VENV) ($(PYTHON) -m venv)"
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip

$(STAMP): pyproject.toml | $(VENV)/bin/python
	@echo "installing mbsynth and its dependencies into $(VENV) (pip, from the network)"
	$(PY) -m pip install --quiet -e .
	touch $@

# The compiled path's kernels, compiled once per machine in helper processes (the flagship
# walk runs on the KKT path and needs none; the tests use them throughout).
$(KERNELS_STAMP): $(STAMP)
	$(PY) -m mbsynth.cli.compile_ahead
	touch $@

$(TEST_STAMP): pyproject.toml $(STAMP) $(KERNELS_STAMP)
	$(PY) -m pip install --quiet -e '.[test]'
	touch $@

$(DOCS_STAMP): pyproject.toml $(STAMP)
	$(PY) -m pip install --quiet -e '.[docs]'
	touch $@

clean:
	rm -rf $(VENV) build *.egg-info docs/_build docs/auto_gallery

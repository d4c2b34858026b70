# Two commands on a fresh machine: `make demo` and `make test`.
PYTHON ?= python3
VENV   ?= .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed
OUT    ?= demo_output
# Exact versions known to pass the whole suite (`make lock` refreshes them); pyproject.toml keeps loose ranges.
# PIP_CONSTRAINT also pins the build backend in pip's isolated build environment.
CONSTRAINTS := $(CURDIR)/requirements/constraints.txt
# `make test-latest` and `make lock`: a separate environment with the newest releases pyproject.toml allows
LATEST_VENV ?= .venv-latest
export VTK_DEFAULT_OPENGL_WINDOW ?= vtkEGLRenderWindow
export MPLBACKEND ?= Agg

.PHONY: all demo demo-video test test-durations test-fast test-latest lock bench venv system-deps browser clean docs docs-quick

all: test

$(STAMP): pyproject.toml requirements/constraints.txt
	@test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	PIP_CONSTRAINT=$(CONSTRAINTS) $(BIN)/python -m pip install --quiet --upgrade pip
	PIP_CONSTRAINT=$(CONSTRAINTS) $(BIN)/python -m pip install --quiet -e '.[test]'
	@touch $(STAMP)

venv: $(STAMP) system-deps

# Off-screen rendering needs EGL/Mesa; install them from Debian when missing (root, apt only).
system-deps:
	@if ! ldconfig -p 2>/dev/null | grep -q 'libEGL.so.1'; then \
	  if command -v apt-get >/dev/null 2>&1 && [ "$$(id -u)" = 0 ]; then \
	    echo "installing libegl1 libgl1-mesa-dri libgbm1 for headless rendering"; \
	    apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq libegl1 libgl1-mesa-dri libgbm1 >/dev/null; \
	  else echo "warning: libEGL not found; mesh rendering may fail (install libegl1 libgl1-mesa-dri libgbm1)"; fi; \
	fi

# The report test renders the HTML report in headless Chromium (Debian's package), installed when missing.
browser:
	@if ! command -v chromium >/dev/null 2>&1; then \
	  if command -v apt-get >/dev/null 2>&1 && [ "$$(id -u)" = 0 ]; then \
	    echo "installing chromium for the headless report test"; \
	    apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium >/dev/null; \
	  else echo "warning: chromium not found; the browser test will be skipped (apt-get install chromium)"; fi; \
	fi

demo: venv
	@echo "[demo 1/3] static Gor'kov sweep at the defaults: CSV, static coefficients, figures, rendered mesh"
	$(BIN)/python -m acousim sweep --out $(OUT)/sweep.csv --plots $(OUT)/sweep_figures --coefficients $(OUT)/static_coefficients.json --render $(OUT)/dimer_gorkov.png
	@echo "[demo 2/3] digital twin: the paper-like data set (12 runs of 4 s)"
	$(BIN)/python -m acousim simulate --preset paper-like --runs 12 --seed 1 --out $(OUT)/twin --figures $(OUT)/twin_figures --force --no-progress
	@echo "[demo 3/3] fit, compare, diagnose and report"
	$(BIN)/python -m validation report $(OUT)/twin --out $(OUT)/report
	@echo "demo written to $(OUT)/: open $(OUT)/report/report.html"

# The same job from camera frames: the twin renders high-speed video, the tracking measures it, the report reads it.
demo-video: venv
	@echo "[demo-video 1/3] digital twin with its camera: 8 field drops (60 frames at rest, the fall, 2 s of motion) as 180 x 150 px video (OUT/video_twin/video/)"
	$(BIN)/python -m acousim simulate --preset paper-like --runs 8 --duration 2 --seed 3 --video --rest-frames 60 --out $(OUT)/video_twin --force --no-progress
	@echo "[demo-video 2/3] tracking: video to runs of (t, y, theta), each the field-on motion with t = 0 at the field's return"
	$(BIN)/python -m tracking track $(OUT)/video_twin/video --out $(OUT)/tracked --force
	@echo "[demo-video 3/3] fit, compare, diagnose and report, with the tracking's section"
	$(BIN)/python -m validation report $(OUT)/tracked --out $(OUT)/report_video
	@echo "written to $(OUT)/: open $(OUT)/report_video/report.html"

# One pytest worker per core (pytest-xdist), each test file on one worker so that module fixtures are built
# once, the boundary-element files together and the files that use a dask cluster together (tests/conftest.py);
# one numba and one BLAS thread per worker
# (the boundary-element assembly is numba-parallel; the workers already keep every core busy, and more threads
# per worker only compete for them).
PYTEST_WITH = NUMBA_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1 \
	CUBEDIMER_REQUIRE_BROWSER=$$(command -v chromium >/dev/null 2>&1 && echo 1 || echo 0) \
	$(1)/python -m pytest -q -n auto --dist loadfile
PYTEST := $(call PYTEST_WITH,$(BIN))

test: venv browser
	$(PYTEST)

# The whole suite on the newest releases (no constraints) in $(LATEST_VENV), made afresh: an upgrade is a decision.
test-latest: system-deps browser
	rm -rf $(LATEST_VENV)
	$(PYTHON) -m venv $(LATEST_VENV)
	$(LATEST_VENV)/bin/python -m pip install --quiet --upgrade pip hatchling
	$(LATEST_VENV)/bin/python -m pip install --quiet -e '.[test]'
	$(call PYTEST_WITH,$(LATEST_VENV)/bin)

# Refresh the constraints: the newest releases, the whole suite, and the freeze only if it passes (the build
# backend hatchling is installed there too, so that its version is frozen with the rest).
lock: test-latest
	@mkdir -p requirements
	@{ echo "# Exact versions of the test and demo environment, frozen by \`make lock\` after the whole suite passed"; \
	   echo "# on them ($$($(LATEST_VENV)/bin/python --version), $$(date -u +%Y-%m-%d)). Used as pip constraints by make demo/test."; \
	   $(LATEST_VENV)/bin/python -m pip freeze --all --exclude-editable | grep -v -i -E '^(setuptools|wheel)=='; \
	} > requirements/constraints.txt.new
	mv requirements/constraints.txt.new requirements/constraints.txt
	@echo "requirements/constraints.txt refreshed from $(LATEST_VENV)"

# the seconds of each test unit from this checkout's last full `make test`, committed so that a fresh clone's
# `make test` also starts the longest units first (tests/conftest.py)
test-durations:
	@test -f .pytest_cache/v/cubedimer/unit_seconds || { echo "run make test first"; exit 2; }
	cp .pytest_cache/v/cubedimer/unit_seconds tests/unit_durations.json

test-fast: venv
	$(PYTEST) -m "not slow"

# The documentation site, offline, warnings as errors: the guides of docs/, the API reference of every package's
# public API and the example gallery of examples/, executed (a few minutes on 2 cores); open docs/_build/html/index.html.
# `make docs-quick` builds the same pages without executing the gallery (CI).
DOCS_STAMP := $(VENV)/.installed-docs
SPHINX = $(abspath $(BIN))/python -m sphinx -b html -W --keep-going -q . _build/html

$(DOCS_STAMP): $(STAMP)
	PIP_CONSTRAINT=$(CONSTRAINTS) $(BIN)/python -m pip install --quiet -e '.[test,docs]'
	@touch $(DOCS_STAMP)

docs: venv $(DOCS_STAMP)
	rm -rf docs/_build docs/auto_examples docs/api/generated
	cd docs && NUMBA_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1 $(SPHINX)
	@echo "site written: docs/_build/html/index.html"

docs-quick: venv $(DOCS_STAMP)
	rm -rf docs/_build docs/auto_examples docs/api/generated
	cd docs && $(SPHINX) -D plot_gallery=0
	@echo "site written without executing the gallery: docs/_build/html/index.html"

bench: venv
	$(BIN)/python -m benchmarks --out benchmarks/results.md

clean:
	rm -rf $(VENV) $(LATEST_VENV) $(OUT) .pytest_cache docs/_build docs/auto_examples docs/api/generated "$${XDG_CACHE_HOME:-$$HOME/.cache}/cubedimer/numba"

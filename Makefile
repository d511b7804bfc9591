# Quick start: `make demo` (set up + render the gallery) and `make test` (set up + run the tests).
# `make test` also installs the [reference] extra (Mitsuba 3) so the cross-checks against it run, the [viewer]
# extra and Xvfb (tools/install-system-packages) so the viewer's window tests run, and the [ar] extra (OpenCV).
PYTHON ?= python3
VENV   ?= .venv
BIN    := $(VENV)/bin
OUT    ?= out/demo

.PHONY: demo test lint bench clean

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)

# Stamp files: reinstall only when pyproject.toml changes.
$(VENV)/.installed: pyproject.toml | $(BIN)/python
	$(BIN)/python -m pip install --quiet -e .
	touch $@

$(VENV)/.installed-test: pyproject.toml | $(BIN)/python
	tools/install-system-packages
	$(BIN)/python -m pip install --quiet -e ".[test,reference,viewer,ar]"
	touch $@ $(VENV)/.installed

demo: $(VENV)/.installed
	$(BIN)/reflets demo -o $(OUT)

test: $(VENV)/.installed-test
	$(BIN)/python -m pytest -q

lint: $(VENV)/.installed-test
	$(BIN)/ruff check src tests
	$(BIN)/lint-imports --no-cache

clean:
	rm -rf $(VENV) out build *.egg-info src/*.egg-info

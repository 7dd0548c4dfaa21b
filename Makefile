# Two entry points: `make demo` and `make test`; each bootstraps .venv on a fresh machine.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP_DEMO := $(VENV)/.installed-demo
STAMP_TEST := $(VENV)/.installed-test

.PHONY: demo test lint typecheck check-specs bench fuzz clean

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip

$(STAMP_DEMO): pyproject.toml | $(BIN)/python
	$(BIN)/python -m pip install --quiet -e '.[plot]'
	touch $@

$(STAMP_TEST): pyproject.toml | $(BIN)/python
	$(BIN)/python -m pip install --quiet -e '.[test,plot]'
	touch $@

demo: $(STAMP_DEMO)
	$(BIN)/python -m uvms_model.demo out

lint: $(STAMP_TEST)
	$(BIN)/ruff check hybrid uvms_model tests bench conftest.py

typecheck: $(STAMP_TEST)
	$(BIN)/mypy hybrid uvms_model

check-specs: $(STAMP_TEST)
	$(BIN)/hybrid validate specs/*.yaml
	$(BIN)/hybrid check specs/*.yaml

test: lint typecheck check-specs
	$(BIN)/python -m pytest -q

bench: $(STAMP_TEST)
	$(BIN)/python -m bench

fuzz: $(STAMP_TEST)
	HYBRID_FUZZ=1 $(BIN)/python -m pytest -q tests/simulation/native/test_native_property.py

clean:
	rm -rf $(VENV) out .pytest_cache .mypy_cache .ruff_cache

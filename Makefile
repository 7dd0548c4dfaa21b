# Entry points: `make demo`, `make test` and `make docs`; each bootstraps .venv on a fresh machine.
# `demo`, `test` and `docs` install hybrid and, beside it, the UVMS case study (uvms_model/, its own
# distribution `hybrid-uvms`, which registers the function library its specs use).
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP_DEMO := $(VENV)/.installed-demo
STAMP_TEST := $(VENV)/.installed-test
STAMP_DOCS := $(VENV)/.installed-docs

.PHONY: demo test docs lint typecheck check-specs bench fuzz clean

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip

$(STAMP_DEMO): pyproject.toml uvms_model/pyproject.toml | $(BIN)/python
	$(BIN)/python -m pip install --quiet -e '.[plot]' -e ./uvms_model
	touch $@

$(STAMP_TEST): pyproject.toml uvms_model/pyproject.toml | $(BIN)/python
	$(BIN)/python -m pip install --quiet -e '.[test,plot]' -e ./uvms_model
	touch $@

$(STAMP_DOCS): pyproject.toml uvms_model/pyproject.toml | $(BIN)/python
	$(BIN)/python -m pip install --quiet -e '.[docs]' -e ./uvms_model
	touch $@

demo: $(STAMP_DEMO)
	$(BIN)/python -m uvms_model.demo out

lint: $(STAMP_TEST)
	$(BIN)/ruff check hybrid uvms_model tests bench conftest.py docs/conf.py docs/_ext

typecheck: $(STAMP_TEST)
	$(BIN)/mypy hybrid uvms_model

check-specs: $(STAMP_TEST)
	$(BIN)/hybrid validate specs/*.yaml
	$(BIN)/hybrid check specs/*.yaml

# The suite on every core (pytest-xdist), each test file on one worker (its fixtures made once).
# mypy (about 40 s of one core from a fresh clone) runs beside it rather than before it; its
# report follows the suite's, and either failing fails the target.
test: lint check-specs
	@echo "$(BIN)/mypy hybrid uvms_model  (beside the suite; its report follows it)"
	@$(BIN)/mypy hybrid uvms_model > $(VENV)/mypy-report.txt 2>&1 & typecheck=$$!; \
	$(BIN)/python -m pytest -q -n auto --dist loadfile; suite=$$?; \
	wait $$typecheck; typed=$$?; \
	echo "$(BIN)/mypy hybrid uvms_model:"; cat $(VENV)/mypy-report.txt; \
	[ $$suite -eq 0 ] && [ $$typed -eq 0 ]

# The site, from scratch, every warning an error (docs/writing-docs.md); open docs/_build/html/index.html.
docs: $(STAMP_DOCS)
	rm -rf docs/_build/html docs/_build/doctrees
	$(BIN)/python -m sphinx -b html -W --keep-going -q -d docs/_build/doctrees docs docs/_build/html
	@echo "built docs/_build/html/index.html"

bench: $(STAMP_TEST)
	$(BIN)/python -m bench

# Randomized tests at full size (well over an hour on 2 cores): every test marked `fuzz`,
# with HYBRID_FUZZ=1 scaling the example counts (check vs simulate: 5,000 models; loader:
# 100,000 mutated specs), and the simulation fuzz (2,000 generated models with every
# solver method) with 20 Ctrl-C at random moments of a long run, and 25 Ctrl-C at random
# moments of each command plus kill -9 of simulate (both backends) and of a sweep resumed.
fuzz: $(STAMP_TEST)
	HYBRID_FUZZ=1 $(BIN)/python -m pytest -q -p no:cacheprovider -m fuzz tests
	HYBRID_FUZZ_MODELS=2000 HYBRID_FUZZ_ALL_METHODS=1 HYBRID_INTERRUPT_MOMENTS=20 \
		$(BIN)/python -m pytest -q -s -p no:cacheprovider \
		tests/fuzz/test_fuzz_simulation.py tests/cli/test_cli_simulate_interrupts.py
	HYBRID_FUZZ=1 $(BIN)/python -m pytest -q -p no:cacheprovider \
		tests/simulation/native/test_native_property.py tests/simulation/native/test_native_spaceex.py
	HYBRID_INTERRUPT_ANYWHERE=25 $(BIN)/python -m pytest -q -p no:cacheprovider \
		tests/cli/test_cli_interrupt_anywhere.py

clean:
	rm -rf $(VENV) out .pytest_cache .mypy_cache .ruff_cache docs/_build docs/api docs/_generated

# fuzzyfire: `make test` creates .venv (torch CPU build first) when missing or stale, then runs the tests.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: install test test-fast lint bench clean experiment

install: $(STAMP)

$(STAMP): pyproject.toml
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet torch==2.13.0
	$(BIN)/python -m pip install --quiet -e ".[dev]"
	touch $(STAMP)

test: $(STAMP)
	$(BIN)/python -m pytest -q

test-fast: $(STAMP)
	$(BIN)/python -m pytest -q -m "not slow"

lint: $(STAMP)
	$(BIN)/ruff check .
	$(BIN)/ruff format --check .

bench: $(STAMP)
	@for script in bench/*.py; do echo "# $$script"; $(BIN)/python $$script || exit 1; done

# The study: make experiment [CONFIG=configs/paper.yaml] [REAL=labelled/folder] [RARE=folder] [OUT=folder]
CONFIG ?= configs/demo.yaml
experiment: $(STAMP)
	$(BIN)/fuzzyfire experiment $(CONFIG) $(if $(OUT),--out $(OUT)) \
	  $(if $(REAL),--set real.path=$(abspath $(REAL)) --set real.standin=null) \
	  $(if $(RARE),--set rare.path=$(abspath $(RARE)) --set rare.standin=null)

clean:
	rm -rf $(VENV) .pytest_cache build *.egg-info

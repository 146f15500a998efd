# fuzzyfire: `make test` creates .venv (torch CPU build first) when missing or stale, then runs the tests.
# Every package is installed at the version requirements.lock pins (`make lock` refreshes it).
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed
LOCK := requirements.lock

.PHONY: install test test-fast lint bench clean experiment lock reference

install: $(STAMP)

$(STAMP): pyproject.toml $(LOCK)
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet torch==2.13.0 -c $(LOCK)
	$(BIN)/python -m pip install --quiet -e ".[dev]" -c $(LOCK)
	$(BIN)/python -m ground.run.lock
	touch $(STAMP)

# Refresh requirements.lock: install pyproject.toml's dependencies unconstrained into a scratch venv, freeze them.
lock:
	rm -rf .lock-venv && $(PYTHON) -m venv .lock-venv
	.lock-venv/bin/python -m pip install --quiet --upgrade pip
	.lock-venv/bin/python -m pip install --quiet torch==2.13.0
	.lock-venv/bin/python -m pip install --quiet -e ".[dev]"
	head -3 $(LOCK) > $(LOCK).new
	.lock-venv/bin/python -m pip freeze --exclude-editable | sed 's/^torch==\([0-9.]*\)+cpu$$/torch==\1/' >> $(LOCK).new
	mv $(LOCK).new $(LOCK) && rm -rf .lock-venv
	@echo "wrote $(LOCK): $$(grep -c '==' $(LOCK)) packages"

test: $(STAMP)
	$(BIN)/python -m pytest -q

test-fast: $(STAMP)
	$(BIN)/python -m pytest -q -m "not slow"

lint: $(STAMP)
	$(BIN)/ruff check .
	$(BIN)/ruff format --check .

bench: $(STAMP)
	@for script in bench/*.py; do echo "# $$script"; $(BIN)/python $$script || exit 1; done

# The study: make experiment [CONFIG=...] [REAL=labelled/folder] [RARE=folder] [NEGATIVES=fire-free/photos]
#   [BROAD=fire/photos] [OUT=folder] [SET="key=value key=value"]. Without REAL: configs/demo.yaml (stand-in data,
#   offline); with REAL: configs/own-data.yaml (the recommended study of your data). NEGATIVES are your fire-free
#   photos: the false-alarm test set (the quarter its holdout picks by content hash) and, the rest, backgrounds and
#   hard negatives of the pools (the pool holds out the test set's share: one key). BROAD is a folder of fire photos without boxes (each holds fire): a test set judged per
#   image (a fire/ + normal/ layout: SET="tests.broad={path: /abs/layout}").
CONFIG ?= $(if $(REAL),configs/own-data.yaml,configs/demo.yaml)
comma := ,
experiment: $(STAMP)
	$(BIN)/fuzzyfire experiment $(CONFIG) $(if $(OUT),--out $(OUT)) \
	  $(if $(REAL),--set real.path=$(abspath $(REAL))) \
	  $(if $(RARE),--set 'rare={path: $(abspath $(RARE))}') \
	  $(if $(NEGATIVES),--set 'tests={fire-free: {path: $(abspath $(NEGATIVES))$(comma) holdout: 0.25}}' \
	    --set 'synth.method2.backgrounds=[$(abspath $(NEGATIVES))]' --set synth.method2.photo_negatives=1.0) \
	  $(if $(BROAD),--set 'tests.broad={path: $(abspath $(BROAD))$(comma) label: fire}') \
	  $(foreach s,$(SET),--set '$(s)')

# Regenerate docs/config.md and configs/synth-method*.yaml from the config dataclasses (a test checks them).
reference: $(STAMP)
	$(BIN)/python -m fuzzyfire.reference

clean:
	rm -rf $(VENV) .pytest_cache build *.egg-info

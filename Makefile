# The commands a fresh clone needs (see README):
#   make demo   — create .venv if needed, then run `gausspp demo`
#   make test   — create .venv if needed, then run the whole test suite
#   make docs   — create .venv if needed, then build the site (docs/_build/html), running every example, and open
#                 every page in a headless browser (docs/browser_check; skipped with a message without npm)
VENV ?= .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed

.PHONY: demo test bench docs

$(STAMP): pyproject.toml
	python3 -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e ".[test,plots,backends,dask,docs]"
	touch $(STAMP)

demo: $(STAMP)
	$(VENV)/bin/gausspp demo

test: $(STAMP)
	$(PY) -m pytest

bench: $(STAMP)
	$(PY) benchmarks/step.py

docs: $(STAMP)
	$(PY) -m sphinx -W --keep-going -b html docs docs/_build/html
	$(PY) docs/browser_check/run.py docs/_build/html

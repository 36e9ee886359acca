# The two commands a fresh clone needs (see README):
#   make demo   — create .venv if needed, then run `gausspp demo`
#   make test   — create .venv if needed, then run the whole test suite
VENV ?= .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed

.PHONY: demo test bench

$(STAMP): pyproject.toml
	python3 -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e ".[test,plots,backends,dask]"
	touch $(STAMP)

demo: $(STAMP)
	$(VENV)/bin/gausspp demo

test: $(STAMP)
	$(PY) -m pytest

bench: $(STAMP)
	$(PY) benchmarks/step.py

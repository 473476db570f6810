VENV ?= .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed

.PHONY: demo test lint bench clean

$(STAMP): pyproject.toml
	python3 -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e '.[test]'
	touch $(STAMP)

demo: $(STAMP)
	$(VENV)/bin/pfusion demo --view

# one BLAS/OpenMP thread per process: every service and test worker is its own process,
# and a pool sized for the host's CPUs would spin against its peers on a 2-core quota
test: lint
	OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 MKL_NUM_THREADS=1 $(PY) -m pytest -q -n 2 --dist worksteal --durations=25 tests

# ruff (pyflakes, pycodestyle, isort, bugbear) on the whole tree, mypy on common/core and
# common/wire (pyproject.toml says which rules and why)
lint: $(STAMP)
	$(VENV)/bin/ruff check .
	$(VENV)/bin/mypy

bench: $(STAMP)
	$(PY) benchmarks/core.py

clean:
	rm -rf $(VENV) out .pytest_cache

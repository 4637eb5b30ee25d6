# Set-up on a fresh machine is part of every target: a virtual environment in .venv with the
# package installed in editable mode and its test dependencies.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: run test bench clean

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip
	$(BIN)/pip install --quiet -e '.[test]'
	touch $(STAMP)

run: $(STAMP)
	$(BIN)/substruct run cases/tapered_rod.yaml --out results --force
	$(BIN)/substruct run cases/tapered_rod_table1.yaml --out results --force
	$(BIN)/substruct run cases/three_dof_frf.yaml --out results --force

# The house rules first (import layers, types), then the tests.
test: $(STAMP)
	$(BIN)/lint-imports
	$(BIN)/mypy substruct
	OMP_NUM_THREADS=1 MPLBACKEND=Agg $(BIN)/python -m pytest -q

bench: $(STAMP)
	OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 $(BIN)/python benchmarks/modes.py

clean:
	rm -rf $(VENV) results build *.egg-info

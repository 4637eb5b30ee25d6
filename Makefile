# Set-up on a fresh machine is part of every target: a virtual environment in .venv with the
# package installed in editable mode and its test dependencies.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: run test bench fast clean

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip
	$(BIN)/pip install --quiet -e '.[test]'
	touch $(STAMP)

run: $(STAMP)
	$(BIN)/substruct run cases/tapered_rod.yaml --out results --force
	$(BIN)/substruct run cases/tapered_rod_table1.yaml --out results --force
	$(BIN)/substruct run cases/three_dof_frf.yaml --out results --force
	$(BIN)/substruct run cases/frame_plate.yaml --out results --force

# The house rules first (import layers, types), then the tests.
test: $(STAMP)
	$(BIN)/lint-imports
	$(BIN)/mypy substruct
	OMP_NUM_THREADS=1 MPLBACKEND=Agg $(BIN)/python -m pytest -q

# CHOLMOD for the SPD factorizations, on an optimised BLAS: Debian's SuiteSparse headers and
# OpenBLAS (which becomes the system's libblas.so.3), as root or through sudo, then
# scikit-sparse through the [cholmod] extra, then a check that CHOLMOD's BLAS is OpenBLAS.
# Without it the factorizations are PARDISO's (x86_64) or SuperLU's.
fast: $(STAMP)
	if [ "$$(id -u)" = 0 ]; then apt-get install -y libsuitesparse-dev libopenblas-dev; \
	else sudo apt-get install -y libsuitesparse-dev libopenblas-dev; fi
	$(BIN)/pip install -e '.[test,cholmod]'
	$(BIN)/python -c "import sksparse.cholmod, threadpoolctl; \
	  blas = [i for i in threadpoolctl.threadpool_info() if i['user_api'] == 'blas' \
	          and 'site-packages' not in i['filepath']]; \
	  assert blas, 'CHOLMOD runs on the reference BLAS'; \
	  print('CHOLMOD BLAS:', *{i['internal_api'] + ' ' + i['filepath'] for i in blas})"

bench: $(STAMP)
	OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 $(BIN)/python benchmarks/modes.py

clean:
	rm -rf $(VENV) results build *.egg-info

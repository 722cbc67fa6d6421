# The README's two commands are `make run` and `make test`; both set up the
# machine first (scripts/setup.sh is idempotent: a few seconds when done).
SHELL := /bin/sh
VENV  := .venv
PY    := $(VENV)/bin/python
UPD   := $(VENV)/bin/upd
OUT   ?= results
NP    ?= 2
# pyharm-os, the benchmark-only peer of bench_hbm.py (benchmarks/pyharm_jenkins.py)
PYHARM ?= 1.2.2
MPIRUN := mpirun -n $(NP) --allow-run-as-root --oversubscribe -x OMP_NUM_THREADS=1 -x OPENBLAS_NUM_THREADS=1
export OMP_NUM_THREADS ?= 1
export OPENBLAS_NUM_THREADS ?= 1
export VTK_DEFAULT_OPENGL_WINDOW ?= vtkEGLRenderWindow
export PYVISTA_OFF_SCREEN ?= true

.PHONY: setup run test test-slow bench bench-env lint

setup:
	@sh scripts/setup.sh

## the main job: the paper's damper comparison on the paper-like rig, then on the heavy
## default rig (docs/FINDINGS.md sets them side by side); cases spread over $(NP) MPI ranks
run: setup
	$(MPIRUN) $(UPD) study studies/paper_rig.toml --out $(OUT)/paper_rig
	$(MPIRUN) $(UPD) study studies/paper.toml --out $(OUT)/paper

## the default (fast) test suite, after the lint (ruff check + format --check)
test: lint
	$(PY) -m pytest -q -n 2 --dist loadgroup

## the slow tests (run with the benchmarks)
test-slow: setup
	$(PY) -m pytest -q -m slow

## make bench: every benchmark; pyHarm (the peer of bench_hbm.py) in its own .venv-bench
## first (numpy 2 and jax: never in .venv); without it the comparison says it was not run
bench: setup
	-$(MAKE) bench-env
	$(PY) benchmarks/run_all.py --out $(OUT)/bench

bench-env: .venv-bench/.pyharm-$(PYHARM)

.venv-bench/.pyharm-$(PYHARM):
	/usr/bin/python3 -m venv .venv-bench
	.venv-bench/bin/pip install -q pyharm-os==$(PYHARM)
	touch $@

## ruff check and ruff format --check: the first step of make test (and so of CI)
lint: setup
	$(VENV)/bin/ruff check workbench tests benchmarks
	$(VENV)/bin/ruff format --check workbench tests benchmarks

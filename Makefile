# Two commands do all set-up on a fresh machine:  make demo  and  make test
PY := .venv/bin/python
MPI_ENV := OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1

.PHONY: setup demo test test-slow test-petsc-newest docs clean

setup:
	@bash scripts/setup_env.sh

# The paper's Scene 3 (its three cases) on a coarse mesh to 30 years, with Figs. 8-12 (output/demo)
demo: setup
	$(MPI_ENV) $(PY) scripts/scene3_study.py --demo

test: setup
	bash scripts/run_tests.sh

# The manual (Sphinx, MyST Markdown; warnings are errors) into build/docs
docs: setup
	$(PY) -m sphinx -W --keep-going -q -b html docs build/docs

test-slow: setup
	$(MPI_ENV) $(PY) -m pytest -q -m slow

# Build (or reuse) PETSc 3.26.1 + petsc4py from PyPI and run the suite against it too
test-petsc-newest: setup
	PETTHM_TEST_NEWEST=1 bash scripts/run_tests.sh

clean:
	rm -rf output .pytest_cache

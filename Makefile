# Two commands do all set-up on a fresh machine:  make demo  and  make test
PY := .venv/bin/python
MPI_ENV := OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1

.PHONY: setup demo test test-slow test-petsc-newest clean

setup:
	@bash scripts/setup_env.sh

demo: setup
	$(MPI_ENV) $(PY) -m petthm heat_erfc -options_file options/scenes/heat_erfc.opts

test: setup
	$(MPI_ENV) $(PY) -m pytest -q

test-slow: setup
	$(MPI_ENV) $(PY) -m pytest -q -m slow

# Build PETSc 3.26.1 + petsc4py from PyPI into .venv-petsc-3.26 and run the fast tests there
test-petsc-newest:
	bash scripts/install_petsc_pypi.sh .venv-petsc-3.26
	$(MPI_ENV) .venv-petsc-3.26/bin/python -m pytest -q

clean:
	rm -rf output .pytest_cache

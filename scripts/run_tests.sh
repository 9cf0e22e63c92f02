#!/usr/bin/env bash
# The test command of the README (make test):
#   1. the default suite with the set-up environment (.venv);
#   2. in CI (CI=true) or with PETTHM_TEST_NEWEST=1, the same suite against
#      PETSc 3.26.1 + petsc4py built from PyPI into a cached virtual
#      environment (~10 min the first time, then reused):
#      ${PETTHM_NEWEST_VENV:-$HOME/.cache/petthm/venv-petsc-3.26.1}
set -euo pipefail
cd "$(dirname "$0")/.."
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
.venv/bin/python -m pytest -q "$@"
if [ "${CI:-}" = true ] || [ "${PETTHM_TEST_NEWEST:-0}" = 1 ]; then
  venv=${PETTHM_NEWEST_VENV:-$HOME/.cache/petthm/venv-petsc-3.26.1}
  mkdir -p "$(dirname "$venv")"
  echo "== test suite against PETSc 3.26.1 (PyPI build in $venv) =="
  bash scripts/install_petsc_pypi.sh "$venv"
  "$venv/bin/python" -m pytest -q "$@"
fi

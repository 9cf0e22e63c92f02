#!/usr/bin/env bash
# Set up everything petthm needs on a fresh Debian/Ubuntu machine (idempotent).
#
# PETSc is taken, in this order, from
#   1. a petsc4py (>= 3.18) importable by $PYTHON or python3 (cluster module,
#      conda, Spack: load it before running make);
#   2. the distribution's packages (apt-get, needs root; about a minute);
#   3. a PyPI build of PETSc + petsc4py (scripts/install_petsc_pypi.sh, ~10 min).
# petthm itself is installed (editable) into the virtual environment .venv,
# which sees the system's site-packages so that a system petsc4py is used.
set -euo pipefail
cd "$(dirname "$0")/.."
VENV=.venv
APT_PACKAGES="python3-petsc4py-real python3-mpi4py python3-h5py python3-meshio python3-scipy
  python3-matplotlib python3-sympy python3-pytest python3-venv python3-pip petsc-dev openmpi-bin"

has_petsc4py() {  # $1: python executable
  "$1" - <<'PY' 2>/dev/null
import sys
import petsc4py
v = tuple(int(x) for x in petsc4py.__version__.split(".")[:2])
sys.exit(0 if v >= (3, 18) else 1)
PY
}

old_numpy() {  # $1: python executable; true for a numpy 1.x older than 1.25
  "$1" - <<'PY' 2>/dev/null
import sys
import numpy
v = tuple(int(x) for x in numpy.__version__.split(".")[:2])
sys.exit(0 if v < (1, 25) else 1)
PY
}

if [ -x "$VENV/bin/python" ] && has_petsc4py "$VENV/bin/python" && ! old_numpy "$VENV/bin/python" \
   && "$VENV/bin/python" -c "import petthm, gmsh, h5py, meshio, scipy, sympy, pytest, xdist, mpi4py, ruff, iapws, sphinx, myst_parser, pydata_sphinx_theme" 2>/dev/null; then
  exit 0
fi

start=$(date +%s)
BASE=""
for py in "${PYTHON:-}" python3 /usr/bin/python3; do
  [ -n "$py" ] && command -v "$py" >/dev/null && has_petsc4py "$py" && { BASE=$(command -v "$py"); break; }
done
if [ -z "$BASE" ] && [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null; then
  echo "petthm setup: installing PETSc and Python packages with apt-get"
  apt-get update -qq
  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq $APT_PACKAGES >/dev/null
  has_petsc4py /usr/bin/python3 && BASE=/usr/bin/python3
fi
if [ -z "$BASE" ]; then
  echo "petthm setup: no petsc4py found and no apt-get; building PETSc from PyPI (~10 min)"
  bash scripts/install_petsc_pypi.sh "$VENV"
else
  [ -x "$VENV/bin/python" ] || "$BASE" -m venv --system-site-packages "$VENV"
fi
PIP="$VENV/bin/python -m pip"
need=""
for mod in gmsh:gmsh h5py:h5py meshio:meshio scipy:scipy sympy:sympy pytest:pytest xdist:pytest-xdist mpi4py:mpi4py ruff:ruff iapws:iapws \
           sphinx:sphinx myst_parser:myst-parser pydata_sphinx_theme:pydata-sphinx-theme; do
  "$VENV/bin/python" -c "import ${mod%%:*}" 2>/dev/null || need="$need ${mod#*:}"
done
# the environment sees the system's packages (Debian's petsc4py); the manual's tools may need
# newer versions (markdown-it-py, docutils) than unrelated system packages declare (rich,
# awscli), which petthm does not use: pip is told not to warn about those
[ -z "$need" ] || $PIP install -q --no-warn-conflicts $need
# numpy 1.25+ sorts int64 with SIMD (AVX-512), which the Jacobian's pattern uses
# (petthm/discretisation/radix.py, docs/performance/index.md); within 1.x, so that the system's
# petsc4py, scipy and h5py (built against an older 1.x) keep working
if old_numpy "$VENV/bin/python"; then $PIP install -q --no-warn-conflicts "numpy>=1.25,<2"; fi
$PIP install -q --no-deps --no-build-isolation -e .
echo "petthm setup: done in $(( $(date +%s) - start )) s ($("$VENV/bin/python" -c 'from petsc4py import PETSc; print("PETSc", ".".join(map(str, PETSc.Sys.getVersion())))'))"

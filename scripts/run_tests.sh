#!/usr/bin/env bash
# The test command of the README (make test):
#   1. the linter (ruff, settings in pyproject.toml) over everything tracked;
#   2. the manual (make docs: Sphinx, warnings as errors) into build/docs;
#   3. the default suite with the set-up environment (.venv), spread over one
#      pytest-xdist worker per core (PETTHM_TEST_WORKERS: another count; 0 runs
#      the tests in this process);
#   4. in CI (CI=true) or with PETTHM_TEST_NEWEST=1, the groups of the suite
#      whose code paths differ between PETSc versions against PETSc 3.26.1 +
#      petsc4py built from PyPI into a cached virtual environment (~10 min the
#      first time, then reused): ${PETTHM_NEWEST_VENV:-$HOME/.cache/petthm/venv-petsc-3.26.1};
#      the build starts at the lowest priority beside steps 1-3.
#      They are tests/unit (compat: COO, sections, the cohesive split),
#      tests/interface (options, output, errors), tests/parallel, tests/solvers
#      and the contact, friction and Scene 3 tests; the verification of the heat, flow,
#      poroelastic and Scene 2 discretisations (the same numpy kernels and
#      LU solves on both versions) runs on the first pass only, and so does
#      the 3D Sneddon penny crack (a P2 LU solve of 2.5 min with PETSc's own
#      LU; the 2D crack covers the contact path), the SLURM chain (shell
#      stand-ins, no PETSc) and Scene 2's kill -9 restarts (the checkpoint
#      I/O is lauwerier's, tested on both passes); so do the predictor's
#      iteration counts (a Python extrapolation over Vec operations), Scene 2's
#      default path on two ranks (its block path on two ranks runs on both) and
#      Scene 3's flow-and-heat split against its control (the coupled MMS takes
#      the same recipe on both): the tests marked first_pass_only.  Both passes
#      print their slowest tests.
set -euo pipefail
cd "$(dirname "$0")/.."
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
workers=(-n "${PETTHM_TEST_WORKERS:-auto}")
newest=false
if [ "${CI:-}" = true ] || [ "${PETTHM_TEST_NEWEST:-0}" = 1 ]; then newest=true; fi
venv=${PETTHM_NEWEST_VENV:-$HOME/.cache/petthm/venv-petsc-3.26.1}
if $newest; then
  # built (or found) at the lowest priority while the first pass runs: the cycles the tests leave idle
  mkdir -p "$(dirname "$venv")"
  build_log=$(mktemp)
  # (in this session: the kernel's nice levels rank processes within a session's scheduling group)
  nice -n 19 bash scripts/install_petsc_pypi.sh "$venv" > "$build_log" 2>&1 &
  build=$!
  # a failed first pass ends the build too, with the processes it started
  stop_tree() { local child; for child in $(pgrep -P "$1"); do stop_tree "$child"; done; kill "$1" 2>/dev/null || true; }
  trap 'stop_tree "$build"' EXIT
fi
.venv/bin/python -m ruff check .
start=$(date +%s)
.venv/bin/python -m sphinx -W --keep-going -q -b html docs build/docs
echo "== the manual: $(( $(date +%s) - start )) s (build/docs/index.html) =="
start=$(date +%s)
.venv/bin/python -m pytest -q "${workers[@]}" --durations=15 "$@"
echo "== default suite: $(( $(date +%s) - start )) s =="
if $newest; then
  echo "== the PETSc-dependent groups against PETSc 3.26.1 (PyPI build in $venv) =="
  start=$(date +%s)
  if ! wait "$build"; then
    cat "$build_log"
    echo "petthm: error: the PyPI build of PETSc 3.26.1 failed (its log above)" >&2
    exit 1
  fi
  cat "$build_log"
  echo "== the build's remainder after the first pass: $(( $(date +%s) - start )) s =="
  start=$(date +%s)
  "$venv/bin/python" -m pytest -q "${workers[@]}" --durations=15 -m "not slow and not first_pass_only" \
      tests/unit tests/interface tests/parallel tests/solvers \
      tests/verification/test_contact.py tests/verification/test_friction.py tests/verification/test_scene3.py "$@"
  echo "== PETSc 3.26.1 pass: $(( $(date +%s) - start )) s =="
fi

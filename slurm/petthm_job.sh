# Shared body of petthm's SLURM job scripts (sourced by slurm/*.sbatch).
#
# petthm_job SCRIPT SCENE OPTIONS_FILE [petthm options ...]
#
# Runs SCENE with srun in $PETTHM_OUT (default output/SCENE), -log_view into
# that folder.  The job scripts ask SLURM for SIGTERM a few minutes before
# the time limit (#SBATCH --signal=TERM@300): petthm finishes its step,
# writes checkpoint.h5 and exits with code 3 ("interrupted").  This function
# then submits SCRIPT again with the same arguments, to start after this job
# ends (--dependency=afterany), with PETTHM_CONTINUE=1: the next job goes on
# with -thm_restart from the checkpoint.  The chain ends when the run
# completes (exit 0), fails (1: summary.json says why) or the input is
# refused (2).
#
# Load the site's PETSc, petsc4py, mpi4py and h5py before petthm_job runs
# (module, Spack or conda), e.g.
#   module load petsc/3.22 py-petsc4py py-mpi4py py-h5py
# or put PETTHM_SETUP="module load ..." in the environment.

petthm_job() {
    local script=$1 scene=$2 opts=$3
    shift 3
    cd "${SLURM_SUBMIT_DIR:-.}" || return 2
    if [ -n "${PETTHM_SETUP:-}" ]; then eval "$PETTHM_SETUP"; fi
    local out=${PETTHM_OUT:-output/$scene}
    local start=(-thm_output_dir "$out")
    if [ "${PETTHM_CONTINUE:-0}" = 1 ] && [ -f "$out/checkpoint.h5" ]; then
        start=(-thm_restart "$out")
    fi
    mkdir -p "$out"
    ${PETTHM_SRUN:-srun} "${PETTHM_PYTHON:-python}" -m petthm "$scene" -options_file "$opts" \
        "${start[@]}" -log_view ":$out/log_view-${SLURM_JOB_ID:-local}.txt" "$@"
    local status=$?
    if [ "$status" = 3 ]; then                    # interrupted: go on in a chained job
        sbatch ${SLURM_JOB_ID:+--dependency=afterany:$SLURM_JOB_ID} \
            --export=ALL,PETTHM_CONTINUE=1,PETTHM_OUT="$out" "$script" "${PETTHM_ARGS[@]}"
    fi
    return "$status"
}

#!/bin/bash
# Item 9's weak scaling of the Krylov count (stop 36's case): 3D Terzaghi to 5 s, mesh size 0.7,
# the column widened with the ranks (width 4 / 6.3 / 8.4 / 11.9 on 1 / 2 / 4 / 8 ranks,
# oversubscribed on 2 cores: counts only), the size rule's block path.
#   [SRC=checkout] [OUT=/tmp/s41/weak] weak.sh [extra options]
SRC=${SRC:-/work/main}; OUT=${OUT:-/tmp/s41/weak}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1 \
       OMPI_MCA_mpi_yield_when_idle=1 OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1
extra=("$@")
cd $SRC
for nw in "1 4" "2 6.3" "4 8.4" "8 11.9"; do
  set -- $nw
  d=$OUT/n$1; rm -rf $d; mkdir -p $d
  mpiexec -n $1 .venv/bin/python -m petthm terzaghi -options_file options/scenes/terzaghi.opts \
    -thm_terzaghi_dim 3 -thm_final_time 5 -thm_mesh_size 0.7 -thm_terzaghi_width $2 \
    -thm_direct_max_unknowns 0 -thm_output_dir $d "${extra[@]}" > $d/log.txt 2>&1
  python3 -c "
import json; s = json.load(open('$d/summary.json'))
print('ranks $1 width $2', s['status'], 'unknowns', sum(s['dofs'].values()), 'steps', s['steps'],
      'Newton', s['snes_iterations'], 'Krylov', s['ksp_iterations'],
      'per Newton %.1f' % (s['ksp_iterations'] / s['snes_iterations']))"
done

#!/bin/bash
# Scene 3 default mesh, P2 u, case 2: five 0.2-year steps from the start; the new default (no aggressive
# coarsening on the p-multigrid's P1 level) against PETSc's default (one level), alternated
cd /work/main
for name in ${NAMES:-new old new2 old2}; do
  x=""; case $name in old*) x="-vi_fieldsplit_mech_contact_mg_coarse_pc_gamg_square_graph 1";; esac
  d=/tmp/s43/s3/$name; rm -rf $d; mkdir -p $d
  OPENBLAS_NUM_THREADS=1 /usr/bin/time -f '%e %U %M' -o $d/time.txt .venv/bin/python -m petthm inclined_penny \
    -options_file options/scenes/inclined_penny.opts -thm_scene3_case 2 -thm_final_time 31556952 \
    -thm_dt_initial 6311390 -thm_dt_growth 1 -thm_output_dir $d -log_view :$d/log_view.txt $x > $d/out.txt 2>&1
  python3 -c "
import json; s=json.load(open('$d/summary.json')); t=open('$d/time.txt').read().split()
print('$name', s['status'], 'unknowns', sum(s['dofs'].values()), 'steps', s['steps'], 'rej', s['rejected_steps'], 'Newton', s['snes_iterations'], 'Krylov', s['ksp_iterations'], 'per Newton %.1f' % (s['ksp_iterations']/s['snes_iterations']), 'wall', t[0], 'user', t[1], 'rssMB', int(t[2])//1024)" >> /tmp/s43/s3/summary.txt
  [ "$1" = once ] && [ $name = old ] && break
done

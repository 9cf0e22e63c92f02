#!/bin/bash
# item 9 strong scaling on the landed code: Scene 2 P1 layered L4 (stop 29's case, 219 009 unknowns) to 3 640 s,
# the size rule's block path (Scene 2's recipe), 1 and 2 ranks alternated, nothing else running
cd /work/main
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1
for n in 1 2 1 2; do
  d=/tmp/s43/strong/n$n-$(date +%s); mkdir -p $d
  /usr/bin/time -f '%e %M' -o $d/time.txt mpiexec -n $n .venv/bin/python -m petthm penny_impermeable \
    -options_file options/scenes/penny_impermeable.opts -thm_scene2_layer 2 -thm_scene2_layer_growth 2.5 \
    -thm_scene2_fracture_size 2.5 -thm_scene2_well_size 1.25 -thm_mesh_size 18.75 -thm_final_time 3640 \
    -thm_output_dir $d > $d/out.txt 2>&1
  python3 -c "
import json; s=json.load(open('$d/summary.json')); t=open('$d/time.txt').read().split()
print('ranks $n', s['status'], 'unknowns', sum(s['dofs'].values()), 'steps', s['steps'], 'Newton', s['snes_iterations'], 'Krylov', s['ksp_iterations'], 'wall', t[0], 'wall_time', {k: round(v,1) for k,v in s['wall_time'].items()}, 'peak MB per rank', round(s['peak_memory_mb']['max_rank']))" >> /tmp/s43/strong/summary.txt
done

#!/bin/bash
# stop 42: BoomerAMG without aggressive coarsening and the contact-Schur term off, level 3 window
cd "$(dirname "$0")"
G=-vi_fieldsplit_mech_contact_
LEV=L3 ./winlev.sh nl0_off ${G}pc_hypre_boomeramg_agg_nl 0 -vi_contact_schur off
LEV=L3 ./winlev.sh nl0_off_cg8 ${G}pc_hypre_boomeramg_agg_nl 0 ${G}ksp_max_it 8 -vi_contact_schur off

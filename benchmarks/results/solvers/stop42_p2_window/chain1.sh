#!/bin/bash
# stop 42, the level-3 window's variants, one after the other (beside the P2 default run)
cd "$(dirname "$0")"
G=-vi_fieldsplit_mech_contact_
C=${G}mg_coarse_
AMG="${C}pc_type hypre ${C}pc_hypre_type boomeramg ${C}pc_hypre_boomeramg_strong_threshold 0.8 ${C}pc_hypre_boomeramg_coarsen_type HMIS ${C}pc_hypre_boomeramg_interp_type ext+i ${C}pc_hypre_boomeramg_P_max 4 ${C}pc_hypre_boomeramg_agg_nl 1 ${C}pc_hypre_boomeramg_relax_type_down SOR/Jacobi ${C}pc_hypre_boomeramg_relax_type_up backward-SOR/Jacobi"
./win.sh sym -vi_pc_fieldsplit_type symmetric_multiplicative
./win.sh amg_th05 ${G}pc_hypre_boomeramg_strong_threshold 0.5
./win.sh amg_nl0 ${G}pc_hypre_boomeramg_agg_nl 0
./win.sh amg_sweeps2 ${G}pc_hypre_boomeramg_grid_sweeps_down 2 ${G}pc_hypre_boomeramg_grid_sweeps_up 2
./win.sh pmg_amg ${G}pmg 1 ${G}pc_type mg $AMG
./win.sh pmg_amg_sor ${G}pmg 1 ${G}pc_type mg $AMG ${G}mg_levels_pc_type sor

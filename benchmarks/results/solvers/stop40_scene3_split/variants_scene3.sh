cd /tmp/s10/s3
M=-vi_fieldsplit_mech_contact_
BA="${M}pc_type hypre ${M}pc_hypre_type boomeramg ${M}pc_hypre_boomeramg_strong_threshold 0.8 ${M}pc_hypre_boomeramg_coarsen_type HMIS ${M}pc_hypre_boomeramg_interp_type ext+i ${M}pc_hypre_boomeramg_P_max 4 ${M}pc_hypre_boomeramg_agg_nl 1 ${M}pc_hypre_boomeramg_relax_type_down SOR/Jacobi ${M}pc_hypre_boomeramg_relax_type_up backward-SOR/Jacobi"
CG="${M}ksp_type cg ${M}ksp_max_it 4 ${M}ksp_norm_type none"
FH(){ echo "-vi_fieldsplit_$1_ksp_type gmres -vi_fieldsplit_$1_ksp_rtol 1e-3 -vi_fieldsplit_$1_ksp_max_it 200 -vi_fieldsplit_$1_pc_type bjacobi -vi_fieldsplit_$1_sub_pc_type ilu"; }
bash win3.sh base
bash win3.sh A_s2 -vi_groups mech=u+lam+tau,pm=pm,flow_heat=pf+Tf+Tm $CG $BA $(FH flow_heat)
bash win3.sh B_rest -vi_groups mech=u+lam+tau,rest=pm+pf+Tf+Tm $CG $BA $(FH rest)
bash win3.sh C_heat1 -vi_groups flow_heat=pf+Tf+Tm,mech=u+lam+tau,pm=pm $CG $BA $(FH flow_heat)
bash win3.sh D_restheat1 -vi_groups rest=pm+pf+Tf+Tm,mech=u+lam+tau $CG $BA $(FH rest)

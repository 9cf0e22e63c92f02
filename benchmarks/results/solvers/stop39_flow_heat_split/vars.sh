P=-vi_fieldsplit_mech_contact_pc_hypre_boomeramg_
A="${P}agg_nl 1 ${P}relax_type_down SOR/Jacobi ${P}relax_type_up backward-SOR/Jacobi"
G="-vi_groups mech=u+lam+tau,pm=pm,rest=pf+Tf+Tm"
C=-vi_fieldsplit_mech_contact_ksp_
R=-vi_fieldsplit_rest_
CG4="${C}type cg ${C}max_it 4 ${C}rtol 1e-12 ${C}norm_type none"
RI="${R}ksp_type gmres ${R}ksp_rtol 1e-3 ${R}pc_type ilu"
NEW="$A $G $CG4 $RI"

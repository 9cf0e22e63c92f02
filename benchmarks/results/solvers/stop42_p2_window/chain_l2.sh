#!/bin/bash
# stop 42: level 2's window (after base.sh), the variants of levels 1 and 3
cd "$(dirname "$0")"
G=-vi_fieldsplit_mech_contact_
export LEV=L2
./winlev.sh recipe
./winlev.sh schur_off -vi_contact_schur off
./winlev.sh cg8_schur_off ${G}ksp_max_it 8 -vi_contact_schur off
./winlev.sh cg16 ${G}ksp_max_it 16
./winlev.sh cg16_schur_off ${G}ksp_max_it 16 -vi_contact_schur off

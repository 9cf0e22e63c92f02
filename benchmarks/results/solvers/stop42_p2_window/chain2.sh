#!/bin/bash
# stop 42: the contact-Schur term of the flow and heat split on level 3's window
cd "$(dirname "$0")"
G=-vi_fieldsplit_mech_contact_
LEV=L3 ./winlev.sh schur_off -vi_contact_schur off
LEV=L3 ./winlev.sh cg16_schur_off ${G}ksp_max_it 16 -vi_contact_schur off

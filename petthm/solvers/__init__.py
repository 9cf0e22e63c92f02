"""The solver layer: the time stepper around PETSc's TS, SNES and KSP
(``timestepper``) and its schedule (``stepcontrol``, ``courant``,
``predictor``), the SNES hooks (``snes_hooks``, ``viconvergence``), the
field splits and the block preconditioner (``fieldsplit``, ``sweep``,
``recipes``), and the preconditioners of the contact and of P2
displacement (``contactpc``, ``glue``, ``nodeblocks``, ``pmg``).

May import: the physics, verification, discretisation and mesh layers and
the base modules."""

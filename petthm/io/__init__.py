"""The files of a run: history, summary and XDMF/HDF5 fields (``output``),
the checkpoint and the stop requests (``checkpoint``), and the output
folder with its lock and manifest (``rundir``).

May import: the solver, physics, discretisation and mesh layers and the
base modules."""

"""The run driver: the lifecycle of a run (``driver``: options, mesh,
set-up, time loop, output, status), what happens after every step
(``stepreport``), what a restart continues (``continuation``) and what
summary.json records besides the results (``provenance``).

May import: every layer below (scenes, io, solvers, physics,
verification, discretisation, mesh, base)."""

"""The mesh layer: gmsh geometry and meshing (``generate``, ``layered``),
the DMPlex of a mesh file with its boundary labels and vectorised topology
(``plex``, ``topology``), the reference simplices (``reference``), the
cohesive split along fractures and the fracture surface (``fracture``),
and the partition that keeps cohesive cells with their rock cells
(``partition``).

May import: the base modules (``petthm.errors``, ``petthm.compat``,
``petthm.params``).  Nothing here knows fields, physics or solvers."""

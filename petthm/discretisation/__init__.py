"""The discretisation layer: Lagrange elements and quadrature (``fe``),
fields and their sections (``fields``), Dirichlet conditions and ties
(``constraints``), the registration tables of kernels (``model``), the
vectorised assembly with its Jacobian pattern (``assembly``, ``context``,
``sparsity``, ``simplexpairs``, ``p1blocks``, ``radix``), integrals and
error norms of a solution (``functionals``), the transient
problem (``problem``: state, residual and Jacobian callbacks, scaling)
and MPI-safe probes of its fields (``probes``).

May import: the mesh layer and the base modules.  No physics: kernels are
registered from above."""

"""Reference solutions and self-checks, beside the physics layer:
analytical solutions (``analytic``), the manufactured solution of the
coupled system (``manufactured``) and the finite-difference check of a
problem's Jacobian (``jacobian``).

May import: the physics, discretisation and mesh layers and the base modules."""

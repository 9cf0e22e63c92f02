"""The physics layer: the physical parameters (``materials``), fluid
properties (``fluid``), the pointwise kernels (``kernels``), the model
builders that compose them (``builders``), wells in the rock
(``matrixwells``), mass and energy balances (``balance``) and the monitors
the scenes share (``monitors``).

May import: the discretisation and mesh layers and the base modules."""

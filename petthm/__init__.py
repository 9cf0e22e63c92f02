"""petthm: PETSc-based thermo-hydro-mechanics of fractured geothermal reservoirs."""
__version__ = "0.1.0"

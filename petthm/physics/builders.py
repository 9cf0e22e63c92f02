"""Model builders: the coupled physics of the theory manual composed into a ``Model``.

A scene creates a ``ModelBuilder`` with its parameters and calls the
builders of the physics it has, in any order; each builder adds its fields
and terms and keeps the kernel objects that later builders couple to:

=====================  =======================================  ===========
builder                physics (the theory manual)             fields
=====================  =======================================  ===========
``elasticity``         thermo-poro-elastic rock (2), Biot (5)    u
``matrix_flow``        Darcy flow with storage (5)              pm
``matrix_heat``        advection-conduction in the rock (6)      Tm
``contact``            face loads, frictionless contact (2, 3)   lam
``deformable``         a = ac(lam) + max(g, 0) (3)               -
``fracture_flow``      cubic law with storage, da/dt (4)         pf
``leakoff``            pm = pf on the walls (5)                  -
``fracture_heat``      fracture heat, wall exchange (7)          Tf
``wells``              point wells, on a fracture or along a     -
                       matrix well's interval (9)
=====================  =======================================  ===========

``build()`` then adds the terms that couple two of them once both exist
(today the thermo-mechanical heating of section 6, when
``-thm_thermomechanical_heating`` is on and the model has u and Tm) and
orders the fields canonically (u, lam, pf, pm, Tf, Tm).  Adding a coupled
term is one kernel (``petthm/physics/kernels``) and one builder here.
"""
from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import replace

import numpy as np

from petthm.discretisation.fields import FieldSpec
from petthm.discretisation.model import (
    FRACTURE,
    FRACTURE_DUAL,
    Domain,
    Heating,
    Model,
    NodeOutputs,
    PointTerm,
    Range,
    traces,
)
from petthm.errors import InputError
from petthm.params import CELSIUS
from petthm.physics.kernels import contact as ct
from petthm.physics.kernels import exchange as xk
from petthm.physics.kernels import flow as fk
from petthm.physics.kernels import friction as fr
from petthm.physics.kernels import heat as hk
from petthm.physics.kernels import poroelastic as pe
from petthm.physics.kernels.regional import Regional, per_region
from petthm.physics.kernels.wallflux import WallConduction
from petthm.physics.materials import NUSSELT
from petthm.physics.monitors import contact_outputs

#: canonical order of the fields (the order of the unknowns in the section)
FIELD_ORDER = ("u", "lam", "tau", "pf", "pm", "Tf", "Tm")

#: shift of the contact function relative to the displacement scale (kernels/contact.py)
GAP_TOLERANCE = 1e-12


#: rock layers thinner than this fraction of the fracture's cells: the SUPG wall term over/undershoots
THIN_WALL_LAYER = 0.05


def thin_wall_layers(mesh) -> str | None:
    """-thm_fracture_supg_wall_conduction on a mesh whose rock cells next to
    the fracture are much thinner than its cells: a warning (measured: Tf
    left [Tinj, T0] by 0.1-1.3 % at ratios 0.005-0.02 in Scene 1 and by 6 %
    at 0.025 in Scene 2, 0 % at 0.05; manual: verification, fracture flow
    and heat); None on a mesh without such layers (collective)."""
    ratio = mesh.fracture.thinnest_wall_layer() if mesh.fracture is not None else float("inf")
    if ratio >= THIN_WALL_LAYER:
        return None
    return (f"-thm_fracture_supg_wall_conduction on rock layers {ratio:.3g} times as thick as the "
            f"fracture's cells (< {THIN_WALL_LAYER:g}): Tf left [Tinj, T0] by up to 6 % on meshes with such "
            "layers; check bounds.Tf in summary.json")


#: temperatures are kelvin inside and degrees Celsius in every output
TEMPERATURE = {"unit": "K", "output_unit": "degC", "output_offset": -CELSIUS}


#: the heat transport schemes whose stored energy counts the water's content (kernels/transport.py)
WATER_ENERGY_SCHEMES = ("upwind", "limited")


def heat_scheme(p, degree: int, supg: bool = True) -> str:
    """The discretisation of a run's heat advection of temperatures of
    ``degree`` (``-thm_heat_transport``; ``auto``: the bound-preserving
    limited scheme for P1, SUPG for P2, which has no bound-preserving scheme;
    theory manual, discrete bounds); galerkin where the scene asks for no
    stabilisation, ``supg=False``."""
    if not supg:
        return "galerkin"
    scheme = getattr(p, "heat_transport", "auto")
    if scheme == "auto":
        return "limited" if degree == 1 else "supg"
    return scheme


def each_fracture(value, f: Callable):
    """``f(value)``; for a ``Regional`` (one value per fracture), ``f`` of each (``per_region``)."""
    if isinstance(value, Regional):
        return per_region(f(v) for v in value.values)
    return f(value)


class ModelBuilder:
    """Composes a ``Model`` from the builders below (see the module docstring).

    ``p``: the scene's ``materials.Parameters``; ``dim``: the mesh dimension;
    ``regions``: the parameters of each rock region (a heterogeneous rock,
    in the order of the model's ``cell_regions``; default: ``p`` alone).
    The kernel objects made so far are public attributes: ``elastic``,
    ``mechanics``, ``aperture``, ``flows`` and ``heats`` ({Domain: object})."""

    def __init__(self, p, dim: int, regions: tuple = ()):
        self.p, self.dim = p, dim
        self.regions = tuple(regions) or (p,)
        self.model = Model()
        self.elastic: pe.Elastic | None = None
        self.mechanics: ct.FractureMechanics | None = None
        self.aperture: ct.Aperture | None = None
        self.frictional: fr.Friction | None = None
        self.flows: dict = {}
        self.heats: dict = {}

    # -- rock ---------------------------------------------------------------------------
    def rock(self, value: Callable):
        """A rock coefficient, ``value(parameters)``: a number (or array) where
        every region has the same, else one per region (kernels/regional.py)."""
        return per_region(value(q) for q in self.regions)

    def elasticity(self, degree: int, *, biot: bool = False, thermal: bool = False,
                   body_force: tuple = (), p_ref=None, T_ref=None) -> pe.Elastic:
        """u with drained elasticity (E, nu), the Biot coupling to pm
        (alpha, p0 when the scene has -thm_initial_pressure) and the thermal
        strain of Tm (beta_s, T0); ``p_ref``, ``T_ref`` (K): the in-situ
        pressure and temperature where they are not those numbers (functions
        of position, ``poroelastic.at_points``)."""
        p = self.p
        kw = {}
        if biot:           # sigma carries alpha (pm - p0): u is the displacement from the in-situ state
            kw.update(p="pm", biot=self.rock(lambda q: q.rock_biot_coefficient),
                      p_ref=getattr(p, "initial_pressure", 0.0) if p_ref is None else p_ref)
        if thermal:
            kw.update(T="Tm", thermal_expansion=self.rock(lambda q: q.rock_thermal_expansion),
                      T_ref=p.T0 if T_ref is None else T_ref)
        self.elastic = pe.Elastic(self.rock(lambda q: q.rock_youngs_modulus),
                                  self.rock(lambda q: q.rock_poisson_ratio), self.dim,
                                  body_force=body_force, **kw)
        self.model.add_field(FieldSpec("u", self.dim, degree, unit="m"))
        self.model.add(pe.elastic_terms(self.elastic))
        return self.elastic

    def matrix_flow(self, degree: int, *, permeability, storage,
                    thermal_storage=0.0, heat: bool = False,
                    source: Callable | None = None, gravity: tuple = (),
                    reference_pressure: float | None = None,
                    reference_temperature: float | None = None) -> fk.Flow:
        """pm: S dp/dt - B dT/dt + div(-k/mu (grad p - rho_f g)) = s (with
        ``heat``: mu(Tm), B; ``source`` s(x, t), 1/s: the manufactured
        solutions; ``gravity``: the vector rho_f g, N/m3); the permeability
        and storages numbers or ``Regional`` (``rock``).  The reference
        state of the stored water: -thm_initial_pressure and T0 unless given."""
        p = self.p
        p0 = getattr(p, "initial_pressure", 0.0) if reference_pressure is None else reference_pressure
        T0 = (p.T0 if reference_temperature is None else reference_temperature) if heat else 0.0
        fl = fk.Flow(Domain.MATRIX, "pm", "Tm" if heat else None, storage, permeability,
                     p.fluid_viscosity,
                     thermal_storage if heat else 0.0, source=source,
                     reference_pressure=p0, reference_temperature=T0, gravity=tuple(gravity))
        self.model.add_field(FieldSpec("pm", 1, degree, unit="Pa"))
        self.model.add(fk.flow_terms(fl))
        self.flows[Domain.MATRIX] = fl
        return fl

    def biot_stabilisation(self, factor: float) -> None:
        """The pressure stabilisation of the Biot flow equation (kernels/poroelastic.py)."""
        self.model.add(pe.pressure_stabilisation_terms(self.elastic, "pm", factor))

    def matrix_heat(self, degree: int, *, capacity: float | None = None, conductivity=None,
                    lumped: bool = False, velocity=None, source: Callable | None = None,
                    supg: bool = True, reference_temperature: float = 0.0) -> hk.Heat:
        """Tm in conservative form (kernels/heat.py), advected by the
        matrix flow if there is one, or by a prescribed ``velocity``; the
        capacity and conductivity of the porous rock (``Parameters.rho_c``,
        ``conductivity``) unless given (a rock without pores)."""
        p = self.p
        advect = Domain.MATRIX in self.flows or velocity is not None
        C = self.rock(lambda q: q.rho_c) if capacity is None else capacity
        L = self.rock(lambda q: q.conductivity) if conductivity is None else conductivity
        el = self.elastic
        flow = self.flows.get(Domain.MATRIX)
        biot = (el.u, el.biot) if el is not None and flow is not None and el.p == flow.p and el.biot else ()
        h = hk.Heat(Domain.MATRIX, "Tm", C, L,
                    p.fluid_rho_c if advect else 0.0, flow, velocity=velocity,
                    source=source, reference_temperature=reference_temperature, degree=degree,
                    biot=biot, **self._transport(degree, advect, supg, lumped))
        self.model.add_field(FieldSpec("Tm", 1, degree, **TEMPERATURE))
        self.model.add(hk.heat_terms(h))
        self.heats[Domain.MATRIX] = h
        return h

    # -- fracture mechanics ----------------------------------------------------------------
    def contact(self, *, normal_stress: float, u_scale: float, pressure: Callable | None = None,
                insitu_stress: np.ndarray | None = None) -> ct.FractureMechanics:
        """lam >= 0 with the face loads pf + lam + sigma0_nn on u+-
        (kernels/contact.py); the fluid pressure is the field pf (when the
        model has fracture flow) or a prescribed ``pressure(x, t)``.
        ``normal_stress``: the in-situ compressive stress on the fracture;
        ``u_scale``: the displacement scale (the VI's gap tolerance).  lam
        has the degree of u, paired in the dual basis
        (``-thm_contact_pairing dual``), or is P1 with the consistent
        pairing (``consistent``).  ``insitu_stress``: the in-situ stress
        tensor (tension positive) whose shear on each face the friction
        carries in the in-situ state (needs friction); ``normal_stress`` is
        then its compressive normal stress on the fracture."""
        dual = self.p.contact_pairing == "dual"
        self.mechanics = ct.FractureMechanics(self.dim, pf=None if pressure else "pf", pressure=pressure,
                                              insitu_normal_stress=-normal_stress,
                                              insitu_stress=() if insitu_stress is None else
                                              tuple(np.ravel(insitu_stress)),
                                              gap_tolerance=GAP_TOLERANCE * u_scale,
                                              pairing=FRACTURE_DUAL if dual else FRACTURE)
        degree = self.model.spec("u").degree if dual else 1
        self.model.add_field(FieldSpec("lam", 1, degree, Domain.FRACTURE, unit="Pa"))
        self.model.add(ct.fracture_mechanics_terms(self.mechanics))
        self.model.bounds["lam"] = (0.0, None)
        self.model.outputs.append(NodeOutputs(Domain.FRACTURE, "lam", contact_outputs))
        if self.elastic is not None:
            self.model.recovered_traction = ct.RecoveredTraction(self.mechanics, self.elastic)
        if self.p.fracture_friction > 0 or self.p.fracture_cohesion > 0:
            self.friction(degree, dual)
        return self.mechanics

    def friction(self, degree: int, dual: bool) -> fr.Friction:
        """The tangential traction tau (d - 1 components) with Coulomb's law
        (kernels/friction.py); needs the dual pairing."""
        if not dual:
            raise InputError("option -thm_fracture_friction > 0 needs -thm_contact_pairing dual")
        p = self.p
        self.frictional = fr.Friction(self.mechanics, p.fracture_friction, p.fracture_cohesion,
                                      p.rock_youngs_modulus)
        self.model.add_field(FieldSpec("tau", self.dim - 1, degree, Domain.FRACTURE, unit="Pa"))
        self.model.friction_law = self.frictional
        self.model.add(fr.friction_terms(self.frictional))
        return self.frictional

    def joint_law(self) -> ct.JointLaw:
        p = self.p
        return ct.JointLaw(p.fracture_aperture, p.fracture_normal_stiffness,
                           p.fracture_residual_fraction * p.fracture_aperture)

    def deformable(self, mechanics: ct.FractureMechanics) -> ct.Aperture:
        """The aperture a(lam, g) that fracture flow and heat use."""
        self.aperture = ct.Aperture(mechanics, self.joint_law())
        self.model.aperture_law = self.aperture.law
        return self.aperture

    # -- fracture flow and heat -------------------------------------------------------------
    def fracture_flow(self, degree: int, *, reference_aperture, heat: bool = False,
                      compressibility: float | None = None, source: Callable | None = None,
                      gravity: tuple = ()) -> fk.Flow:
        """pf: cubic-law flow on the fracture with storage a c_f (- a beta_f dTf/dt
        with ``heat``), mu(Tf); per unit aperture on a deformable fracture.
        ``reference_aperture``: a number, or a ``Regional`` of one aperture
        per fracture (the model's ``fracture_regions``); ``gravity``: the
        vector rho_f g (N/m3), whose part along the fracture drives its flow."""
        p = self.p
        a = reference_aperture if self.aperture is None else 1.0
        cf = p.fluid_compressibility if compressibility is None else compressibility
        beta = each_fracture(a, lambda a: a * p.fluid_thermal_expansion) if heat else 0.0
        fl = fk.Flow(Domain.FRACTURE, "pf", "Tf" if heat else None, each_fracture(a, lambda a: a * cf),
                     each_fracture(a, lambda a: a ** 3 / 12 * np.eye(self.dim)),
                     p.fluid_viscosity, beta, aperture=self.aperture, source=source, gravity=tuple(gravity),
                     reference_pressure=getattr(p, "initial_pressure", 0.0),
                     reference_temperature=p.T0 if heat else 0.0)
        self.model.add_field(FieldSpec("pf", 1, degree, Domain.FRACTURE, unit="Pa"))
        self.model.add(fk.flow_terms(fl))
        self.flows[Domain.FRACTURE] = fl
        return fl

    def leakoff(self) -> None:
        """Leakoff: the matrix pressure on the walls is the fracture pressure
        (a tie, manual, verification: fracture flow and heat), so the Darcy flux through the walls is L."""
        self.model.ties["pm"] = "pf"

    def fracture_heat(self, degree: int, *, reference_aperture: float, lumped: bool = False,
                      supg: bool = True, source: Callable | None = None) -> hk.Heat:
        """Tf: advection-conduction in the fracture and the wall exchange
        with the rock (``-thm_fracture_heat_exchange``): equilibrium ties the
        wall nodes of Tm to Tf; otherwise hw (Tf - Tm) on both faces, with
        hw = Nu lambda_f / (2 a) at the local aperture of a deformable fracture.
        ``source``: a heat source per unit fracture area s(x, t) (W/m2; the
        manufactured solutions)."""
        p = self.p
        a = reference_aperture if self.aperture is None else 1.0
        ex = p.fracture_heat_exchange
        hw = None if ex.mode == "equilibrium" else \
            each_fracture(reference_aperture, lambda a: ex.coefficient(a, p.fluid_conductivity))
        if hw is not None and self.aperture is not None and ex.mode == "nusselt":
            hw = xk.ApertureExchange(NUSSELT * p.fluid_conductivity / 2, self.aperture)
        if hw is None:
            self.model.ties["Tm"] = "Tf"
        else:
            if Domain.MATRIX in self.flows:
                raise InputError("option -thm_fracture_heat_exchange: only 'equilibrium' is implemented "
                                 "with a permeable matrix (the heat carried by leakoff needs the wall flux)")
            self.model.add(xk.exchange_terms("Tf", traces("Tm"), hw, lumped=lumped))
        h = hk.Heat(Domain.FRACTURE, "Tf", each_fracture(a, lambda a: a * p.fluid_rho_c),
                    each_fracture(a, lambda a: a * p.fluid_conductivity), p.fluid_rho_c,
                    self.flows[Domain.FRACTURE], degree=degree, aperture=self.aperture,
                    source=source, **self._transport(degree, True, supg, False))
        self.model.add_field(FieldSpec("Tf", 1, degree, Domain.FRACTURE, **TEMPERATURE))
        if hw is not None:
            self.model.add(hk.heat_terms(h))
        self.heats[Domain.FRACTURE] = h          # tied: its terms in build(), with the rock's wall flux
        return h

    def _transport(self, degree: int, advect: bool, supg: bool, lumped: bool) -> dict:
        """The heat advection's discretisation (``-thm_heat_transport``; a
        scene that passes ``supg=False`` asks for Galerkin): SUPG, or
        algebraic upwinding (kernels/transport.py), flux-corrected with
        ``limited`` (kernels/limiter.py), with the capacity lumped
        (with or without advection: a consistent capacity over- and
        undershoots next to a sudden change of the wall temperature)."""
        scheme = heat_scheme(self.p, degree, supg)
        if scheme in WATER_ENERGY_SCHEMES and degree != 1:
            raise InputError(f"option -thm_heat_transport {scheme}: P1 temperatures only (this run has "
                             f"P{degree}: -thm_fe_degree 1, or -thm_heat_transport supg)")
        if scheme in WATER_ENERGY_SCHEMES:
            limited = advect and scheme == "limited"
            settle = {"settle": self.p.heat_limiter_settle} if limited else {}
            return {"supg": False, "lumped": True, "upwind": advect, "limited": limited, **settle}
        return {"supg": scheme == "supg", "lumped": lumped}

    def wells(self, terms: list[PointTerm]) -> None:
        self.model.points.extend(terms)

    def _tied_fracture_heat(self) -> None:
        """The terms of the fracture heat tied to the rock (equilibrium exchange);
        with -thm_fracture_supg_wall_conduction its SUPG residual carries the
        rock's wall conduction (kernels/wallflux.py)."""
        h = self.heats[Domain.FRACTURE]
        rock = self.heats.get(Domain.MATRIX)
        if self.p.fracture_supg_wall_conduction and h.upwind:
            raise InputError("option -thm_fracture_supg_wall_conduction: a term of the SUPG residual; this "
                             "run's heat transport has none (-thm_heat_transport supg, or leave it out)")
        if rock is not None and h.supg and h.advects and self.p.fracture_supg_wall_conduction:
            h = replace(h, wall=WallConduction(rock.T, rock.conductivity))
            self.heats[Domain.FRACTURE] = h
            self.model.mesh_checks.append(thin_wall_layers)
        self.model.add(hk.heat_terms(h))

    # -- the model ------------------------------------------------------------------------
    def build(self) -> Model:
        """The model, with the couplings of pairs of builders added and the
        fields in the canonical order."""
        m = self.model
        if m.ties.get("Tm") == "Tf":
            self._tied_fracture_heat()
        # a scene whose model has u and Tm declares -thm_thermomechanical_heating
        if self.elastic is not None and m.has("Tm") and self.p.thermomechanical_heating:
            porous = m.has("pm")
            phi_beta = self.rock(lambda q: q.rock_porosity * q.fluid_thermal_expansion) if porous else 0.0
            pm = "pm" if porous else None
            m.add(pe.heating_terms(self.elastic, "Tm", pm, phi_beta))
            m.heating = Heating(self.elastic.region, pe.heating_power(self.elastic, "Tm", pm, phi_beta),
                                self.heats[Domain.MATRIX].capacity)
        # what a block preconditioner adds to the pressure block (not the Jacobian)
        if self.elastic is not None and self.elastic.p is not None and m.has(self.elastic.p):
            m.preconditioner += pe.fixed_stress_terms(self.elastic, self.elastic.p)
        m.fields.sort(key=lambda f: FIELD_ORDER.index(f.name))
        for name, r in self.temperature_ranges().items():
            m.ranges.setdefault(name, r)
        return m

    def temperature_ranges(self) -> dict[str, Range]:
        """Each temperature field's range: between the lowest and the highest
        temperature the scene gives (initial, injection, boundary; theory
        manual, "Discrete bounds"), where no heat source acts; a field with a
        source (the manufactured solutions) has its range reported without
        bounds."""
        given = [getattr(self.p, f.name) + CELSIUS for f in dataclasses.fields(self.p)
                 if f.metadata.get("unit") == "degC" and isinstance(getattr(self.p, f.name), (int, float))]
        out = {}
        for h in self.heats.values():
            if h.source is not None or not given:
                out[h.T] = Range()
            else:
                out[h.T] = Range(min(given), max(given))
        return out

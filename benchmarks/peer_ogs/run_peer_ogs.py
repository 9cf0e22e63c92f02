#!/usr/bin/env python3
"""Peer benchmark (issue 16, item 5): petthm against OpenGeoSys 6.5.9 on the
Lauwerier case, error against wall time, both codes in the same invocation.

    python benchmarks/peer_ogs/run_peer_ogs.py [--out output/peer_ogs]
        [--ogs-levels 1,2,3] [--petthm-levels 0,1,2] [--repeat 1]
        [--petthm-root .] [--venv ~/.cache/petthm/venv-ogs] [--work DIR]

The case is petthm's ``lauwerier`` scene (2D, H = 1 m): a fracture along
y = W from the injector at x = 0 to the producer at x = L = 100 m, aperture
b = 1 mm, rate Q = 1e-4 m^2/s, impermeable rock (lambda 2.88 W/m/K, rho 2820,
c 1170), water (1000 kg/m3, 4200 J/kg/K) injected at 20 degC into rock at
100 degC, rock W = max(60 m, 4 sqrt(kappa t_end)) on each side, held at
100 degC on its far sides.  The score is max |T_out - T_Lauwerier| over
1e4 s <= t <= t_end (K), with petthm.verification.analytic.lauwerier_temperature for both
codes, computed here from each run's outlet history.

OpenGeoSys: the PyPI wheel ``ogs==6.5.9`` is installed into its own virtual
environment (``--venv``; a wheel in /tmp/ogs_dl/ is used when present).  The
script writes the case itself: a structured quadrilateral mesh whose rows are
layered away from the fracture (first layer h0, growing by a ratio), the
fracture as 1D line elements on the shared row of nodes (MaterialIDs 1, the
rock 0), point meshes for the injector and producer and a line mesh for the
far sides (all ASCII VTU with bulk_node_ids), and the .prj of the HT process
(monolithic T-p, aperture_size from a cell field: b on the fracture, 1 in the
rock, so the 1D elements carry transmissivity b^3/12/mu and heat capacity
b rho_f c_f), Picard iterations, Eigen SparseLU, backward Euler with the same
step schedule as the petthm run of the same level.  Injection: a nodal source
Q on the pressure and T = 20 degC at the injector node; producer: p = 0;
outlet temperature: T at the producer node, written every step (output of
the producer point mesh only).

Runs go one at a time, alternating OGS and petthm level by level so that the
machine's load hits both alike; the wall time of each is that of its whole
process (start-up, mesh reading/generation, output included).
"""
from __future__ import annotations

import argparse
import csv
import glob
import json
import math
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]

# ---------------------------------------------------------------- the case
L, B, Q = 100.0, 1e-3, 1e-4                       # m, m, m^2/s (per metre of height)
LAM_S, RHO_S, C_S = 2.88, 2820.0, 1170.0          # rock
RHO_F, C_F, LAM_F, MU = 1000.0, 4200.0, 0.6, 1e-3  # water (petthm's defaults)
T0, TI = 100.0, 20.0                               # degC
T_SCORE = 1e4                                      # the error is scored from this time on (s)
DT0 = 100.0                                        # first step (s) of every schedule

#: time-step schedules shared by both codes (growth per step, largest step s)
SCHEDULES = {0: (1.10, 2e7), 1: (1.07, 1e7), 2: (1.05, 5e6), 3: (1.03, 2.5e6),
             4: (1.3, 5e7), 5: (1.2, 2e7)}           # 4, 5: petthm's BDF2 cases only
#: OGS levels: (element size along the fracture m, first layer h0 m, layer growth, schedule)
OGS_LEVELS = {1: (4.0, 0.2, 1.5, 0), 2: (2.0, 0.1, 1.3, 1), 3: (1.0, 0.05, 1.2, 2),
              4: (0.5, 0.05, 1.1, 3)}
#: petthm levels (P2, graded mesh): (fracture mesh size m, far mesh size m, schedule)
PETTHM_LEVELS = {0: (4.0, 20.0, 0), 1: (2.0, 15.0, 1), 2: (1.0, 10.0, 2), 3: (0.5, 10.0, 3)}
#: petthm's layered-mesh variant (-thm_lauwerier_layer), levels as above with "l" prefixed
PETTHM_LAYER, PETTHM_LAYER_GROWTH = 0.05, 1.5
#: petthm with OGS's wall layers ("w" prefixed): (fracture mesh size m, far mesh size m,
#: first layer m, layer growth, schedule); w0 has OGS R1's wall layer and schedule
PETTHM_WALL_LEVELS = {0: (3.0, 30.0, 0.2, 1.6, 0), 1: (2.0, 30.0, 0.1, 1.5, 1)}
#: petthm with OGS's wall layers and PETSc's BDF2 (-ts_type bdf -ts_bdf_order 2: second order in
#: time, so fewer, longer steps; "b" prefixed): as PETTHM_WALL_LEVELS
PETTHM_BDF2_LEVELS = {0: (4.0, 30.0, 0.3, 1.6, 4), 1: (2.0, 30.0, 0.1, 1.5, 5)}


def width(t_end: float) -> float:
    """Rock on each side of the fracture: petthm's default for this end time."""
    kappa = LAM_S / (RHO_S * C_S)
    return max(60.0, float(math.ceil(4.0 * math.sqrt(kappa * t_end))))


def schedule(level: int, t_end: float) -> list[float]:
    """Backward-Euler steps: DT0 growing by g up to dt_max, the last one cut to t_end."""
    g, dtmax = SCHEDULES[level]
    steps, t, dt = [], 0.0, DT0
    while t < t_end * (1 - 1e-12):
        dt = min(dt, t_end - t)
        steps.append(dt)
        t += dt
        dt = min(dt * g, dtmax)
    return steps


def exact_outlet(t, root: Path):
    """Lauwerier's outlet temperature (degC) from petthm.verification.analytic."""
    sys.path.insert(0, str(root))
    from petthm.verification.analytic import lauwerier_temperature
    return lauwerier_temperature(np.array([L]), np.asarray(t, float)[:, None], Q, B, RHO_S * C_S, LAM_S,
                                 RHO_F * C_F, T0, TI)[:, 0]


def score(t, T, root: Path) -> float:
    t, T = np.asarray(t, float), np.asarray(T, float)
    m = t >= T_SCORE * (1 - 1e-12)
    return float(np.max(np.abs(T[m] - exact_outlet(t[m], root))))


def load_avg() -> float:
    try:
        return os.getloadavg()[0]
    except OSError:
        return float("nan")


# ---------------------------------------------------------------- OGS venv
def ensure_ogs(venv: Path) -> Path:
    """The ogs executable of the virtual environment, installed if missing."""
    ogs = venv / "bin" / "ogs"
    if ogs.exists() and (venv / "bin" / "python").exists():
        p = subprocess.run([str(venv / "bin" / "python"), "-c", "import meshio, ogs"], capture_output=True)
        if p.returncode == 0:
            return ogs
    print(f"installing ogs==6.5.9 and meshio into {venv}", flush=True)
    py = shutil.which("python3.11") or sys.executable      # the wheel is built for CPython 3.11 (cp311)
    subprocess.run([py, "-m", "venv", str(venv)], check=True)
    pip = [str(venv / "bin" / "python"), "-m", "pip", "install", "-q"]
    local = sorted(glob.glob("/tmp/ogs_dl/ogs-6.5.9-*.whl"))
    subprocess.run(pip + [local[-1] if local else "ogs==6.5.9", "meshio"], check=True)
    return ogs


# ---------------------------------------------------------------- OGS case files
def layers(h0: float, growth: float, W: float) -> np.ndarray:
    """Distances from the fracture 0 ... W: first layer h0, each next one `growth` times thicker."""
    d, h = [0.0], h0
    while d[-1] < W:
        d.append(d[-1] + h)
        h *= growth
    d[-1] = W
    if len(d) > 2 and d[-1] - d[-2] < 0.5 * (d[-2] - d[-3] if len(d) > 3 else d[-2]):
        del d[-2]
    return np.array(d)


def _vtu(path: Path, pts, cells, cell_types, point_data=(), cell_data=()):
    """An ASCII VTK UnstructuredGrid: cells is a list of node-id lists."""
    conn = " ".join(str(i) for c in cells for i in c)
    off = np.cumsum([len(c) for c in cells])
    fmt = {"Float64": "%.17g", "Int32": "%d", "UInt64": "%d", "UInt8": "%d", "Int64": "%d"}

    def arr(name, typ, a, ncomp=1):
        a = np.asarray(a).ravel()
        return (f'<DataArray type="{typ}" Name="{name}" NumberOfComponents="{ncomp}" format="ascii">\n'
                + " ".join(fmt[typ] % v for v in a) + "\n</DataArray>\n")
    pd = "".join(arr(n, t, a) for n, t, a in point_data)
    cd = "".join(arr(n, t, a) for n, t, a in cell_data)
    with open(path, "w") as f:
        f.write('<?xml version="1.0"?>\n<VTKFile type="UnstructuredGrid" version="1.0" '
                'byte_order="LittleEndian" header_type="UInt64">\n<UnstructuredGrid>\n'
                f'<Piece NumberOfPoints="{len(pts)}" NumberOfCells="{len(cells)}">\n'
                f"<PointData>\n{pd}</PointData>\n<CellData>\n{cd}</CellData>\n"
                "<Points>\n" + arr("Points", "Float64", pts, 3) + "</Points>\n<Cells>\n"
                f'<DataArray type="Int64" Name="connectivity" format="ascii">\n{conn}\n</DataArray>\n'
                + arr("offsets", "Int64", off) + arr("types", "UInt8", cell_types)
                + "</Cells>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n")


def write_ogs_mesh(d: Path, dx: float, h0: float, growth: float, W: float) -> dict:
    nx = int(round(L / dx))
    x = np.linspace(0.0, L, nx + 1)
    dist = layers(h0, growth, W)
    y = np.concatenate([W - dist[::-1], W + dist[1:]])         # 0 ... 2W, fracture row at y = W
    jf = len(dist) - 1
    ny = len(y) - 1
    X, Y = np.meshgrid(x, y)
    pts = np.column_stack([X.ravel(), Y.ravel(), np.zeros(X.size)])
    def nid(j, i):
        return j * (nx + 1) + i
    quads = [[nid(j, i), nid(j, i + 1), nid(j + 1, i + 1), nid(j + 1, i)]
             for j in range(ny) for i in range(nx)]
    lines = [[nid(jf, i), nid(jf, i + 1)] for i in range(nx)]
    cells = quads + lines
    types = [9] * len(quads) + [3] * len(lines)
    mat = [0] * len(quads) + [1] * len(lines)
    aperture = [1.0] * len(quads) + [B] * len(lines)
    _vtu(d / "domain.vtu", pts, cells, types,
         cell_data=[("MaterialIDs", "Int32", mat), ("aperture", "Float64", aperture)])
    for name, node, quad in (("inlet", nid(jf, 0), jf * nx), ("outlet", nid(jf, nx), jf * nx + nx - 1)):
        _vtu(d / f"{name}.vtu", pts[[node]], [[0]], [1], point_data=[("bulk_node_ids", "UInt64", [node])],
             cell_data=[("bulk_element_ids", "UInt64", [quad])])
    far = [nid(0, i) for i in range(nx + 1)] + [nid(ny, i) for i in range(nx + 1)]
    far_lines = [[i, i + 1] for i in range(nx)] + [[nx + 1 + i, nx + 2 + i] for i in range(nx)]
    _vtu(d / "far.vtu", pts[far], far_lines, [3] * len(far_lines),
         point_data=[("bulk_node_ids", "UInt64", far)])
    return {"cells": len(quads) + len(lines), "quads": len(quads), "lines": len(lines), "nodes": len(pts),
            "dofs": 2 * len(pts), "layers_per_side": len(dist) - 1}


def _prop(name, value, typ="Constant"):
    return f"<property><name>{name}</name><type>{typ}</type><value>{value}</value></property>"


def _medium(mid, porosity, permeability, conductivity):
    liquid = "".join([_prop("density", RHO_F), _prop("viscosity", MU), _prop("specific_heat_capacity", C_F),
                      _prop("thermal_conductivity", LAM_F)])
    solid = "".join([_prop("density", RHO_S), _prop("specific_heat_capacity", C_S),
                     _prop("thermal_conductivity", LAM_S), _prop("storage", 0.0)])
    medium = "".join([_prop("porosity", porosity), _prop("permeability", permeability),
                      _prop("thermal_conductivity", conductivity),
                      _prop("thermal_longitudinal_dispersivity", 0.0),
                      _prop("thermal_transversal_dispersivity", 0.0)])
    return (f'<medium id="{mid}"><phases><phase><type>AqueousLiquid</type><properties>{liquid}</properties>'
            f"</phase><phase><type>Solid</type><properties>{solid}</properties></phase></phases>"
            f"<properties>{medium}</properties></medium>")


#: OGS linear solvers (Eigen, as the wheel is built): a direct one and an iterative one
LINEAR_SOLVERS = {"SparseLU": "<eigen><solver_type>SparseLU</solver_type><scaling>true</scaling></eigen>",
                  "BiCGSTAB": "<eigen><solver_type>BiCGSTAB</solver_type><precon_type>ILUT</precon_type>"
                              "<max_iteration_step>2000</max_iteration_step><error_tolerance>1e-14"
                              "</error_tolerance><scaling>true</scaling></eigen>"}


def write_ogs_prj(d: Path, steps: list[float], stabilization: str, solver: str = "SparseLU") -> None:
    pairs = "".join(f"<pair><repeat>1</repeat><delta_t>{dt!r}</delta_t></pair>" for dt in steps)
    stab = ("" if stabilization == "none" else
            f"<numerical_stabilization><type>{stabilization}</type><cutoff_velocity>0</cutoff_velocity>"
            "</numerical_stabilization>")
    prj = f"""<?xml version="1.0" encoding="ISO-8859-1"?>
<!-- written by benchmarks/peer_ogs/run_peer_ogs.py: petthm's lauwerier case for OGS's HT process -->
<OpenGeoSysProject>
  <meshes><mesh>domain.vtu</mesh><mesh>inlet.vtu</mesh><mesh>outlet.vtu</mesh><mesh>far.vtu</mesh></meshes>
  <processes><process>
    <name>HT</name><type>HT</type><integration_order>2</integration_order>
    <process_variables><temperature>T</temperature><pressure>p</pressure></process_variables>
    <specific_body_force>0 0</specific_body_force>
    <aperture_size><parameter>aperture</parameter></aperture_size>
    {stab}
  </process></processes>
  <media>
    {_medium(0, 0.0, 1e-20, LAM_S)}
    {_medium(1, 1.0, B * B / 12.0, LAM_F)}
  </media>
  <time_loop>
    <processes><process ref="HT">
      <nonlinear_solver>picard</nonlinear_solver>
      <convergence_criterion><type>PerComponentDeltaX</type><norm_type>INFINITY_N</norm_type>
        <abstols>1e-6 1</abstols></convergence_criterion>
      <time_discretization><type>BackwardEuler</type></time_discretization>
      <time_stepping><type>FixedTimeStepping</type><t_initial>0</t_initial><t_end>{sum(steps)!r}</t_end>
        <timesteps>{pairs}</timesteps></time_stepping>
    </process></processes>
    <output>
      <type>VTK</type><prefix>lw_{{:meshname}}</prefix><suffix>_ts_{{:timestep}}</suffix>
      <meshes><mesh>outlet</mesh><mesh>inlet</mesh></meshes>
      <timesteps><pair><repeat>1000000</repeat><each_steps>1</each_steps></pair></timesteps>
      <variables><variable>T</variable><variable>p</variable></variables>
    </output>
  </time_loop>
  <parameters>
    <parameter><name>aperture</name><type>MeshElement</type><mesh>domain</mesh><field_name>aperture</field_name></parameter>
    <parameter><name>T_initial</name><type>Constant</type><value>{T0}</value></parameter>
    <parameter><name>T_injection</name><type>Constant</type><value>{TI}</value></parameter>
    <parameter><name>p_zero</name><type>Constant</type><value>0</value></parameter>
    <parameter><name>rate</name><type>Constant</type><value>{Q}</value></parameter>
  </parameters>
  <process_variables>
    <process_variable><name>T</name><components>1</components><order>1</order>
      <initial_condition>T_initial</initial_condition>
      <boundary_conditions>
        <boundary_condition><mesh>far</mesh><type>Dirichlet</type><parameter>T_initial</parameter></boundary_condition>
        <boundary_condition><mesh>inlet</mesh><type>Dirichlet</type><parameter>T_injection</parameter></boundary_condition>
      </boundary_conditions>
    </process_variable>
    <process_variable><name>p</name><components>1</components><order>1</order>
      <initial_condition>p_zero</initial_condition>
      <boundary_conditions>
        <boundary_condition><mesh>outlet</mesh><type>Dirichlet</type><parameter>p_zero</parameter></boundary_condition>
      </boundary_conditions>
      <source_terms>
        <source_term><mesh>inlet</mesh><type>Nodal</type><parameter>rate</parameter></source_term>
      </source_terms>
    </process_variable>
  </process_variables>
  <nonlinear_solvers><nonlinear_solver><name>picard</name><type>Picard</type><max_iter>10</max_iter>
    <linear_solver>lu</linear_solver></nonlinear_solver></nonlinear_solvers>
  <linear_solvers><linear_solver><name>lu</name>
    {LINEAR_SOLVERS[solver]}</linear_solver></linear_solvers>
</OpenGeoSysProject>
"""
    (d / "lauwerier.prj").write_text(prj)


READ_OUTLET = r"""
import glob, json, re, sys, meshio
rows = []
for f in glob.glob(sys.argv[1] + "/lw_" + sys.argv[2] + "_ts_*.vtu"):
    m = meshio.read(f)
    rows.append((int(re.search(r"_ts_(\d+)", f).group(1)), float(m.point_data["T"][0]),
                 float(m.point_data["p"][0])))
print(json.dumps(sorted(rows)))
"""


def run_ogs(level: int, out: Path, venv: Path, t_end: float, root: Path, stabilization: str,
            solver: str = "SparseLU") -> dict:
    dx, h0, growth, sched = OGS_LEVELS[level]
    d = out / (f"ogs_R{level}" + ("" if solver == "SparseLU" else f"_{solver}"))
    shutil.rmtree(d, ignore_errors=True)
    d.mkdir(parents=True)
    steps = schedule(sched, t_end)
    info = write_ogs_mesh(d, dx, h0, growth, width(t_end))
    write_ogs_prj(d, steps, stabilization, solver)
    ogs = ensure_ogs(venv)
    env = dict(os.environ, OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1")
    load = load_avg()
    t0 = time.perf_counter()
    p = subprocess.run([str(ogs), "-o", str(d), "lauwerier.prj"], cwd=d, capture_output=True, text=True,
                       env=env)
    wall = time.perf_counter() - t0
    (d / "ogs.log").write_text(p.stdout + p.stderr)
    if p.returncode:
        raise RuntimeError(f"OGS R{level} failed (rc {p.returncode}); the end of its log:\n"
                           + "\n".join((p.stdout + p.stderr).splitlines()[-25:]))
    # the inlet pressure checks the fracture's transmissivity: Q L 12 mu / b^3 = 1.2e5 Pa
    rows, inlet = (json.loads(subprocess.run([str(venv / "bin" / "python"), "-c", READ_OUTLET, str(d), m],
                                             capture_output=True, text=True, check=True).stdout)
                   for m in ("outlet", "inlet"))
    times = np.concatenate([[0.0], np.cumsum(steps)])
    ts = np.array([times[k] for k, _, _ in rows])
    T = np.array([v for _, v, _ in rows])
    _write_history(d / "outlet_history.csv", ts, T, root)
    return {"code": "OGS 6.5.9" + ("" if solver == "SparseLU" else f" {solver}"), "case": f"R{level}",
            "mesh": f"quads+1D lines, dx {dx:g} m, wall layer {h0:g} m "
            f"x{growth:g} ({info['layers_per_side']} layers/side)", "cells": info["cells"],
            "dofs": info["dofs"], "steps": len(steps), "wall_s": wall, "error_K": score(ts, T, root),
            "load_before": load, "schedule": sched, "p_inlet_end_Pa": inlet[-1][2],
            "ogs_reported_s": _ogs_time(p.stdout)}


def _ogs_time(log: str):
    """OGS's own 'Simulation completed. It took X s' (time loop, without start-up)."""
    for line in log.splitlines():
        if "Simulation completed. It took" in line:
            return float(line.split("took")[1].split()[0])
    return None


def _write_history(path: Path, t, T, root: Path):
    ex = exact_outlet(t, root)
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["time_s", "T_out_degC", "T_lauwerier_degC"])
        w.writerows(zip(t, T, ex, strict=False))


# ---------------------------------------------------------------- petthm
def run_petthm(case: str, out: Path, t_end: float, root: Path) -> dict:
    layered, bdf2 = case.startswith("l"), case.startswith("b")
    ogs_layer = case.startswith("w") or bdf2
    level = int(case.lstrip("lwb"))
    if ogs_layer:
        fs, ms, layer, layer_growth, sched = (PETTHM_BDF2_LEVELS if bdf2 else PETTHM_WALL_LEVELS)[level]
    else:
        fs, ms, sched = PETTHM_LEVELS[level]
        layer, layer_growth = PETTHM_LAYER, PETTHM_LAYER_GROWTH
    g, dtmax = SCHEDULES[sched]
    d = out / f"petthm_P2_{case}"
    shutil.rmtree(d, ignore_errors=True)
    opts = ["-thm_final_time", t_end, "-thm_fe_degree", 2, "-thm_lauwerier_fracture_size", fs,
            "-thm_mesh_size", ms, "-thm_dt_initial", DT0, "-thm_dt_growth", g, "-thm_dt_max", dtmax]
    if layered or ogs_layer:
        opts += ["-thm_lauwerier_layer", layer, "-thm_lauwerier_layer_growth", layer_growth]
    if bdf2:
        opts += ["-ts_type", "bdf", "-ts_bdf_order", 2]
    cmd = [sys.executable, "-m", "petthm", "lauwerier", "-thm_output_dir", str(d), "-thm_quiet",
           "-thm_overwrite", *map(str, opts)]
    env = dict(os.environ, OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1")
    load = load_avg()
    t0 = time.perf_counter()
    p = subprocess.run(cmd, cwd=root, capture_output=True, text=True, env=env)
    wall = time.perf_counter() - t0
    if p.returncode:
        raise RuntimeError(f"petthm {case} failed:\n{p.stdout}\n{p.stderr}")
    s = json.loads((d / "summary.json").read_text())
    with open(d / "history.csv") as f:
        rows = list(csv.DictReader(f))
    t = np.array([float(r["time"]) for r in rows])
    T = np.array([float(r["production_temperature"]) for r in rows])
    _write_history(d / "outlet_history.csv", t, T, root)
    kind = f"layered {layer} m x{layer_growth}" if layered or ogs_layer else "graded"
    mesh = f"P2 {kind}, fracture h {fs:g} m, far {ms:g} m"
    name = (f"B{level}-layered" if bdf2 else f"W{level}-layered" if ogs_layer
            else f"L{level}" + ("-layered" if layered else ""))
    return {"code": "petthm P2 BDF2" if bdf2 else "petthm P2", "case": name, "mesh": mesh,
            "cells": s["cells"], "dofs": sum(s["dofs"].values()), "steps": s["steps"], "wall_s": wall,
            "error_K": score(t, T, root), "load_before": load, "schedule": sched,
            "petthm_wall_total_s": s["wall_time"]["total"],
            "petthm_reported_error_K": (s["error"]["outlet_max_rel_t_ge_1e4"] or float("nan")) * (T0 - TI)}


# ---------------------------------------------------------------- report
FIELDS = ["code", "case", "mesh", "cells", "dofs", "steps", "schedule", "wall_s", "error_K", "load_before",
          "ogs_reported_s", "p_inlet_end_Pa", "petthm_wall_total_s", "petthm_reported_error_K", "repeat"]


def write_results(rows, out: Path, t_end: float, stabilization: str, solver: str = "SparseLU"):
    out.mkdir(parents=True, exist_ok=True)
    with open(out / "peer_ogs.csv", "w", newline="") as f:
        w = csv.DictWriter(f, FIELDS, extrasaction="ignore")
        w.writeheader()
        for r in rows:
            w.writerow({k: (f"{v:.4g}" if isinstance(v, float) else v) for k, v in r.items()})
    best = _best(rows)
    lines = ["# petthm vs OpenGeoSys 6.5.9: Lauwerier outlet error against wall time",
             "", f"End time {t_end:g} s; error = max |T_out - T_Lauwerier| over {T_SCORE:g} s <= t <= "
             f"{t_end:g} s (K); wall = whole process, one run at a time (best of "
             f"{max(r['repeat'] for r in rows)} run(s)); OGS stabilization: {stabilization}; "
             f"OGS linear solver(s): Eigen {solver}.", "",
             "| code | case | mesh | cells | dofs | steps (schedule) | wall (s) | error (K) | "
             "load avg before |",
             "|---|---|---|---|---|---|---|---|---|"]
    for r in best:
        g, dtmax = SCHEDULES[r["schedule"]]
        lines.append(f"| {r['code']} | {r['case']} | {r['mesh']} | {r['cells']} | {r['dofs']} | {r['steps']} "
                     f"(x{g:g}, max {dtmax:.0e} s) | {r['wall_s']:.2f} | {r['error_K']:.3f} | "
                     f"{r['load_before']:.2f} |")
    lines += ["", "petthm at each OGS run's error: the fastest measured petthm run with the same or a "
              "smaller error (any mesh), and the graded series' wall time at that error interpolated "
              "log-log between its runs ('-': no petthm run reaches it / outside the series' range).", "",
              "| OGS case | OGS error (K) | OGS wall (s) | fastest petthm run with error <= it | "
              "its wall (s) | speed-up | graded P2 interpolated (s) | speed-up |",
              "|---|---|---|---|---|---|---|---|"]
    pets = [r for r in best if r["code"].startswith("petthm")]
    graded = sorted((r for r in pets if "layered" not in r["case"]), key=lambda r: r["error_K"])
    for r in sorted((x for x in best if x["code"].startswith("OGS")), key=lambda x: (x["code"], x["case"])):
        ok = [x for x in pets if x["error_K"] <= r["error_K"]]
        f = min(ok, key=lambda x: x["wall_s"]) if ok else None
        tw = _interp_wall(graded, r["error_K"])
        lines.append(f"| {r['code'].replace('OGS 6.5.9', '').strip() or 'SparseLU'} {r['case']} | "
                     f"{r['error_K']:.3f} | {r['wall_s']:.2f} | "
                     + (f"{f['case']} ({f['error_K']:.3f} K) | {f['wall_s']:.2f} | "
                        f"{r['wall_s'] / f['wall_s']:.2f}x | " if f else "- | - | - | ")
                     + (f"{tw:.2f} | {r['wall_s'] / tw:.2f}x |" if tw else "- | - |"))
    (out / "peer_ogs.md").write_text("\n".join(lines) + "\n")
    plot(best, out / "peer_ogs.png", t_end)


def _best(rows):
    """Per (code, case): the run with the smallest wall time (errors are deterministic)."""
    keep = {}
    for r in rows:
        k = (r["code"], r["case"])
        if k not in keep or r["wall_s"] < keep[k]["wall_s"]:
            keep[k] = r
    return list(keep.values())


def _interp_wall(pet, err):
    """petthm's wall time at error `err`, log-log between the bracketing runs of the graded series."""
    for a, b in zip(pet, pet[1:], strict=False):                 # sorted by error, ascending
        if a["error_K"] <= err <= b["error_K"]:
            if b["error_K"] == a["error_K"]:
                return min(a["wall_s"], b["wall_s"])
            s = math.log(err / a["error_K"]) / math.log(b["error_K"] / a["error_K"])
            return math.exp(math.log(a["wall_s"]) + s * math.log(b["wall_s"] / a["wall_s"]))
    return None


def plot(rows, path: Path, t_end: float):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6.2, 4.6))
    series = {}
    for r in rows:
        key = r["code"] + (" OGS's wall layers" if r["case"][0] in "WB" else
                           " layered" if "layered" in r["case"] else "")
        series.setdefault(key, []).append(r)
    style = {"OGS 6.5.9": ("o", "-"), "OGS 6.5.9 BiCGSTAB": ("D", ":"), "petthm P2": ("s", "-"),
             "petthm P2 layered": ("^", "--"), "petthm P2 OGS's wall layers": ("v", "-."),
             "petthm P2 BDF2 OGS's wall layers": ("P", "-.")}
    for key, rs in series.items():
        rs = sorted(rs, key=lambda r: r["wall_s"])
        mk, ls = style.get(key, ("x", ":"))
        ax.loglog([r["wall_s"] for r in rs], [r["error_K"] for r in rs], marker=mk, linestyle=ls, label=key)
        for r in rs:
            ax.annotate(r["case"].replace("-layered", ""), (r["wall_s"], r["error_K"]), fontsize=7,
                        xytext=(3, 3), textcoords="offset points")
    ax.set_xlabel("wall time of the whole run (s, one core)")
    ax.set_ylabel(f"max outlet error, {T_SCORE:g} s <= t <= {t_end:g} s (K)")
    ax.set_title("Lauwerier: petthm vs OpenGeoSys 6.5.9")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", default=str(ROOT / "output" / "peer_ogs"))
    ap.add_argument("--work", default=None, help="run directories (default: OUT/runs)")
    ap.add_argument("--ogs-levels", default="1,2,3")
    ap.add_argument("--petthm-levels", default="0,1,2",
                    help="petthm P2 levels; 'lN' for the layered mesh of level N (e.g. 0,1,2,l0,l1), "
                         "'wN' for the meshes with OGS's wall layers (PETTHM_WALL_LEVELS), "
                         "'bN' for those with BDF2 (PETTHM_BDF2_LEVELS)")
    ap.add_argument("--repeat", type=int, default=1, help="run everything this many times (best wall kept)")
    ap.add_argument("--final-time", type=float, default=1e9)
    ap.add_argument("--stabilization", default="none", choices=("none", "FullUpwind"),
                    help="OGS's numerical stabilization of the heat advection (FullUpwind gives outlet "
                    "temperatures far above 100 degC on this mixed-dimensional mesh in 6.5.9: "
                    "docs/verification/peer-ogs.md)")
    ap.add_argument("--ogs-solvers", default="SparseLU",
                    help="OGS's linear solvers, comma-separated, each run at every OGS level: "
                    + ", ".join(LINEAR_SOLVERS) + " (Eigen SparseLU; BiCGSTAB with ILUT)")
    ap.add_argument("--petthm-root", default=str(ROOT),
                    help="repository whose petthm is run (cwd of its runs)")
    ap.add_argument("--venv", default=os.path.expanduser("~/.cache/petthm/venv-ogs"))
    a = ap.parse_args(argv)
    out, root, venv = Path(a.out), Path(a.petthm_root).resolve(), Path(a.venv)
    work = Path(a.work) if a.work else out / "runs"
    ensure_ogs(venv)
    ogs_levels = [int(x) for x in a.ogs_levels.split(",") if x]
    pet_cases = [x for x in a.petthm_levels.split(",") if x]
    solvers = [x for x in a.ogs_solvers.split(",") if x]
    for x in solvers:
        if x not in LINEAR_SOLVERS:
            ap.error(f"--ogs-solvers: unknown solver {x}")
    plan = []
    for k in range(max(len(ogs_levels), len(pet_cases))):        # alternate the two codes
        if k < len(ogs_levels):
            plan += [("ogs", (ogs_levels[k], solver)) for solver in solvers]
        if k < len(pet_cases):
            plan.append(("petthm", pet_cases[k]))
    rows = []
    for rep in range(1, a.repeat + 1):
        for code, case in plan:
            r = (run_ogs(case[0], work, venv, a.final_time, root, a.stabilization, case[1]) if code == "ogs"
                 else run_petthm(case, work, a.final_time, root))
            r["repeat"] = rep
            rows.append(r)
            print(f"[{rep}] {r['code']} {r['case']}: {r['wall_s']:.2f} s, error {r['error_K']:.3f} K, "
                  f"{r['cells']} cells, {r['steps']} steps (load {r['load_before']:.2f})", flush=True)
            write_results(rows, out, a.final_time, a.stabilization, a.ogs_solvers)
    print(f"wrote {out}/peer_ogs.csv, peer_ogs.md, peer_ogs.png")


if __name__ == "__main__":
    main()

"""Element matrices summed per nonzero (petthm/discretisation/sparsity.py) against the
plain sum of every element entry, and the Jacobian of a coupled scene
assembled through it against the element entries handed to PETSc as they
are."""
import math

import numpy as np
import pytest

from petthm import compat
from petthm.discretisation.sparsity import NodePairs


def _tables(rng, ne, nodes, nn, m, offsets):
    """Element dof tables (ne, nn*m) of a field with m components at
    ``offsets[node]`` (node-major, components consecutive)."""
    cells = np.array([rng.choice(nodes, nn, replace=False) for _ in range(ne)])
    base = offsets[cells]
    return (base[:, :, None] + np.arange(m)).reshape(ne, nn * m)


def _dense_sum(rows, cols, values, size):
    """The element matrices added entry by entry (np.add.at), as PETSc's COO does."""
    A = np.zeros((size, size))
    R = np.broadcast_to(rows[:, :, None], values.shape)
    C = np.broadcast_to(cols[:, None, :], values.shape)
    np.add.at(A, (R.ravel(), C.ravel()), values.ravel())
    return A


def _summed(block, rows, cols, values, size, global_index):
    """The block's sums as a dense matrix, values given element-major (ne, nbF, nbG)."""
    ne, m, n = block.ne, block.m, block.n
    v = values.reshape(ne, block.nnF, m, block.nnG, n).transpose(2, 4, 0, 1, 3).copy()
    out = np.zeros(block.size)
    block.add(v.ravel(), out)
    r, c = np.empty(block.size, compat.INT), np.empty(block.size, compat.INT)
    block.pattern(global_index, r, c)
    assert len(set(zip(r.tolist(), c.tolist(), strict=False))) == block.size, "one entry per nonzero"
    A = np.zeros((size, size))
    A[r, c] = out
    return A


@pytest.mark.parametrize("m,n", [(1, 1), (3, 3), (3, 1), (1, 2)])
def test_sums_per_nonzero_equal_the_element_entries_added_one_by_one(m, n):
    rng = np.random.default_rng(1)
    nodes, ne, nnF, nnG = 12, 40, 4, 3
    # two fields on the same points, interleaved per point as a PetscSection lays them out
    offsets_f = np.arange(nodes) * (m + n)
    offsets_g = offsets_f + m
    size = nodes * (m + n)
    rows = _tables(rng, ne, np.arange(nodes), nnF, m, offsets_f)
    cols = _tables(rng, ne, np.arange(nodes), nnG, n, offsets_g)
    values = rng.standard_normal((ne, nnF * m, nnG * n))
    block = NodePairs(rows, cols, m, n, size)
    assert block.npairs < ne * nnF * nnG                      # repeated node pairs were merged
    ident = np.arange(size, dtype=compat.INT)
    assert np.allclose(_summed(block, rows, cols, values, size, ident),
                       _dense_sum(rows, cols, values, size), rtol=0, atol=1e-13)


def test_a_shared_node_pair_index_is_used_only_where_it_reproduces_the_pairs():
    """Two field pairs on the same element node tables share the index; a
    block over other node tables with as many entries does not take it
    (negative control: taking it would add entries to the wrong nonzeros)."""
    rng = np.random.default_rng(2)
    nodes, ne, nn = 10, 30, 3
    off_u, off_p = np.arange(nodes) * 4, np.arange(nodes) * 4 + 3           # u (3 comps), p
    cells = np.array([rng.choice(nodes, nn, replace=False) for _ in range(ne)])
    u = (off_u[cells][:, :, None] + np.arange(3)).reshape(ne, 3 * nn)
    p = off_p[cells]
    uu = NodePairs(u, u, 3, 3, 4 * nodes)
    up = NodePairs(u, p, 3, 1, 4 * nodes, like=uu)
    pp = NodePairs(p, p, 1, 1, 4 * nodes, like=uu)
    assert up.inv is uu.inv and pp.inv is uu.inv
    other = off_p[np.array([rng.choice(nodes, nn, replace=False) for _ in range(ne)])]
    po = NodePairs(p, other, 1, 1, 4 * nodes, like=uu)
    assert po.inv is not uu.inv
    values = rng.standard_normal((ne, nn, nn))
    ident = np.arange(4 * nodes, dtype=compat.INT)
    for block, cols in ((pp, p), (po, other)):
        assert np.allclose(_summed(block, p, cols, values, 4 * nodes, ident),
                           _dense_sum(p, cols, values, 4 * nodes), rtol=0, atol=1e-13)


def test_constrained_rows_and_columns_keep_negative_indices():
    rng = np.random.default_rng(3)
    rows = _tables(rng, 8, np.arange(6), 3, 1, np.arange(6))
    block = NodePairs(rows, rows, 1, 1, 6)
    g = np.arange(6, dtype=compat.INT)
    g[2] = -1
    r, c = np.empty(block.size, compat.INT), np.empty(block.size, compat.INT)
    block.pattern(g, r, c)
    keys = block.keys
    assert np.array_equal(r < 0, keys // 6 == 2) and np.array_equal(c < 0, keys % 6 == 2)


def _element_level_matrix(problem, values):
    """The Jacobian from the assemblers' element entries (``values``: per
    assembler, per slab) handed to PETSc as they are (every element entry
    its own COO entry, PETSc summing them), plus the point and diagonal
    entries as ``Problem`` adds them."""
    g = problem.disc.global_index
    rows, cols, vals = [], [], []
    for a in problem.assemblers.values():
        for slab in a.sums.slabs:
            b = a.sums.blocks[slab.key][0]
            if len(slab.key) == 2:
                rt, ct = a.dofs(slab.key[0]), a.dofs(slab.key[1])
            else:
                field, boundary, i = slab.key
                rt = ct = a.dofs(field)[a._facets[boundary][i].cells]
            rt = rt.reshape(b.ne, b.nnF, b.m).transpose(2, 0, 1)[:, None, :, :, None]
            ct = ct.reshape(b.ne, b.nnG, b.n).transpose(2, 0, 1)[None, :, :, None, :]
            r, c = np.broadcast_arrays(g[rt], g[ct])
            rows.append(r.ravel())
            cols.append(c.ravel())
            vals.append(values[a.sums][slab])
    n = sum(a.nnz for a in problem.assemblers.values())
    rest = problem._jvals[n:]
    extra = [(p.coo_rows, p.coo_cols) for p in problem.points] + [(problem._diagonal, problem._diagonal)]
    rows += [r for r, _ in extra]
    cols += [c for _, c in extra]
    vals.append(rest)
    M = compat.coo_matrix(problem.dm, np.concatenate(rows), np.concatenate(cols))
    compat.coo_set_values(M, np.concatenate(vals))
    M.assemble()
    return M


@pytest.mark.parametrize("scene,opts", [
    ("coupled_mms", dict(thm_fe_degree=2, thm_mesh_size=0.25)),
    ("heat_mms", dict(thm_mms_dim=3, thm_fe_degree=2, thm_mesh_size=0.5)),
    ("lauwerier", dict(thm_fe_degree=1, thm_lauwerier_fracture_size=10.0)),
])
def test_the_summed_jacobian_equals_the_element_entries_summed_by_petsc(tmp_path, monkeypatch, scene, opts):
    from conftest import build_problem
    from petthm.discretisation.sparsity import SummedBlocks
    p = build_problem(tmp_path, scene, **opts)
    rng = np.random.default_rng(4)
    x = p.X.duplicate()
    x.setArray(rng.standard_normal(x.getLocalSize()) * 0.1)
    J = p.create_matrix()
    values = {}
    summed = SummedBlocks.sum

    def spy(self, out, keep_constant):                 # the element values of the full assembly
        values.setdefault(self, {k: v.copy() for k, v in self.values.items()})
        return summed(self, out, keep_constant)
    monkeypatch.setattr(SummedBlocks, "sum", spy)
    p.ijacobian(None, 0.5, x, x, 3.0, J, J)
    monkeypatch.setattr(SummedBlocks, "sum", summed)
    p.ijacobian(None, 0.5, x, x, 3.0, J, J)           # the second keeps the constant blocks
    M = _element_level_matrix(p, values)
    blocks = sum(len(a.sums.blocks) for a in p.assemblers.values())
    numbered = [b for a in p.assemblers.values() for b, _ in a.sums.blocks.values()]
    assert any(b.by_topology for b in numbered)                  # the rock's blocks at least
    for b in numbered:                                            # one entry per nonzero either way
        assert b.npairs == np.unique(b.keys).size
    M.axpy(-1.0, J)
    print(scene, "blocks", blocks, "difference", M.norm(), "of", J.norm())
    assert M.norm() <= 1e-12 * J.norm()


def test_a_discarded_matrix_is_made_again_from_nothing(tmp_path):
    """``Problem.discard_matrix`` (benchmarks/scene_assembly.py): the next
    matrix is a new one, with new node pairs, and the same Jacobian."""
    from conftest import build_problem
    p = build_problem(tmp_path, "contact_patch", thm_contact_dim=2)
    xl, xdl = (a.copy() for a in p.local_arrays(p.X, 0.0))

    def jacobian():
        J = p.create_matrix()
        compat.coo_set_values(J, p.jacobian_values(xl, xdl, 0.0, 1.0))
        J.assemble()
        return J
    J1 = jacobian()
    blocks = {k: b for a in p.assemblers.values() for k, (b, _) in a.sums.blocks.items()}
    assert p.create_matrix() is J1                                   # kept until discarded
    p.discard_matrix()
    J2 = jacobian()
    assert J2 is not J1
    again = {k: b for a in p.assemblers.values() for k, (b, _) in a.sums.blocks.items()}
    assert again.keys() == blocks.keys() and all(again[k] is not blocks[k] for k in blocks)
    J2.axpy(-1.0, J1)
    assert J2.norm() <= 1e-14 * J1.norm()


def _simplex_tables(tmp_path, dim, rng, shuffle):
    """Element node tables of a small DMPlex box (vertices, then edges in
    ``fe.EDGES``' order), each cell's vertices in a random local order when
    ``shuffle`` (its edge columns renumbered to match): every ordering class
    of ``simplexpairs`` occurs, not only the ascending one of ``Mesh``."""
    from petsc4py import PETSc

    from petthm.discretisation import fe
    from petthm.mesh import generate as meshing
    from petthm.mesh.plex import Mesh, read_plex
    path = meshing.box(str(tmp_path / "box.msh"), [1.0] * dim, 0.4)
    mesh = Mesh(read_plex(path, PETSc.COMM_SELF))
    verts, edges = mesh.cell_vertices.copy(), mesh.cell_edges.copy()
    if shuffle:
        E = [tuple(e) for e in fe.EDGES[dim]]
        where = {frozenset(e): k for k, e in enumerate(E)}
        for c in range(len(verts)):
            perm = rng.permutation(dim + 1)                 # new local vertex i = old vertex perm[i]
            edges[c] = [edges[c][where[frozenset((perm[a], perm[b]))]] for a, b in E]
            verts[c] = verts[c][perm]
    nverts = mesh.vertex_coords.shape[0]
    return verts, edges - edges.min() + nverts, nverts + edges.max() - edges.min() + 1


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("degrees", [(1, 1), (2, 2), (2, 1), (1, 2)])
@pytest.mark.parametrize("shuffle", [False, True])
def test_pairs_numbered_by_topology_are_the_unique_pairs(tmp_path, dim, degrees, shuffle):
    """``simplexpairs.numbered_slots``: every element entry's slot holds one
    node pair, every slot is used, there are exactly as many slots as
    distinct pairs (``np.unique``), and each slot's given entry is one of
    its pairs, for P1/P2 rows and columns, triangles and tetrahedra, with
    the cells' vertices in every local order."""
    from petthm.discretisation.simplexpairs import numbered_slots
    rng = np.random.default_rng(5)
    verts, edges, nnodes = _simplex_tables(tmp_path, dim, rng, shuffle)
    table = {1: verts, 2: np.hstack([verts, edges])}
    rows, cols = table[degrees[0]], table[degrees[1]]
    found = numbered_slots(rows, cols, dim)
    slots, count = found.slots(slice(None)), found.count
    assert np.array_equal(np.concatenate([found.slots(slice(s, s + 7)) for s in range(0, len(rows), 7)]),
                          slots)                                # in batches the same
    row_at, col_at = found.row_at, found.col_at
    keys = (rows.astype(np.int64)[:, :, None] * nnodes + cols[:, None, :])
    unique = np.full(count, -1, np.int64)
    unique[slots] = keys
    assert np.array_equal(unique[slots], keys)                  # one pair per slot
    assert (unique >= 0).all()                                  # every slot used
    assert count == np.unique(keys).size                        # each pair in one slot
    assert np.array_equal(rows.reshape(-1)[row_at] * nnodes + cols.reshape(-1)[col_at], unique)   # where
    orders = {tuple(np.argsort(v)) for v in verts}
    assert len(orders) == (math.factorial(dim + 1) if shuffle else 1)


def test_tables_that_are_not_simplices_fall_back_to_sorting():
    """Random node tables of six nodes per element are no P2 triangles: the
    topology's numbering, unchecked, puts two pairs into one slot (shown:
    the negative control of the check); checked, it declines (the nodes are
    no function of the vertices and edges), and ``NodePairs`` sorts instead;
    its sums are exact either way."""
    from petthm.discretisation.simplexpairs import numbered_slots
    rng = np.random.default_rng(6)
    nodes, ne = 20, 40
    rows = _tables(rng, ne, np.arange(nodes), 6, 1, np.arange(nodes))
    rows = rows[(np.diff(np.sort(rows[:, :3], axis=1), axis=1) > 0).all(axis=1)]   # 3 distinct vertices
    found = numbered_slots(rows, rows, 2, checked=False)
    slots, count = found.slots(slice(None)), found.count
    keys = rows.astype(np.int64)[:, :, None] * nodes + rows[:, None, :]
    unique = np.full(count, -1, np.int64)
    unique[slots] = keys
    assert not np.array_equal(unique[slots], keys)
    assert numbered_slots(rows, rows, 2) is None
    block = NodePairs(rows, rows, 1, 1, nodes, simplex_dim=2)
    assert not block.by_topology and block.npairs == np.unique(keys).size
    values = rng.standard_normal((rows.shape[0], 6, 6))
    ident = np.arange(nodes, dtype=compat.INT)
    assert np.allclose(_summed(block, rows, rows, values, nodes, ident),
                       _dense_sum(rows, rows, values, nodes), rtol=0, atol=1e-13)
    assert numbered_slots(rows[:, :5], rows, 2) is None                     # not a P1/P2 node count
    assert numbered_slots(np.array([[0, 0, 1]]), np.array([[0, 0, 1]]), 2) is None   # a repeated vertex


def test_a_node_shared_by_two_edges_declines_the_topology():
    """The check's other half: nodes that are a function of the vertices and
    edges but not one-to-one (two edges' midpoints numbered as one node)
    would put one pair into two slots; the numbering declines them."""
    from petthm.discretisation.simplexpairs import numbered_slots
    rows = np.array([[0, 1, 2, 3, 4, 5], [1, 2, 6, 4, 7, 8]])      # two P2 triangles, edge (1, 2) shared
    assert numbered_slots(rows, rows, 2) is not None
    merged = rows.copy()
    merged[1, 4] = 3                                   # the second triangle's edge (2, 6) is node 3 too
    assert numbered_slots(merged, merged, 2) is None

"""The named physical groups of a gmsh mesh (petthm.mesh.groups;
../shared/docs/reservoir.md section 1): read from both of gmsh's formats
without reading the mesh, and the naming rules as input errors."""
import pytest

from petthm.errors import InputError
from petthm.mesh.groups import Group, check_names, named_groups, read_physical_names, reserved_words

MSH22 = """$MeshFormat
2.2 0 8
$EndMeshFormat
$PhysicalNames
4
1 7 "inj"
2 3 "Fault1"
2 4 "top"
3 1 "Granite"
$EndPhysicalNames
$Nodes
1
1 0 0 0
$EndNodes
"""


def _box_file(path, groups, version=2.2, binary=False):
    """Mesh the unit cube with gmsh and write it to ``path``; ``groups(gmsh,
    box)`` adds the physical groups.  The gmsh module, or the test is skipped."""
    gmsh = pytest.importorskip("gmsh")
    gmsh.initialize(["-v", "0"])
    try:
        gmsh.model.add("box")
        box = gmsh.model.occ.addBox(0, 0, 0, 1, 1, 1)
        gmsh.model.occ.synchronize()
        groups(gmsh, box)
        gmsh.option.setNumber("Mesh.MeshSizeMax", 0.34)
        gmsh.model.mesh.generate(3)
        gmsh.option.setNumber("Mesh.MshFileVersion", version)
        gmsh.option.setNumber("Mesh.Binary", int(binary))
        gmsh.write(str(path))
    finally:
        gmsh.finalize()
    return str(path)


def test_the_names_of_a_version_2_file_are_read(tmp_path):
    (tmp_path / "v2.msh").write_text(MSH22)
    assert read_physical_names(str(tmp_path / "v2.msh")) == [
        Group(1, 7, "inj"), Group(2, 3, "Fault1"), Group(2, 4, "top"), Group(3, 1, "Granite")]


@pytest.mark.parametrize("binary", [False, True])
def test_the_names_of_a_version_4_file_from_gmsh_are_read(tmp_path, binary):
    def groups(gmsh, box):
        gmsh.model.addPhysicalGroup(3, [box], 5, name="Reservoir")
        gmsh.model.addPhysicalGroup(2, [1], 9, name="west")
    path = _box_file(tmp_path / "g.msh", groups, version=4.1, binary=binary)
    assert sorted(read_physical_names(path), key=lambda g: g.dim) == \
        [Group(2, 9, "west"), Group(3, 5, "Reservoir")]


def test_a_file_without_names_has_none_and_a_broken_section_is_an_error(tmp_path):
    (tmp_path / "plain.msh").write_text(MSH22.replace("$PhysicalNames", "$Skip").replace("$EndPhysicalNames",
                                                                                        "$EndSkip"))
    assert read_physical_names(str(tmp_path / "plain.msh")) == []
    (tmp_path / "bad.msh").write_text(MSH22.replace("1 7 \"inj\"", "one"))
    with pytest.raises(InputError, match=r"bad.msh: its \$PhysicalNames section is not gmsh.s"):
        read_physical_names(str(tmp_path / "bad.msh"))
    with pytest.raises(InputError, match=r"-thm_mesh_file: cannot read .*missing.msh"):
        read_physical_names(str(tmp_path / "missing.msh"))


def test_every_rank_gets_the_names_and_the_error(tmp_path):
    from mpi4py import MPI
    (tmp_path / "v2.msh").write_text(MSH22)
    assert named_groups(str(tmp_path / "v2.msh"), MPI.COMM_WORLD)[1] == Group(2, 3, "Fault1")
    with pytest.raises(InputError, match="cannot read"):
        named_groups(str(tmp_path / "missing.msh"), MPI.COMM_WORLD)


def test_names_that_follow_the_contract_pass():
    groups = [Group(3, 1, "Granite"), Group(2, 3, "Fault1"), Group(1, 7, "inj")]
    check_names(groups, {"fracture": {"normal"}, "well": {"radius"}},
                {"Fault1": "fracture", "inj": "well", "Granite": "region"})


@pytest.mark.parametrize("groups,kinds,message", [
    ([Group(2, 1, "fault_1")], {}, r"'fault_1' \(dimension 2, tag 1\): a name is a letter followed by"),
    ([Group(2, 1, "1fault")], {}, "a name is a letter"),
    ([Group(2, 1, "my fault")], {}, "without spaces"),
    ([Group(3, 1, "Depth")], {}, "the name of a label DMPlex makes itself"),
    ([Group(2, 1, "Fault"), Group(2, 2, "fault")], {}, r"'fault' .* and 'Fault' .* differ only in case"),
    ([Group(2, 1, "top"), Group(3, 2, "top")], {}, "share the name"),
    ([Group(2, 1, "Normal")], {"Normal": "fracture"},
     r"'Normal' is the first word of a global -thm_fracture_\* option \(-thm_fracture_normal_\.\.\.\)"),
    ([Group(1, 1, "radius")], {"radius": "well"}, r"-thm_well_radius_\.\.\."),
])
def test_names_that_break_the_contract_are_input_errors(groups, kinds, message):
    with pytest.raises(InputError, match=message):
        check_names(groups, {"fracture": {"normal", "heat"}, "well": {"radius"}}, kinds)


def test_the_reserved_words_are_the_first_words_of_the_global_options():
    opts = ["-thm_fracture_normal_stiffness", "-thm_fracture_aperture", "-thm_fracture_heat_exchange",
            "-thm_well_radius", "-thm_rock_porosity"]
    assert reserved_words(opts, "fracture") == {"normal", "aperture", "heat"}
    assert reserved_words(opts, "well") == {"radius"}
    assert reserved_words(opts, "region") == set()


def test_the_option_table_reserves_the_words_of_the_contract():
    """reservoir.md's examples: a fracture called normal, heat, residual or
    aperture, a well called radius."""
    from petthm import params as P
    from petthm.scenes import MODULES, scene_class
    classes = [P.RunParams] + [c for n in MODULES for c in scene_class(n).parameters]
    options = P.known_options(classes)
    assert {"normal", "heat", "residual", "aperture"} <= reserved_words(options, "fracture")
    assert "radius" in reserved_words(options, "well")


def test_boundary_labels_by_name_are_those_by_coordinates(tmp_path):
    """The labels of named boundary groups (the faces of a gmsh box named
    west and top) hold the same points as plex.label_boundaries makes from
    the faces' coordinates; the negative control: the east face's."""
    import numpy as np
    from petsc4py import PETSc

    from petthm.mesh.groups import label_named_boundaries
    from petthm.mesh.plex import label_boundaries, read_plex
    from petthm.mesh.topology import label_name
    from petthm.scenes.base import face

    def add_groups(gmsh, box):
        gmsh.model.addPhysicalGroup(3, [box], 1, name="rock")
        faces = {tag: gmsh.model.occ.getCenterOfMass(2, tag)
                 for _, tag in gmsh.model.getBoundary([(3, box)], oriented=False)}
        gmsh.model.addPhysicalGroup(2, [t for t, c in faces.items() if abs(c[0]) < 1e-9], 11, name="west")
        gmsh.model.addPhysicalGroup(2, [t for t, c in faces.items() if abs(c[2] - 1) < 1e-9], 12, name="top")
    path = _box_file(tmp_path / "box.msh", add_groups)
    groups = [g for g in read_physical_names(path) if g.dim == 2]
    by_name = read_plex(path, PETSc.COMM_WORLD)
    label_named_boundaries(by_name, groups)
    by_coords = read_plex(path, PETSc.COMM_WORLD)
    label_boundaries(by_coords, {"west": face(0, 0.0), "top": face(2, 1.0), "east": face(0, 1.0)})

    def points(dm, name):
        return np.sort(dm.getStratumIS(label_name(name), 1).getIndices())
    assert points(by_name, "west").size > 0
    assert np.array_equal(points(by_name, "west"), points(by_coords, "west"))
    assert np.array_equal(points(by_name, "top"), points(by_coords, "top"))
    assert not np.array_equal(points(by_name, "west"), points(by_coords, "east"))
    with pytest.raises(InputError, match=r"physical group 'ghost' \(dimension 2, tag 99\) has no facets"):
        label_named_boundaries(by_name, [Group(2, 99, "ghost")])

"""Every unstructured grid (.vtu) and XDMF series (.xmf) the command line writes opens in meshio (Debian's
python3-meshio 7.0, the reader most Python FE users reach for) with all its arrays, and every .vtp/.vtu opens in
VTK's own readers with the unit of each array in its `units` field data (docs/output.md, "Units in the files").

Runs `sflsh mesh`, `sflsh material show`, `sflsh simulate` (vtk and the default xdmf, with the layer), `sflsh motion
export --format xdmf`, a small scene (vtk
and xdmf, with the layer, a rigid object), `sflsh compare` and `sflsh verify` (the FEBio block) at small sizes: the coarse layer, four frames, the
reduced model. `compare` writes surfaces only (compare.vtp: VTK and ParaView; meshio has no .vtp reader), as do
`sflsh validate`'s σ maps (dynamics.vtp, the same writer; not run here: --preset quick takes minutes).
"""
import pathlib
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from conftest import run_cli

meshio = pytest.importorskip("meshio")  # Debian python3-meshio (scripts/setup.sh)

SUBJECT = ["--subject", "OPEN_TRAIN_1"]
SHAPE_MODEL = pathlib.Path(__file__).resolve().parents[2] / "data" / "shape_models" / "default.toml"
SIMULATE = ["simulate", "--solver", "reduced", "--mesh", "coarse", *SUBJECT, "--motion", "jiggle_on_toes",
            "--frames", "4", "--write-layer"]
SCENE = """
[scene]
name = "meshio"
fps = 60
frames = 4

[effects]
inertia = true
object_contact = true

[[body]]
name = "subject"
subject = "OPEN_TRAIN_1"
motion = "jiggle_on_toes"
solver = "reduced"
mesh = "coarse"
handles = 30

[[object]]
name = "ball"
shape = "sphere"
radius = 0.06
motion = "fixed"
position = [0.0, 0.06, 0.5]

[output]
layer = true
format = "{format}"
"""
# Text arrays of the field data (UTF-8 in UInt8, one line per value): not arrays with a unit of their own.
TEXT_ARRAYS = {"units", "part_names", "node_kind_names"}


def text(values):
    """The lines of a text array of field data (UInt8, as meshio and VTK return it)."""
    values = np.asarray(values)
    assert values.dtype == np.uint8, values.dtype
    return values.tobytes().decode("utf-8").split("\n")


def units_table(values):
    """A `units` text array as {name: unit}."""
    return dict(entry.split(": ", 1) for entry in text(values))


def vtk_arrays(path):
    """{"point"|"cell"|"field": {name: numpy array}} of a .vtp/.vtu read by VTK's own XML readers."""
    from vtkmodules.util.numpy_support import vtk_to_numpy
    from vtkmodules.vtkIOXML import vtkXMLPolyDataReader, vtkXMLUnstructuredGridReader

    reader = vtkXMLPolyDataReader() if path.suffix == ".vtp" else vtkXMLUnstructuredGridReader()
    reader.SetFileName(str(path))
    reader.Update()
    assert reader.GetErrorCode() == 0, path
    data = reader.GetOutput()
    assert data.GetNumberOfPoints() > 0, path
    out = {}
    for kind, group in (("point", data.GetPointData()), ("cell", data.GetCellData()), ("field", data.GetFieldData())):
        out[kind] = {group.GetArrayName(i): vtk_to_numpy(group.GetAbstractArray(i))
                     for i in range(group.GetNumberOfArrays())}
    return out


def check_vtk_file(path):
    """VTK reads the file, and its `units` names each numeric array once with a unit (not "?")."""
    arrays = vtk_arrays(path)
    names = {n for kind in arrays.values() for n in kind} - TEXT_ARRAYS
    units = units_table(arrays["field"]["units"])
    assert set(units) == names, (path, set(units) ^ names)
    assert "?" not in units.values(), (path, units)
    for label in ("part", "node_kind"):
        if label in names:
            assert all(text(arrays["field"][label + "_names"])), (path, label)
    return arrays


def check_vtu_in_meshio(path):
    """meshio.read opens the .vtu with the points, the tets and every array VTK reads, and its units."""
    mesh = meshio.read(path)
    arrays = vtk_arrays(path)
    assert mesh.points.shape[0] > 0
    assert [block.type for block in mesh.cells] in (["tetra"], ["triangle"]), path
    assert set(mesh.point_data) == set(arrays["point"]), path
    assert set(mesh.cell_data) == set(arrays["cell"]), path
    assert set(mesh.field_data) == set(arrays["field"]), path
    for name, values in arrays["point"].items():
        np.testing.assert_array_equal(mesh.point_data[name].reshape(values.shape), values, err_msg=name)
    for name, values in arrays["cell"].items():
        np.testing.assert_array_equal(mesh.cell_data[name][0].reshape(values.shape), values, err_msg=name)
    assert units_table(mesh.field_data["units"]) == units_table(arrays["field"]["units"])


def xmf_units(path):
    """The `units` Information of an .xmf as {name: unit}."""
    value = ET.parse(path).getroot().find(".//Information[@Name='units']").get("Value")
    return dict(entry.split(": ", 1) for entry in value.split("; "))


def check_xmf_in_meshio(path):
    """meshio's TimeSeriesReader opens the series: the mesh, then every step with every array the .xmf lists."""
    units = xmf_units(path)
    with meshio.xdmf.TimeSeriesReader(str(path)) as reader:
        points, cells = reader.read_points_cells()
        assert points.shape[0] > 0 and len(cells) == 1, path
        seen = set()
        for k in range(reader.num_steps):
            t, point_data, cell_data = reader.read_data(k)
            for name, values in point_data.items():
                assert values.shape[0] == points.shape[0], (path, name)
                assert np.all(np.isfinite(values)), (path, name)
            seen |= set(point_data) | set(cell_data)
        assert reader.num_steps == 4, path
    assert seen == set(units) - {"TimeValue"}, (path, seen ^ set(units))
    assert "?" not in units.values(), (path, units)


def files(folder, suffix):
    return sorted(pathlib.Path(folder).glob("*" + suffix))


def check_folder(folder, vtu=0, xmf=0):
    """Every file of a run folder: .vtu in meshio and VTK, .vtp in VTK, .xmf in meshio; the counts expected."""
    vtus, xmfs = files(folder, ".vtu"), files(folder, ".xmf")
    assert (len(vtus), len(xmfs)) == (vtu, xmf), (folder, vtus, xmfs)
    for path in vtus:
        check_vtk_file(path)
        check_vtu_in_meshio(path)
    for path in files(folder, ".vtp"):
        check_vtk_file(path)
    for path in xmfs:
        check_xmf_in_meshio(path)


def run(cli, *args):
    r = run_cli(cli, *args)
    assert r.returncode == 0, r.stderr


def test_mesh_and_material_show(cli, cache, scratch):
    run(cli, "mesh", *SUBJECT, "--mesh", "coarse", "--mesher", "layered", "--cache", cache, "--out", str(scratch / "mesh"))
    check_folder(scratch / "mesh", vtu=1)
    mesh = meshio.read(scratch / "mesh" / "layer.vtu")
    assert text(mesh.field_data["part_names"])[:2] == ["torso", "left_upper_arm"]
    assert units_table(mesh.field_data["units"])["volume"] == "m^3"
    run(cli, "material", "show", *SUBJECT, "--shape-model", str(SHAPE_MODEL), "--mesh", "coarse",
        "--cache", cache, "--out", str(scratch / "material"))
    check_folder(scratch / "material", vtu=1)


def test_simulate_vtk_and_xdmf_with_the_layer(cli, cache, scratch):
    run(cli, *SIMULATE, "--format", "vtk", "--cache", cache, "--out", str(scratch / "vtk"))
    check_folder(scratch / "vtk", vtu=4)
    frame = scratch / "vtk" / "layer_000003.vtu"
    assert 'compressor="vtkZLibDataCompressor"' in frame.read_text(errors="replace")[:400]
    mesh = meshio.read(frame)
    assert units_table(mesh.field_data["units"])["strain_energy_density"] == "J/m^3"
    assert mesh.cell_data["strain_energy_density"][0].shape == (mesh.cells[0].data.shape[0],)
    run(cli, *SIMULATE, "--cache", cache, "--out", str(scratch / "xdmf"))   # the default: xdmf
    check_folder(scratch / "xdmf", xmf=2)
    run(cli, "motion", "export", *SUBJECT, "--motion", "jiggle_on_toes", "--frames", "4", "--format", "xdmf",
        "--out", str(scratch / "export"))
    check_folder(scratch / "export", xmf=1)


def test_lz4_on_request(cli, cache, scratch):
    # LZ4 writes faster; VTK and ParaView read it, meshio does not (its VTU reader knows zlib and lzma).
    run(cli, *SIMULATE, "--format", "vtk", "--compression", "lz4", "--cache", cache, "--out", str(scratch / "lz4"))
    frame = scratch / "lz4" / "layer_000001.vtu"
    assert 'compressor="vtkLZ4DataCompressor"' in frame.read_text(errors="replace")[:400]
    check_vtk_file(frame)


@pytest.mark.parametrize("format", ["vtk", "xdmf"])
def test_scene_with_the_layer_and_an_object(cli, cache, scratch, format):
    scratch.mkdir(parents=True, exist_ok=True)
    scene = scratch / "scene.toml"
    scene.write_text(SCENE.replace("{format}", format))
    run(cli, "simulate", "--scene", str(scene), "--cache", cache, "--out", str(scratch / "run"))
    if format == "vtk":
        check_folder(scratch / "run", vtu=4)
    else:
        check_folder(scratch / "run", xmf=3)  # subject.xmf, subject_layer.xmf, objects.xmf



def test_compare_writes_surfaces_vtk_reads_with_their_units(cli, cache, scratch):
    # A full-space run and one reduced model over four frames; no .vtu or .xmf, compare.vtp self-described.
    run(cli, "compare", *SUBJECT, "--motion", "jiggle_on_toes", "--mesh", "coarse", "--frames", "4", "--handles", "30",
        "--cubature", "100", "--cache", cache, "--out", str(scratch / "compare"))
    check_folder(scratch / "compare")
    arrays = check_vtk_file(scratch / "compare" / "compare.vtp")
    assert units_table(arrays["field"]["units"])["sigma_full"] == "mm"


def test_verify_solution_frames(cli, scratch):
    # `sflsh verify` on the FEBio block (docs/verification.md), four Newmark steps: solution_*.vtu, one per step.
    example = pathlib.Path(__file__).resolve().parents[2] / "examples" / "verify" / "febio_block"
    scratch.mkdir(parents=True, exist_ok=True)
    (scratch / "block.msh").write_bytes((example / "block.msh").read_bytes())
    problem = (example / "block.toml").read_text()
    problem = problem.replace("duration = 1.0 ", "duration = 0.004166666666666667 ")  # 4 steps of 1/960 s
    assert "duration = 0.004166666666666667" in problem
    (scratch / "block.toml").write_text(problem)
    run(cli, "verify", str(scratch / "block.toml"), "--out", str(scratch / "verify"))
    check_folder(scratch / "verify", vtu=5)
    mesh = meshio.read(scratch / "verify" / "solution_000004.vtu")
    assert mesh.points.shape == (484, 3) and mesh.cells[0].data.shape == (1800, 4)

"""Files: meshes written and read back, missing files named, and compare()
as `scan2lod compare --json`."""

import json

import numpy as np
import pytest

import scan2lod
from conftest import run_cli, used_only


def test_a_mesh_written_and_read_back_is_the_same(bunny_mesh, workdir):
    path = workdir / "bunny.ply"
    scan2lod.write_mesh(path, bunny_mesh)
    back = scan2lod.read_mesh(path)
    vertices, triangles = used_only(bunny_mesh)  # a file keeps the used vertices, in order
    assert np.array_equal(back.vertices, vertices)
    assert np.array_equal(back.triangles, triangles)
    assert np.array_equal(back.normals, bunny_mesh.normals[np.unique(bunny_mesh.triangles)])


def test_a_mesh_from_arrays_copies_them_once_and_checks_indices():
    vertices = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], dtype=np.float64)
    mesh = scan2lod.Mesh(vertices, [[0, 1, 2]])
    vertices[0, 0] = 5
    assert mesh.vertices[0, 0] == 0 and mesh.vertices.dtype == np.float32
    assert mesh.normals is None and mesh.colors is None
    with pytest.raises(ValueError, match=r"triangle 0 names vertex 3; expected 0 to 2 \(the mesh has 3 vertices\)"):
        scan2lod.Mesh(vertices, [[0, 1, 3]])
    with pytest.raises(TypeError, match="triangles must hold integers"):
        scan2lod.Mesh(vertices, [[0.0, 1.0, 2.0]])


def test_missing_files_raise_errors_naming_them(workdir):
    missing = workdir / "no_such_scan.conf"
    with pytest.raises(FileNotFoundError, match="no_such_scan.conf"):
        scan2lod.load_points(missing)
    with pytest.raises(FileNotFoundError, match="no_such_mesh.ply"):
        scan2lod.read_mesh(workdir / "no_such_mesh.ply")
    with pytest.raises(FileNotFoundError, match="no_such_model.mco"):
        scan2lod.load(workdir / "no_such_model.mco")
    with pytest.raises(FileNotFoundError, match="no_such_scan.conf"):
        scan2lod.build([missing])


def test_unusable_paths_for_writing(bunny_mesh, bunny_model, workdir):
    with pytest.raises(ValueError, match="extension"):
        scan2lod.write_mesh(workdir / "bunny.xyz", bunny_mesh)
    with pytest.raises(FileNotFoundError, match="no_folder"):
        bunny_model.save(workdir / "no_folder" / "bunny.mco")


def test_a_damaged_model_is_a_value_error_naming_the_file(workdir):
    path = workdir / "damaged.mco"
    path.write_bytes(b"SCAN2LOD" + bytes(100))
    with pytest.raises(ValueError, match="damaged.mco"):
        scan2lod.load(path)


def test_compare_is_the_command_lines_json(bunny_mesh, bunny_model, workdir):
    a, b = workdir / "full.ply", workdir / "coarse.ply"
    scan2lod.write_mesh(a, bunny_mesh)
    scan2lod.write_mesh(b, bunny_model.extract(triangles=5000))
    ours = scan2lod.compare(a, b, samples=20000)
    theirs = json.loads(run_cli("compare", a, b, "--samples", 20000, "--json"))
    assert ours == theirs
    assert 0 < ours["a_to_b"]["mean"] < 0.01 * ours["diagonal"]
    same = scan2lod.compare(bunny_mesh, bunny_mesh, samples=5000)
    assert same["a_to_b"]["max"] < 1e-6 and same["b_to_a"]["samples"] == 5000

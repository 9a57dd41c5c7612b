"""Points in, mesh out: the command line's reconstruction, through numpy."""

import threading
import time

import numpy as np
import pytest

import scan2lod
from conftest import BUNNY, run_cli, used_only


def test_load_points_reads_every_scan_with_unit_normals(bunny_points):
    points, normals = bunny_points
    assert points.dtype == np.float32 and points.shape[1] == 3
    assert normals.shape == points.shape
    assert len(points) > 100_000  # six range images of the bunny
    lengths = np.linalg.norm(normals, axis=1)
    assert np.allclose(lengths, 1.0, atol=1e-4)


def test_reconstruct_at_128_gives_the_command_lines_triangles(bunny_mesh, workdir):
    out = workdir / "cli_128.ply"
    run_cli("reconstruct", BUNNY, "--resolution", 128, "-o", out)
    cli = scan2lod.read_mesh(out)
    vertices, triangles = used_only(bunny_mesh)
    assert len(cli.triangles) == len(bunny_mesh.triangles) > 10_000
    assert np.array_equal(cli.triangles.astype(np.int64), triangles)
    assert np.array_equal(cli.vertices, vertices)


def test_a_mesh_shows_its_own_memory(bunny_mesh):
    v = bunny_mesh.vertices
    assert v.dtype == np.float32 and v.shape == (v.shape[0], 3)
    assert bunny_mesh.triangles.dtype == np.uint32
    assert not v.flags.owndata and v.base is bunny_mesh
    assert np.shares_memory(v, bunny_mesh.vertices)
    assert bunny_mesh.normals.shape == v.shape
    assert bunny_mesh.triangles.max() < len(v)


def test_arrays_given_without_normals_get_estimated_ones():
    # A sphere of radius 1 sampled densely: the surface lies within a cube of it.
    rng = np.random.default_rng(3)
    p = rng.normal(size=(20000, 3))
    p /= np.linalg.norm(p, axis=1, keepdims=True)
    mesh = scan2lod.reconstruct(p, resolution=32)
    radii = np.linalg.norm(mesh.vertices, axis=1)
    assert abs(radii.mean() - 1.0) < 0.01
    assert radii.max() - radii.min() < 0.1


def test_reconstruct_releases_the_gil(bunny_points):
    # While another thread reconstructs, this one keeps running: its longest
    # pause is far shorter than the call (holding the GIL, it would span it).
    points, normals = bunny_points
    spent = []

    def work():
        start = time.perf_counter()
        scan2lod.reconstruct(points, normals, resolution=64)
        spent.append(time.perf_counter() - start)

    worker = threading.Thread(target=work)
    worker.start()
    last, longest = time.perf_counter(), 0.0
    while worker.is_alive():
        now = time.perf_counter()
        longest, last = max(longest, now - last), now
    worker.join()
    assert spent[0] > 0.05
    assert longest < 0.5 * spent[0]


def test_progress_reaches_the_callback_with_stage_names(bunny_points):
    points, normals = bunny_points
    calls = []
    scan2lod.reconstruct(points, normals, resolution=64, progress=lambda stage, f: calls.append((stage, f)))
    stages = {stage for stage, _ in calls}
    assert "signed distances" in stages
    assert all(0.0 <= f <= 1.0 for _, f in calls)
    assert max(f for stage, f in calls if stage == "signed distances") == 1.0


def test_threads_reconstructing_at_once_each_get_their_own_progress(bunny_points):
    points, normals = bunny_points
    calls, meshes = {0: [], 1: []}, {}

    def work(i):
        meshes[i] = scan2lod.reconstruct(points, normals, resolution=32,
                                         progress=lambda stage, f: calls[i].append((stage, f)))

    threads = [threading.Thread(target=work, args=(i,)) for i in (0, 1)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert np.array_equal(meshes[0].triangles, meshes[1].triangles)
    for i in (0, 1):
        assert ("signed distances", 1.0) in calls[i]
        assert sum(1 for stage, f in calls[i] if (stage, f) == ("signed distances", 1.0)) == 1


def test_a_callback_that_raises_stops_the_call_with_its_error(bunny_points):
    points, normals = bunny_points

    class Stop(Exception):
        pass

    def refuse(stage, fraction):
        raise Stop("stop")

    with pytest.raises(Stop, match="stop"):
        scan2lod.reconstruct(points, normals, resolution=32, progress=refuse)


def test_options_by_their_flag_names(bunny_points):
    points, normals = bunny_points
    kept = scan2lod.reconstruct(points, normals, resolution=64, min_piece=0.0, max_hole=0.0)
    cleaned = scan2lod.reconstruct(points, normals, resolution=64)
    # Closing small holes adds triangles; keeping every speck cannot remove any.
    assert len(kept.triangles) != len(cleaned.triangles)
    with pytest.raises(TypeError, match="'resolutoin'"):
        scan2lod.reconstruct(points, normals, resolutoin=64)
    with pytest.raises(ValueError, match="unknown distance method 'nearest': expected closest, hoppe or planes"):
        scan2lod.reconstruct(points, normals, resolution=64, distance="nearest")


def test_bad_arrays_are_named():
    with pytest.raises(ValueError, match=r"points must be an \(n, 3\) array, got shape \(10, 2\)"):
        scan2lod.reconstruct(np.zeros((10, 2), np.float32))
    with pytest.raises(ValueError, match="normals must have one row per point: 5 rows for 10 points"):
        scan2lod.reconstruct(np.zeros((10, 3)), np.zeros((5, 3)))
    with pytest.raises(ValueError, match="resolution"):
        scan2lod.reconstruct(np.random.default_rng(1).normal(size=(100, 3)), np.ones((100, 3)), resolution=100)

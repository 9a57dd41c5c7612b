"""Shared data for the scan2lod tests: the bundled bunny scans, read once and
reconstructed once at R = 128 (as `scan2lod reconstruct --resolution 128`)."""

import os
import pathlib
import subprocess

import numpy as np
import pytest

import scan2lod

SOURCE = pathlib.Path(os.environ.get("SCAN2LOD_SOURCE_DIR", pathlib.Path(__file__).resolve().parents[2]))
BUNNY = SOURCE / "data" / "bunny" / "bun.conf"


def cli_path():
    return os.environ.get("SCAN2LOD_CLI", str(SOURCE / "build" / "bin" / "scan2lod"))


def run_cli(*args):
    """Runs the command line; returns its stdout (fails the test on an error)."""
    done = subprocess.run([cli_path(), *map(str, args)], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    return done.stdout


def used_only(mesh):
    """The mesh as a file holds it: only the vertices some triangle uses, in order."""
    used = np.unique(mesh.triangles)
    remap = np.full(len(mesh.vertices), -1, dtype=np.int64)
    remap[used] = np.arange(len(used))
    return mesh.vertices[used], remap[mesh.triangles]


@pytest.fixture(scope="session")
def bunny_points():
    return scan2lod.load_points(BUNNY)


@pytest.fixture(scope="session")
def bunny_mesh(bunny_points):
    points, normals = bunny_points
    return scan2lod.reconstruct(points, normals, resolution=128)


@pytest.fixture(scope="session")
def bunny_model(bunny_mesh):
    return scan2lod.build(bunny_mesh)


@pytest.fixture(scope="session")
def workdir(tmp_path_factory):
    return tmp_path_factory.mktemp("scan2lod")

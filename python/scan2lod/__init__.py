"""scan2lod: range scans -> marching-cubes meshes -> level-of-detail models.

    import scan2lod
    points, normals = scan2lod.load_points("bun.conf")
    mesh = scan2lod.reconstruct(points, normals, resolution=128)
    model = scan2lod.build(mesh)
    level = model.extract(triangles=5000)

Arrays are numpy views of the library's memory: float32 (n, 3) positions and
normals, uint32 (m, 3) triangles. Long calls release the GIL and take an
optional progress(stage, fraction) callback. Errors are FileNotFoundError,
OSError and ValueError with the command line's messages.
"""

from ._scan2lod import (  # noqa: F401
    Mesh,
    Model,
    __version__,
    build,
    compare,
    load,
    load_points,
    read_mesh,
    reconstruct,
    write_mesh,
)

__all__ = ["Mesh", "Model", "build", "compare", "load", "load_points", "read_mesh", "reconstruct", "write_mesh"]

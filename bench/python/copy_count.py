#!/usr/bin/env python3
"""How many times scan2lod copies numpy arrays handed to it.

For n points (default 10^7) it measures the growth of the process's peak
resident memory (VmHWM, reset through /proc/self/clear_refs before each call)
over each call, in units of the arrays' own float32 bytes (n * 3 * 4 each):

  Mesh(vertices)             the vertices copied into the mesh: expect 1.0
  Mesh(float64 vertices)     converted while copied, no float32 temporary: 1.0
  reconstruct(points, normals)
                             the import path of reconstruct(): the last point
                             is NaN, so the call stops right after importing
                             (the reconstruction refuses non-finite points):
                             expect 1.0 (points and normals, once each)
  mesh.vertices              a view: expect 0.0

Measure at 10^7 (the default): below glibc's largest mmap threshold (32 MiB
a block) freed blocks come back from the heap without new pages, and the
figures read low.

Run: PYTHONPATH=build/python python3 bench/python/copy_count.py [n]
"""

import sys

import numpy as np

import scan2lod


def peak_kib():
    with open("/proc/self/status") as status:
        for line in status:
            if line.startswith("VmHWM:"):
                return int(line.split()[1])
    raise RuntimeError("no VmHWM in /proc/self/status")


def reset_peak():
    with open("/proc/self/clear_refs", "w") as refs:
        refs.write("5")


def copies(call, array_bytes):
    """Peak memory growth over call(), in units of array_bytes."""
    reset_peak()
    before = peak_kib()
    call()
    return (peak_kib() - before) * 1024 / array_bytes


def main():
    n = int(float(sys.argv[1])) if len(sys.argv) > 1 else 10_000_000
    rng = np.random.default_rng(1)
    points = rng.random((n, 3), dtype=np.float32)
    normals = np.full((n, 3), 0.57735026, dtype=np.float32)
    points[-1] = np.nan
    one = points.nbytes
    empty = np.zeros((0, 3), np.uint32)
    print(f"{n} points, {one / 2**20:.1f} MiB per float32 (n, 3) array")

    holder = []
    ratio = copies(lambda: holder.append(scan2lod.Mesh(points, empty)), one)
    print(f"Mesh(float32 vertices):         {ratio:.3f} copies")
    mesh = holder.pop()
    ratio = copies(lambda: holder.append(mesh.vertices), one)
    print(f"mesh.vertices (a view):         {ratio:.3f} copies")
    holder.clear()
    del mesh

    wide = points.astype(np.float64)
    ratio = copies(lambda: holder.append(scan2lod.Mesh(wide, empty)), one)
    print(f"Mesh(float64 vertices):         {ratio:.3f} copies of the float32 size")
    holder.clear()
    del wide

    def import_only():
        try:
            scan2lod.reconstruct(points, normals, resolution=16)
        except ValueError as refused:
            assert "finite" in str(refused) or "NaN" in str(refused) or "nan" in str(refused), refused
        else:
            raise AssertionError("a NaN point was accepted")

    ratio = copies(import_only, 2 * one)
    print(f"reconstruct(points, normals):   {ratio:.3f} copies (points and normals)")


if __name__ == "__main__":
    main()

"""The Python side of the overhead figure: `python examples/python/overhead.py [STEPS]`
against `cargo run --release --example overhead [-- STEPS]` (same mesh, same motion: 20
random spheres of the `spheres` scene, seed 1, growing along area-weighted vertex
normals, grid backend, 40 steps by default). Prints the wall time of the loop and
the part spent outside `advance` (array copies and numpy normals)."""

import sys
import time

import numpy as np

import surftrack


def vertex_normals(vertices, triangles):
    """Unit sums of the incident triangles' area-weighted normals (as mesh_core does)."""
    p = vertices[triangles]
    face = 0.5 * np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    n = np.zeros_like(vertices)
    for k in range(3):
        np.add.at(n, triangles[:, k], face)
    length = np.linalg.norm(n, axis=1, keepdims=True)
    return np.divide(n, length, out=np.zeros_like(n), where=length > 0)


def main():
    steps = int(sys.argv[1]) if len(sys.argv) > 1 else 40
    n = 20
    mesh = surftrack.generate("spheres", count=n, seed=1)
    speed = 0.5 * n ** (-1.0 / 3.0)
    dt = 1.0 / 40.0
    tracker = surftrack.Tracker(mesh, backend="grid")
    start = time.perf_counter()
    merges = 0
    in_advance = 0.0
    for _ in range(steps):
        m = tracker.mesh
        v = m.vertices
        proposed = v + dt * speed * vertex_normals(v, m.triangles)
        clock = time.perf_counter()
        merges += tracker.advance(proposed).merges
        in_advance += time.perf_counter() - clock
    elapsed = time.perf_counter() - start
    print(
        f"python: {steps} steps, {tracker.mesh.num_triangles} triangles, {merges} merges, "
        f"{elapsed:.3f} s ({in_advance:.3f} s in advance, {elapsed - in_advance:.3f} s outside)"
    )


if __name__ == "__main__":
    main()

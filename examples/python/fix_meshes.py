"""`surftrack.fix` on meshes loaded with trimesh or pymeshlab (when installed): overlapping
meshes become one clean multi-material mesh (a union that keeps each input's material).

    pip install ./crates/surftrack-py trimesh      # or pymeshlab
    python examples/python/fix_meshes.py a.ply b.obj --out out/fixed.ply
    python examples/python/fix_meshes.py            # built-in overlapping copies

Each input becomes material 1, 2, ... (inside) against the outside 0; where they
overlap, `fix` cuts them along each other and the overlaps become interfaces.
"""

import argparse
import os

import numpy as np

import surftrack


def load(path):
    """(vertices, triangles) of a file through trimesh, else pymeshlab, else surftrack."""
    try:
        import trimesh

        m = trimesh.load(path, force="mesh", process=True)
        return np.asarray(m.vertices, dtype=np.float64), np.asarray(m.faces)
    except ImportError:
        pass
    try:
        import pymeshlab

        ms = pymeshlab.MeshSet()
        ms.load_new_mesh(path)
        m = ms.current_mesh()
        return m.vertex_matrix().astype(np.float64), m.face_matrix()
    except ImportError:
        pass
    m = surftrack.Mesh.read(path)
    return m.vertices, m.triangles


def combine(inputs):
    """One labelled mesh from closed outward-oriented surfaces, material k for input k."""
    parts, offset = [], 0
    for k, (v, f) in enumerate(inputs, start=1):
        labels = np.tile([0, k], (len(f), 1))  # front (the normal's side) is the outside
        parts.append((v, f + offset, labels))
        offset += len(v)
    return surftrack.Mesh(*(np.concatenate(p) for p in zip(*parts)))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("files", nargs="*")
    ap.add_argument("--cell", type=float, default=None, help="grid cell size (default: mean edge)")
    ap.add_argument("--out", default="out/fixed.ply")
    args = ap.parse_args()
    if args.files:
        mesh = combine([load(p) for p in args.files])
    else:
        mesh = surftrack.generate("copies", count=3, resolution=16, seed=1)
    print("input:", mesh.validate(intersections=True))
    fixed, report = surftrack.fix(mesh, cell=args.cell)
    print(report)
    print("output:", fixed.validate(intersections=True))
    os.makedirs(os.path.dirname(args.out) or ".", exist_ok=True)
    fixed.write(args.out)
    print(f"wrote {args.out}; volumes {fixed.volumes()}")


if __name__ == "__main__":
    main()

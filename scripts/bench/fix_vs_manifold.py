#!/usr/bin/env python3
"""`surftrack fix` against Manifold's exact union on rotated copies of a real scanned mesh.

    python3 scripts/bench/fix_vs_manifold.py                # 6 bunny copies, table on stdout
    python3 scripts/bench/fix_vs_manifold.py --copies 3 --repeat 5 --out target/fvm

The Stanford bunny (56,172 triangles, closed) comes from PyPI's `pymeshlab` package, which
ships it as package data (`pymeshlab/tests/sample_meshes/bunny.obj`); `manifold3d` from
PyPI computes the exact union. Both are installed into a venv under `target/bench-venv`
on the first run (the script then re-runs itself with that venv's interpreter), so the
only requirements are Python 3 with `venv`, network access to PyPI once, and cargo.

Steps, all in one session on the same machine:
1. `cargo build --release -p bench-harness --bin surftrack` (a no-op when up to date; `--surftrack BIN`
   skips it);
2. `surftrack generate copies --mesh bunny.obj --count K --seed S`: K copies rotated about
   the bunny's vertex centroid, copy i carrying label i (the harness's own rotations);
3. Manifold: every copy as a `Manifold` (from a float64 `Mesh64`, the same coordinates),
   then `batch_boolean(..., Add)`; best of `--repeat` runs;
4. `surftrack fix copies.ply union.ply --json` (release; best of `--repeat-fix` runs): the
   stage seconds from its record, total = their sum (reading and writing files excluded,
   as Manifold's time excludes them); the wall time of the process is printed too;
5. checks of fix's output: `surftrack validate --intersections` (exact self-intersection
   check) in a separate process; every label 0..K present in the output file; volume per
   label; the total enclosed volume against Manifold's union volume; with
   `--determinism`, the output of a one-thread run is byte-identical.

Writes `results.json` and `table.md` in `--out` (default `target/fix-vs-manifold`) and
prints the table; the mesh it copied is left there too, as `base` plus its extension
(`base.obj` for the bunny), for other commands (`surftrack bench scaling --mesh`). Exit code 0 when every check passed, 1 otherwise.
Not part of CI (it needs PyPI and takes about a minute).
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import struct
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
VENV = ROOT / "target" / "bench-venv"
# Versions this script was written against; newer ones should work too.
REQUIREMENTS = ["pymeshlab==2025.7.post1", "manifold3d==3.5.4", "numpy"]


def ensure_venv() -> None:
    """Re-run this script inside target/bench-venv, creating it first if needed."""
    try:
        import manifold3d  # noqa: F401
        import numpy  # noqa: F401
        import pymeshlab  # noqa: F401

        return
    except ImportError:
        pass
    python = VENV / "bin" / "python"
    if Path(sys.prefix).resolve() == VENV.resolve():
        # Already inside: the install itself must have failed or been partial.
        subprocess.check_call([str(python), "-m", "pip", "install", "--quiet", *REQUIREMENTS])
    else:
        if not python.exists():
            print(f"creating {VENV} (pymeshlab, manifold3d, numpy from PyPI)", file=sys.stderr)
            subprocess.check_call([sys.executable, "-m", "venv", str(VENV)])
        subprocess.check_call([str(python), "-m", "pip", "install", "--quiet", *REQUIREMENTS])
    os.execv(str(python), [str(python), __file__, *sys.argv[1:]])


def bunny_path() -> Path:
    """The Stanford bunny inside the pymeshlab package (package data of its tests)."""
    import importlib.util

    spec = importlib.util.find_spec("pymeshlab")
    if spec is None or spec.origin is None:
        raise SystemExit("pymeshlab is not installed")
    path = Path(spec.origin).parent / "tests" / "sample_meshes" / "bunny.obj"
    if not path.exists():
        raise SystemExit(f"no bunny in this pymeshlab: {path} missing; pass --mesh FILE")
    return path


def read_ply(path: Path):
    """Positions (n×3 float64), triangles (m×3 int64), labels (m×2: front, back) of a
    binary little-endian PLY as `surftrack ... --binary` writes it."""
    import numpy as np

    data = path.read_bytes()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode("ascii").splitlines()
    if "format binary_little_endian 1.0" not in header:
        raise SystemExit(f"{path}: expected binary little-endian PLY")
    counts = {}
    for line in header:
        parts = line.split()
        if parts[:1] == ["element"]:
            counts[parts[1]] = int(parts[2])
    face_props = header[header.index(f"element face {counts['face']}") + 1 :]
    if face_props[:3] != [
        "property list uchar int vertex_indices",
        "property int label_front",
        "property int label_back",
    ]:
        raise SystemExit(f"{path}: unexpected face properties {face_props[:3]}")
    nv, nf = counts["vertex"], counts["face"]
    positions = np.frombuffer(data, dtype="<f8", count=3 * nv, offset=end).reshape(nv, 3)
    face_dtype = np.dtype([("n", "u1"), ("v", "<i4", 3), ("front", "<i4"), ("back", "<i4")])
    faces = np.frombuffer(data, dtype=face_dtype, count=nf, offset=end + 24 * nv)
    if nf and not (faces["n"] == 3).all():
        raise SystemExit(f"{path}: non-triangle face")
    labels = np.stack([faces["front"], faces["back"]], axis=1)
    return positions, faces["v"].astype(np.int64), labels


def label_volumes(positions, tris, labels) -> dict[int, float]:
    """Enclosed volume of every material: the divergence theorem over its boundary,
    with each triangle counted positively for the material its normal points away from."""
    import numpy as np

    a, b, c = (positions[tris[:, i]] for i in range(3))
    signed = np.einsum("ij,ij->i", a, np.cross(b, c)) / 6.0
    volumes: dict[int, float] = {}
    for label in np.unique(labels):
        v = signed[labels[:, 1] == label].sum() - signed[labels[:, 0] == label].sum()
        volumes[int(label)] = float(v)
    return volumes


def manifold_union(positions, tris, labels, copies: int, repeat: int) -> dict:
    """Manifold's exact union of the copies: construction and boolean timed separately."""
    import manifold3d
    import numpy as np

    meshes = []
    for k in range(1, copies + 1):
        outward = (labels[:, 0] == 0) & (labels[:, 1] == k)
        inward = (labels[:, 0] == k) & (labels[:, 1] == 0)
        if outward.sum() + inward.sum() == 0:
            raise SystemExit(f"copy {k}: no triangles between labels 0 and {k}")
        t = np.concatenate([tris[outward], tris[inward][:, ::-1]])
        used, inverse = np.unique(t, return_inverse=True)
        meshes.append(
            manifold3d.Mesh64(
                vert_properties=np.ascontiguousarray(positions[used]),
                tri_verts=np.ascontiguousarray(inverse.reshape(-1, 3).astype(np.uint64)),
            )
        )
    best = None
    for _ in range(repeat):
        t0 = time.perf_counter()
        solids = [manifold3d.Manifold(m) for m in meshes]
        t1 = time.perf_counter()
        for i, s in enumerate(solids):
            if s.status() != manifold3d.Error.NoError:
                raise SystemExit(f"Manifold rejects copy {i + 1}: {s.status()}")
        t2 = time.perf_counter()
        union = manifold3d.Manifold.batch_boolean(solids, manifold3d.OpType.Add)
        n_tri = union.num_tri()  # forces the (lazy) boolean
        t3 = time.perf_counter()
        run = {
            "construct_seconds": t1 - t0,
            "union_seconds": t3 - t2,
            "total_seconds": (t1 - t0) + (t3 - t2),
        }
        if best is None or run["total_seconds"] < best["total_seconds"]:
            best = run
    best.update(
        {
            "triangles_out": int(n_tri),
            "volume": float(union.volume()),
            "status": str(union.status()),
            "genus": int(union.genus()),
            "version": getattr(manifold3d, "__version__", None),
        }
    )
    return best


def run_fix(surftrack: Path, inp: Path, out: Path, repeat: int, threads: int | None) -> dict:
    env = dict(os.environ)
    if threads:
        env["RAYON_NUM_THREADS"] = str(threads)
    best = None
    for _ in range(repeat):
        t0 = time.perf_counter()
        proc = subprocess.run(
            [str(surftrack), "fix", str(inp), str(out), "--json", "--binary"],
            capture_output=True,
            text=True,
            env=env,
        )
        wall = time.perf_counter() - t0
        try:
            record = json.loads(proc.stdout)
        except json.JSONDecodeError:
            sys.stderr.write(proc.stdout + proc.stderr)
            raise SystemExit(f"surftrack fix failed (exit {proc.returncode})")
        if "report" not in record:
            raise SystemExit(f"surftrack fix failed: {record.get('error')}")
        stages = {s["stage"]: s["seconds"] for s in record["report"]["stages"]}
        run = {
            "exit_code": proc.returncode,
            "wall_seconds": wall,
            # The call's own wall time: the reference stage runs beside the others, so the
            # stage seconds add up to more.
            "total_seconds": record["report"]["seconds"],
            "stages": stages,
            "record": record,
        }
        if best is None or run["total_seconds"] < best["total_seconds"]:
            best = run
    return best


def validate(surftrack: Path, path: Path) -> dict:
    t0 = time.perf_counter()
    proc = subprocess.run(
        [str(surftrack), "validate", str(path), "--intersections", "--json"],
        capture_output=True,
        text=True,
    )
    seconds = time.perf_counter() - t0
    try:
        report = json.loads(proc.stdout)
    except json.JSONDecodeError:
        report = {"raw": proc.stdout + proc.stderr}
    return {"valid": proc.returncode == 0, "seconds": seconds, "report": report}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--copies", type=int, default=6, help="rotated copies (6)")
    parser.add_argument("--seed", type=int, default=1, help="seed of the rotations (1)")
    parser.add_argument("--mesh", type=Path, help="a closed mesh instead of the bunny")
    parser.add_argument("--out", type=Path, default=ROOT / "target" / "fix-vs-manifold")
    parser.add_argument("--surftrack", type=Path, help="surftrack binary (default: build release)")
    parser.add_argument("--repeat", type=int, default=3, help="Manifold runs, best kept (3)")
    parser.add_argument("--repeat-fix", type=int, default=1, help="fix runs, best kept (1)")
    parser.add_argument("--threads", type=int, help="RAYON_NUM_THREADS for fix (default: all)")
    parser.add_argument(
        "--determinism",
        action="store_true",
        help="also run fix with 1 thread and compare the output files byte for byte",
    )
    args = parser.parse_args()

    ensure_venv()
    args.out.mkdir(parents=True, exist_ok=True)
    surftrack = args.surftrack
    if surftrack is None:
        subprocess.check_call(
            ["cargo", "build", "--release", "--quiet", "-p", "bench-harness", "--bin", "surftrack"], cwd=ROOT
        )
        surftrack = ROOT / "target" / "release" / "surftrack"
    mesh = args.mesh or bunny_path()
    # A copy of the base mesh beside the results, for `bench scaling --mesh` and the like.
    shutil.copyfile(mesh, args.out / ("base" + mesh.suffix))
    copies_ply = args.out / "copies.ply"
    union_ply = args.out / "union.ply"
    subprocess.check_call(
        [str(surftrack), "generate", "copies", "--mesh", str(mesh), "--count", str(args.copies),
         "--seed", str(args.seed), "--binary", "--out", str(copies_ply)],
        stdout=subprocess.DEVNULL,
    )
    positions, tris, labels = read_ply(copies_ply)
    print(f"input: {args.copies} copies of {mesh.name}, {len(tris)} triangles", file=sys.stderr)

    manifold = manifold_union(positions, tris, labels, args.copies, args.repeat)
    fix = run_fix(surftrack, copies_ply, union_ply, args.repeat_fix, args.threads)
    check = validate(surftrack, union_ply)
    same_with_one_thread = None
    if args.determinism:
        single_ply = args.out / "union-1-thread.ply"
        run_fix(surftrack, copies_ply, single_ply, 1, 1)
        same_with_one_thread = single_ply.read_bytes() == union_ply.read_bytes()
    out_pos, out_tris, out_labels = read_ply(union_ply)
    volumes = label_volumes(out_pos, out_tris, out_labels)
    expected = set(range(args.copies + 1))
    present = set(volumes)
    fix_volume = sum(v for label, v in volumes.items() if label != 0)
    rel = (fix_volume - manifold["volume"]) / manifold["volume"]
    ratio = fix["total_seconds"] / manifold["total_seconds"]
    passed = (
        check["valid"]
        and present == expected
        and fix["exit_code"] == 0
        and same_with_one_thread is not False
    )

    stages = fix["stages"]
    top = sorted(stages.items(), key=lambda kv: -kv[1])[:4]
    lines = [
        f"## `surftrack fix` vs Manifold: {args.copies} rotated copies of {mesh.name} "
        f"({len(tris)} triangles, seed {args.seed})",
        "",
        "| | seconds | triangles out | volume |",
        "| --- | ---: | ---: | ---: |",
        f"| Manifold {manifold['version'] or ''} union (construct {manifold['construct_seconds']:.2f} s "
        f"+ boolean {manifold['union_seconds']:.2f} s) | {manifold['total_seconds']:.2f} | "
        f"{manifold['triangles_out']} | {manifold['volume']:.6f} |",
        f"| surftrack fix (its own wall time; process wall {fix['wall_seconds']:.2f} s) | "
        f"{fix['total_seconds']:.2f} | {len(out_tris)} | {fix_volume:.6f} |",
        "",
        f"fix / Manifold: **{ratio:.2f}×**; fix's total volume {100 * rel:+.4f} % against "
        f"Manifold's exact union",
        "",
        "largest stages: " + ", ".join(f"{k} {v:.2f} s" for k, v in top),
        "",
        f"checks: exact intersection check {'valid' if check['valid'] else 'INVALID'} "
        f"({check['seconds']:.1f} s); labels present {sorted(present)}"
        f"{'' if present == expected else ' (expected ' + str(sorted(expected)) + ')'}",
        *(
            []
            if same_with_one_thread is None
            else [
                "",
                "output with 1 thread: "
                + ("identical" if same_with_one_thread else "DIFFERENT"),
            ]
        ),
        "",
        "| label | volume before (copy) | volume after |",
        "| ---: | ---: | ---: |",
    ]
    before = {v["label"]: v["before"] for v in fix["record"]["report"]["volumes"]}
    for label in sorted(present - {0}):
        lines.append(f"| {label} | {before.get(label, float('nan')):.6f} | {volumes[label]:.6f} |")
    table = "\n".join(lines) + "\n"
    print(table)
    (args.out / "table.md").write_text(table)
    results = {
        "schema": "surftrack.fix-vs-manifold/1",
        "mesh": str(mesh),
        "copies": args.copies,
        "seed": args.seed,
        "triangles_in": int(len(tris)),
        "manifold": manifold,
        "fix": {k: v for k, v in fix.items() if k != "record"},
        "fix_record": fix["record"],
        "ratio": ratio,
        "validation": check,
        "labels_present": sorted(present),
        "volumes": volumes,
        "union_volume_relative_difference": rel,
        "same_with_one_thread": same_with_one_thread,
        "passed": passed,
    }
    (args.out / "results.json").write_text(json.dumps(results, indent=2))
    return 0 if passed else 1


if __name__ == "__main__":
    sys.exit(main())

"""The Python bindings end to end: arrays and files in and out, both backends through a
merge, fix, attributes, options by name, every bad input raising the right exception,
and the GIL released during a step.

Run: pip install ./crates/surftrack-py && pytest crates/surftrack-py/tests
"""

import threading
import time

import numpy as np
import pytest

import surftrack

BACKENDS = ["grid", "collision"]


def two_bubbles(gap=0.1, radius=0.3, resolution=2):
    """Two separate spheres, labels 1 (left) and 2 (right), `gap` apart along x."""
    parts = []
    offset = 0
    for side, label in ((-1.0, 1), (1.0, 2)):
        s = surftrack.generate("sphere", radius=radius, resolution=resolution)
        v = s.vertices + np.array([side * (radius + gap / 2), 0.0, 0.0])
        parts.append((v, s.triangles + offset, np.where(s.labels == 1, label, 0)))
        offset += len(v)
    return surftrack.Mesh(*(np.concatenate(p) for p in zip(*parts)))


def squeeze(vertices, d):
    """Moves every vertex by d towards the plane x = 0."""
    out = vertices.copy()
    out[:, 0] -= np.sign(out[:, 0]) * d
    return out


# ----- arrays and files --------------------------------------------------------------


def test_arrays_round_trip_with_their_dtypes_and_shapes():
    m = surftrack.generate("double-bubble", resolution=8)
    v, t, l = m.vertices, m.triangles, m.labels
    assert v.dtype == np.float64 and v.shape == (m.num_vertices, 3)
    assert t.dtype == np.int64 and t.shape == (m.num_triangles, 3)
    assert l.dtype == np.int64 and l.shape == (m.num_triangles, 2)
    assert set(np.unique(l)) == {0, 1, 2}
    # int32 / uint32 indices and Fortran-ordered float arrays are accepted too.
    back = surftrack.Mesh(np.asfortranarray(v), t.astype(np.int32), l.astype(np.uint32))
    np.testing.assert_array_equal(back.vertices, v)
    np.testing.assert_array_equal(back.triangles, t)
    np.testing.assert_array_equal(back.labels, l)
    assert back.validate().valid


def test_read_stitches_a_triangle_soup_when_asked(tmp_path):
    # A tetrahedron with every face on its own vertices, unlabelled: open as written.
    corners = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float)
    faces = [[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]]
    lines = [f"v {x} {y} {z}" for f in faces for (x, y, z) in corners[f]]
    lines += [f"f {3 * k + 1} {3 * k + 2} {3 * k + 3}" for k in range(4)]
    path = tmp_path / "soup.obj"
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(OSError, match="only one triangle"):
        surftrack.Mesh.read(path)
    m = surftrack.Mesh.read(path, stitch=True)
    assert (m.num_vertices, m.num_triangles) == (4, 4)
    assert m.validate().valid
    assert sorted(map(tuple, m.labels)) == [(0, 1)] * 4


@pytest.mark.parametrize("ext", ["ply", "obj"])
def test_files_round_trip(tmp_path, ext):
    m = surftrack.generate("double-bubble", resolution=8)
    path = tmp_path / f"db.{ext}"
    m.write(path)
    r = surftrack.Mesh.read(str(path))
    assert (r.num_vertices, r.num_triangles) == (m.num_vertices, m.num_triangles)
    # OBJ groups triangles by label pair: compare as sets of labelled triangles.
    def labelled(mesh):
        v = mesh.vertices
        return sorted(
            (tuple(np.round(v[tri].ravel(), 12)), tuple(lab))
            for tri, lab in zip(mesh.triangles, mesh.labels)
        )

    assert labelled(r) == labelled(m)
    for k, vol in m.volumes().items():
        assert r.volumes()[k] == pytest.approx(vol, rel=1e-12, abs=1e-12)


def test_volumes_and_validation_report():
    m = surftrack.generate("double-bubble", resolution=12)
    vols = m.volumes()
    assert vols[1] > 0 and vols[2] > 0
    assert vols[0] == pytest.approx(-(vols[1] + vols[2]))
    report = m.validate(intersections=True)
    assert report.valid and bool(report)
    assert report.counts["self_intersecting_pairs"] == 0
    assert report.offenders == {}
    assert report.triangles == m.num_triangles
    assert report.non_manifold_edges > 0  # the triple curve
    assert "valid" in str(report)


def test_validation_names_the_offenders_of_an_open_mesh():
    m = surftrack.generate("sphere", resolution=1)
    opened = surftrack.Mesh(m.vertices, m.triangles[1:], m.labels[1:])
    report = opened.validate()
    assert not report.valid
    assert report.counts["boundary_edges"] == 3
    assert len(report.offenders["boundary_edges"]) == 3


# ----- tracking ----------------------------------------------------------------------


@pytest.mark.parametrize("backend", BACKENDS)
def test_both_backends_merge_two_bubbles_with_every_mesh_valid(backend):
    tracker = surftrack.Tracker(two_bubbles(), backend=backend)
    assert tracker.backend == backend
    merges = 0
    for _ in range(8):
        report = tracker.advance(squeeze(tracker.vertices, 0.015))
        merges += report.merges
        assert report.triangles == tracker.mesh.num_triangles
        assert report.seconds > 0 and report.stages
        assert tracker.mesh.validate(intersections=True).valid
    assert merges >= 1, f"{backend}: no merge"
    # Merged: one connected surface, so some vertex now has both labels 1 and 2 around it.
    m = tracker.mesh
    wall = (m.labels == [1, 2]).all(axis=1) | (m.labels == [2, 1]).all(axis=1)
    assert wall.any(), f"{backend}: no shared wall between the bubbles"


@pytest.mark.parametrize("backend", BACKENDS)
def test_attributes_survive_a_merge(backend):
    tracker = surftrack.Tracker(two_bubbles(), backend=backend)
    v = tracker.vertices
    side = np.sign(v[:, 0])
    velocity = np.zeros_like(v)
    velocity[:, 0] = -side * 0.015
    tracker.set_attribute("side", side)
    tracker.set_attribute("velocity", velocity)
    assert tracker.attribute_names() == ["side", "velocity"]
    merges = 0
    for _ in range(8):
        vel = tracker.attribute("velocity")
        merges += tracker.advance(tracker.vertices + vel).merges
    assert merges >= 1
    v = tracker.vertices
    side = tracker.attribute("side")
    vel = tracker.attribute("velocity")
    assert side.shape == (len(v),) and vel.shape == (len(v), 3)
    live = np.unique(tracker.mesh.triangles)
    far = live[np.abs(v[live, 0]) > 0.15]
    assert len(far) > 50
    # Away from the contact every vertex still knows its bubble and its velocity.
    np.testing.assert_allclose(side[far], np.sign(v[far, 0]), atol=1e-9)
    np.testing.assert_allclose(vel[far, 0], -np.sign(v[far, 0]) * 0.015, atol=1e-9)
    assert np.isfinite(vel[live]).all() and np.abs(vel[live]).max() <= 0.015 + 1e-12
    assert tracker.remove_attribute("side") and not tracker.remove_attribute("side")
    with pytest.raises(KeyError):
        tracker.attribute("side")


def test_fix_repairs_overlapping_copies():
    overlapping = surftrack.generate("copies", count=3, resolution=8, seed=2)
    assert not overlapping.validate(intersections=True).valid
    fixed, report = surftrack.fix(overlapping)
    assert report.valid and report.validation.valid
    assert fixed.validate(intersections=True).valid
    assert report.triangles_in == overlapping.num_triangles
    assert report.triangles_out == fixed.num_triangles
    assert 0.0 < report.untouched_fraction < 1.0 and report.flawed_cells > 0
    # Options by name reach the pipeline: a coarser cell changes the result. At twice the
    # cell the union loses a few per cent of its volume: an error unless allowed.
    with pytest.raises(surftrack.TrackError, match="loses material"):
        surftrack.fix(overlapping, cell=2 * report.cell_size, resampling="global")
    coarse, r2 = surftrack.fix(
        overlapping, cell=2 * report.cell_size, resampling="global", allow_loss=True
    )
    assert r2.cell_size == pytest.approx(2 * report.cell_size)
    assert coarse.validate(intersections=True).valid


def test_a_nested_part_is_named_refused_and_relabelled_by_fix():
    # Two parts made separately, each against the outside 0: the inner one says 0
    # around it although it lies in material 1.
    outer = surftrack.generate("sphere", radius=1.0, resolution=2)
    inner = surftrack.generate("sphere", radius=0.5, resolution=2)
    inner_labels = np.array(inner.labels)
    inner_labels[inner_labels == 1] = 2
    nested = surftrack.Mesh(
        np.vstack([outer.vertices, inner.vertices]),
        np.vstack([outer.triangles, np.array(inner.triangles) + len(outer.vertices)]),
        np.vstack([outer.labels, inner_labels]),
    )
    report = nested.validate()
    assert not report.valid and report.counts["misplaced_shells"] == 1
    assert "lies in material 1" in str(report)
    for backend in BACKENDS:
        with pytest.raises(ValueError, match="misplaced"):
            surftrack.Tracker(nested, backend)
    fixed, fix_report = surftrack.fix(nested)
    assert fixed.validate(intersections=True).valid
    relabelled = fix_report.as_dict()["relabelled"]
    assert [(r["from"], r["to"]) for r in relabelled] == [(0, 1)]
    volumes = fixed.volumes()
    assert volumes[2] == pytest.approx(inner.volumes()[1], rel=1e-12)
    assert volumes[1] == pytest.approx(outer.volumes()[1] - inner.volumes()[1], rel=1e-12)


def test_options_by_name_and_their_errors():
    m = surftrack.generate("double-bubble", resolution=8)
    surftrack.Tracker(m, "grid", cell_size=0.1, seed=3, **{"flaws.deep_cell_test": False})
    surftrack.Tracker(m, "grid", flaws__deep_cell_test=False, resampling="global")
    surftrack.Tracker(m, "collision", merge=False, **{"collision.t1": False})
    with pytest.raises(ValueError, match="resampling"):
        surftrack.Tracker(m, "grid", resampel="global")
    with pytest.raises(ValueError, match="resampling"):
        surftrack.Tracker(m, "grid", resampling="sideways")
    with pytest.raises(ValueError, match="merge"):
        surftrack.Tracker(m, "collision", merj=True)
    with pytest.raises(ValueError, match="grid"):
        surftrack.Tracker(m, "levelset")
    names = surftrack.option_names("grid")
    assert any(n.startswith("resampling = ") for n in names)
    assert any(n.startswith("merge = ") for n in surftrack.option_names("collision"))


def test_generate_names_the_known_scenes():
    with pytest.raises(ValueError, match="double-bubble"):
        surftrack.generate("no-such-scene")


# ----- bad input ----------------------------------------------------------------------


def test_bad_arrays_raise_value_error():
    m = surftrack.generate("sphere", resolution=1)
    v, t, l = m.vertices, m.triangles, m.labels
    cases = {
        "vertices shape": (v[:, :2], t, l),
        "vertices dtype": (v.astype(complex), t, l),
        "vertices strings": (v.astype(str), t, l),
        "NaN": (np.where(np.arange(len(v))[:, None] == 3, np.nan, v), t, l),
        "inf": (np.where(np.arange(len(v))[:, None] == 2, np.inf, v), t, l),
        "triangles dtype": (v, t.astype(float), l),
        "triangles shape": (v, t[:, :2], l),
        "index out of range": (v, np.where(t == 0, len(v), t), l),
        "negative index": (v, np.where(t == 0, -1, t), l),
        "labels dtype": (v, t, l.astype(bool)),
        "labels length": (v, t, l[:-1]),
        "negative label": (v, t, l - 1),
    }
    for name, args in cases.items():
        with pytest.raises(ValueError):
            surftrack.Mesh(*args)
            pytest.fail(name)


def test_invalid_meshes_are_refused_by_trackers():
    m = surftrack.generate("double-bubble", resolution=8)
    labels = m.labels.copy()
    labels[0] = [labels[0][0], 5]  # an inconsistent wedge
    bad = surftrack.Mesh(m.vertices, m.triangles, labels)
    assert not bad.validate().valid
    assert bad.validate().counts["inconsistent_edges"] > 0
    for backend in BACKENDS:
        with pytest.raises(ValueError, match="invalid input"):
            surftrack.Tracker(bad, backend)
    with pytest.raises(ValueError):
        surftrack.fix(surftrack.Mesh(m.vertices, m.triangles[1:], m.labels[1:]))


@pytest.mark.parametrize("backend", BACKENDS)
def test_bad_proposals_and_failed_steps_leave_the_tracker_usable(backend):
    tracker = surftrack.Tracker(surftrack.generate("double-bubble", resolution=8), backend)
    before = tracker.vertices
    n = len(before)
    for bad in (before[:-1], before[:, :2], before.astype(str), np.full_like(before, np.nan)):
        with pytest.raises(ValueError):
            tracker.advance(bad)
    with pytest.raises(ValueError):
        tracker.set_attribute("x", np.zeros(n + 1))
    with pytest.raises(ValueError):
        tracker.set_attribute("x", np.full(n, np.nan))
    np.testing.assert_array_equal(tracker.vertices, before)
    if backend == "collision":
        # A teleport is beyond the collision backend's displacement limit: the step fails.
        with pytest.raises(surftrack.TrackError, match="resolve"):
            tracker.advance(before + 100.0)
    else:
        # A step over an impossible time budget fails in its first stage.
        budget = surftrack.Tracker(tracker.mesh, "grid", time_budget=1e-9)
        kept = budget.vertices
        with pytest.raises(surftrack.TrackError, match="budget"):
            budget.advance(kept * 1.01)
        np.testing.assert_array_equal(budget.vertices, kept)
        assert budget.mesh.validate().valid
    np.testing.assert_array_equal(tracker.vertices, before)
    assert isinstance(surftrack.TrackError("x"), RuntimeError)
    # Still usable: a good step goes through.
    report = tracker.advance(before * 1.01)
    assert report.triangles > 0 and tracker.mesh.validate(intersections=True).valid


def test_file_errors_raise_os_error(tmp_path):
    with pytest.raises(OSError, match="missing.ply"):
        surftrack.Mesh.read(tmp_path / "missing.ply")
    (tmp_path / "junk.ply").write_text("not a ply file\n")
    with pytest.raises(OSError):
        surftrack.Mesh.read(tmp_path / "junk.ply")
    m = surftrack.generate("sphere", resolution=1)
    with pytest.raises(OSError):
        m.write(tmp_path / "no" / "such" / "dir" / "m.ply")
    with pytest.raises(OSError):
        m.write(tmp_path / "m.stl")


# ----- threads and docs ---------------------------------------------------------------


def test_the_gil_is_released_during_a_step():
    # Finer meshes until one step takes long enough to tell (bounded: four sizes).
    for resolution in (24, 48, 96, 192):
        tracker = surftrack.Tracker(surftrack.generate("double-bubble", resolution=resolution))
        proposed = tracker.vertices * 1.02
        ticks = []
        done = threading.Event()

        def step():
            tracker.advance(proposed)
            done.set()

        worker = threading.Thread(target=step)
        start = time.perf_counter()
        worker.start()
        while not done.is_set():
            ticks.append(time.perf_counter())
            time.sleep(0.001)
        worker.join()
        elapsed = time.perf_counter() - start
        if elapsed > 0.05:
            break
    assert elapsed > 0.05, "no step long enough to tell"
    # Python kept running while Rust stepped: ticks spread over the step (with the GIL
    # held there would be one or two, before and after).
    assert len(ticks) > 10, f"only {len(ticks)} ticks in {elapsed:.3f} s"
    gaps = np.diff(ticks)
    assert gaps.max() < 0.5 * elapsed, f"a {gaps.max():.3f} s gap in a {elapsed:.3f} s step"


def test_help_teaches_the_api():
    doc = surftrack.Tracker.__doc__
    for word in ("advance", "backend", "options", "set_attribute", "TrackError"):
        assert word in doc, word
    assert "float64" in surftrack.Mesh.__doc__
    assert "overlap" in surftrack.fix.__doc__
    assert surftrack.Tracker.advance.__doc__


# ----- the examples ---------------------------------------------------------------------

EXAMPLES = __import__("pathlib").Path(__file__).resolve().parents[3] / "examples" / "python"


def run_example(name, *args):
    import subprocess
    import sys

    out = subprocess.run(
        [sys.executable, str(EXAMPLES / name), *map(str, args)],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert out.returncode == 0, out.stderr
    return out.stdout


def test_the_simulator_example_tracks_and_writes_frames(tmp_path):
    stdout = run_example("simulate.py", "--steps", 3, "--out", tmp_path)
    assert "step   3" in stdout and "mesh valid" in stdout
    frames = sorted(p.name for p in tmp_path.glob("frame_*.ply"))
    assert frames == ["frame_0000.ply", "frame_0001.ply", "frame_0002.ply", "frame_0003.ply"]
    assert surftrack.Mesh.read(tmp_path / "frame_0003.ply").validate().valid


def test_the_fix_example_unions_overlapping_files(tmp_path):
    paths = []
    for k, shift in enumerate((0.0, 0.5)):
        s = surftrack.generate("sphere", resolution=3, radius=0.6)
        moved = surftrack.Mesh(s.vertices + [shift, 0, 0], s.triangles, s.labels)
        paths.append(tmp_path / f"s{k}.obj")
        moved.write(paths[-1])
    out = tmp_path / "fixed.ply"
    stdout = run_example("fix_meshes.py", *paths, "--out", out)
    assert "output: mesh valid" in stdout
    fixed = surftrack.Mesh.read(out)
    assert fixed.validate(intersections=True).valid
    assert set(fixed.volumes()) == {0, 1, 2}

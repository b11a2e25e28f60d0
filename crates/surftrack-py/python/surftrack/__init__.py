"""surftrack: multi-material surface tracking on labelled non-manifold triangle meshes.

A mesh is numpy arrays: float64 vertices (n, 3), int triangles (m, 3) and int labels
(m, 2) giving [front, back] materials per triangle (label 0 is the outside).

    import numpy as np, surftrack
    mesh = surftrack.generate("double-bubble")
    tracker = surftrack.Tracker(mesh, backend="grid")       # or "collision"
    for step in range(10):
        v = tracker.vertices
        report = tracker.advance(v * 1.01)                   # your motion here
    assert tracker.mesh.validate().valid

Entry points: Mesh, Tracker, StepReport, ValidationReport, fix, generate, option_names,
TrackError. See help(surftrack.Tracker).
"""

from ._surftrack import (
    BACKENDS,
    FixReport,
    Mesh,
    StepReport,
    TrackError,
    Tracker,
    ValidationReport,
    fix,
    generate,
    option_names,
)

__all__ = [
    "BACKENDS",
    "FixReport",
    "Mesh",
    "StepReport",
    "TrackError",
    "Tracker",
    "ValidationReport",
    "fix",
    "generate",
    "option_names",
]

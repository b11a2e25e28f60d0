//! Helpers shared by the remeshing integration tests.
// Each test crate includes this module and may use only some of it.
#![allow(dead_code)]

use std::collections::BTreeMap;

use mesh_core::geometry::label_volumes;
use mesh_core::remesh::ImproveReport;
use mesh_core::validate::{ValidateOptions, validate};
use mesh_core::{Label, LabeledMesh};

/// Validates with the exact intersection layer.
pub fn assert_valid(mesh: &LabeledMesh, what: &str) {
    let report = validate(mesh, &ValidateOptions::with_intersections());
    assert!(report.is_valid(), "{what}: {report:?}");
}

/// Every label's volume changed by at most the report's bound (which is ≤ Ω per edit).
pub fn assert_volumes(before: &BTreeMap<Label, f64>, mesh: &LabeledMesh, r: &ImproveReport) {
    let after = label_volumes(mesh);
    let edits = r.flip.done + r.collapse.done + r.smooth.done + r.split.done;
    assert!(r.volume_change_bound <= r.max_volume_change * edits as f64 + 1e-12);
    for (l, v) in before {
        let change = (after.get(l).copied().unwrap_or(0.0) - v).abs();
        assert!(
            change <= r.volume_change_bound + 1e-9,
            "label {l}: volume change {change} > bound {}",
            r.volume_change_bound
        );
    }
}

//! `surftrack.Tracker` and `surftrack.StepReport`, and options by name.

use std::collections::HashSet;
use std::sync::Mutex;

use bench_harness::options::{OptionsBuilder, RunOptions, option_lines};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use surftrack::mesh_core::{StageTiming, StepReport};
use surftrack::{Backend, Tracker};

use crate::convert::{
    attribute_values, backend_error, f64_array, f64_vector, guarded, points, to_json, track_error,
    value_error,
};
use crate::mesh::PyMesh;

/// Stage timings as `[(stage, seconds), ...]`.
pub fn stage_list(stages: &[StageTiming]) -> Vec<(&'static str, f64)> {
    stages.iter().map(|s| (s.stage, s.seconds)).collect()
}

/// Applies keyword options to `builder`: each name is a `--set` path, relative to the
/// `table` (`grid` or `collision`) unless it starts with `grid.`, `collision.` or
/// `flow.`; `__` stands for `.` so that nested options can be plain keywords.
pub fn apply_options(
    builder: &mut OptionsBuilder,
    table: &str,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<()> {
    let Some(options) = options else {
        return Ok(());
    };
    for (key, value) in options.iter() {
        let key: String = key.extract()?;
        let dotted = key.replace("__", ".");
        let path = if ["grid.", "collision.", "flow."]
            .iter()
            .any(|p| dotted.starts_with(p))
        {
            dotted
        } else {
            format!("{table}.{dotted}")
        };
        let value = to_json(&value, &path)?;
        builder.set_value(&path, value).map_err(value_error)?;
    }
    Ok(())
}

/// option_names(backend=None) -> [str]: every option as "path = default" (the paths
/// `Tracker` and `fix` take by keyword, relative to the backend's table).
#[pyfunction]
#[pyo3(signature = (backend = None))]
pub fn option_names(backend: Option<&str>) -> PyResult<Vec<String>> {
    let lines = option_lines(&RunOptions::default());
    let Some(backend) = backend else {
        return Ok(lines);
    };
    let b: Backend = backend.parse().map_err(value_error)?;
    let prefix = format!("{}.", b.name());
    Ok(lines
        .into_iter()
        .filter_map(|l| l.strip_prefix(&prefix).map(str::to_string))
        .collect())
}

/// What one step did: stage timings, topology events, sizes.
#[pyclass(name = "StepReport", module = "surftrack", frozen)]
pub struct PyStepReport {
    report: StepReport,
}

#[pymethods]
impl PyStepReport {
    /// [(stage, seconds), ...] in pipeline order.
    #[getter]
    fn stages(&self) -> Vec<(&'static str, f64)> {
        stage_list(&self.report.stages)
    }

    /// Seconds over all stages.
    #[getter]
    fn seconds(&self) -> f64 {
        self.report.total_seconds()
    }

    /// {"merges", "splits", "t1", "t2", "remeshing_edits"}: counts of the step's events.
    #[getter]
    fn events<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let e = &self.report.events;
        let dict = PyDict::new(py);
        dict.set_item("merges", e.merges)?;
        dict.set_item("splits", e.splits)?;
        dict.set_item("t1", e.t1)?;
        dict.set_item("t2", e.t2)?;
        dict.set_item("remeshing_edits", e.remeshing_edits)?;
        Ok(dict)
    }

    /// Regions joined this step.
    #[getter]
    fn merges(&self) -> u64 {
        self.report.events.merges
    }

    /// Regions pulled apart this step.
    #[getter]
    fn splits(&self) -> u64 {
        self.report.events.splits
    }

    /// Live vertices after the step.
    #[getter]
    fn vertices(&self) -> usize {
        self.report.vertices
    }

    /// Live triangles after the step.
    #[getter]
    fn triangles(&self) -> usize {
        self.report.triangles
    }

    /// Sub-steps (time-step halving in the collision backend; 1 otherwise).
    #[getter]
    fn substeps(&self) -> u32 {
        self.report.substeps
    }

    fn __repr__(&self) -> String {
        let e = &self.report.events;
        format!(
            "<StepReport {} triangles, {} merges, {} splits, {} T1, {} T2, {:.3} s>",
            self.report.triangles,
            e.merges,
            e.splits,
            e.t1,
            e.t2,
            self.report.total_seconds()
        )
    }
}

/// The tracker and which attributes were set as 1-D arrays (to hand them back so).
struct State {
    tracker: Tracker,
    one_d: HashSet<String>,
}

/// Tracker(mesh, backend="grid", **options): a surface tracker around a valid mesh.
///
/// Each time step, propose a position for every vertex row of `tracker.vertices` (your
/// simulation's motion) and call `advance(proposed)`: the tracker resolves the topology
/// the motion implies (merges, splits, T1/T2), improves the mesh, and `tracker.mesh` is
/// again closed, consistently labelled and free of self-intersections. Vertex rows
/// change with every step: read `tracker.vertices` (or `tracker.mesh`) after each.
///
/// backend: "grid" (Heiss-Synak et al. 2024: lets the mesh tangle, repairs on a grid;
/// any motion) or "collision" (Los Topos / El Topo: collision-safe, motion must be a
/// trajectory).
///
/// options: every option of the backend by name, as the CLI's `--set` paths relative to
/// the backend's table: `cell_size=0.05`, `seed=3`, `time_budget=2.0`,
/// `**{"flaws.deep_cell_test": False}` or `flaws__deep_cell_test=False`; full paths
/// (`"grid.resampling"`) work too. `option_names(backend)` lists them with defaults.
/// Unknown names raise ValueError listing the known ones.
///
/// Per-vertex attributes (velocities, ...) follow the mesh through every step:
/// `set_attribute("velocity", array)`, then `attribute("velocity")` after a step.
///
/// Errors: ValueError for a bad mesh, option or array (shape, dtype, NaN); TrackError
/// when a step fails, after which the tracker holds the mesh from before the step.
/// The GIL is released while a step runs.
#[pyclass(name = "Tracker", module = "surftrack", frozen)]
pub struct PyTracker {
    state: Mutex<State>,
}

impl PyTracker {
    /// The state, also after a panic in another call (which left it unchanged: steps
    /// work on copies).
    fn lock(&self) -> std::sync::MutexGuard<'_, State> {
        self.state.lock().unwrap_or_else(|e| e.into_inner())
    }
}

#[pymethods]
impl PyTracker {
    #[new]
    #[pyo3(signature = (mesh, backend = "grid", **options))]
    fn py_new(
        py: Python<'_>,
        mesh: PyRef<'_, PyMesh>,
        backend: &str,
        options: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<Self> {
        let backend: Backend = backend.parse().map_err(value_error)?;
        let mut builder = OptionsBuilder::default();
        apply_options(&mut builder, backend.name(), options)?;
        let full = builder.build().map_err(value_error)?.backend_options();
        let mesh = (*mesh.mesh).clone();
        let tracker = py.detach(|| {
            guarded("Tracker()", || {
                Tracker::new(backend, mesh, &full).map_err(backend_error)
            })
        })?;
        Ok(Self {
            state: Mutex::new(State {
                tracker,
                one_d: HashSet::new(),
            }),
        })
    }

    /// "grid" or "collision".
    #[getter]
    fn backend(&self) -> String {
        self.lock().tracker.name().to_string()
    }

    /// The current mesh (a copy).
    #[getter]
    fn mesh(&self) -> PyMesh {
        PyMesh::new_from(self.lock().tracker.mesh().clone())
    }

    /// The current vertex positions, float64 (n, 3), one row per vertex slot: the shape
    /// `advance` expects (rows of unused slots are ignored). Cheaper than `mesh.vertices`.
    #[getter]
    fn vertices<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let flat = {
            let state = self.lock();
            state
                .tracker
                .mesh()
                .positions()
                .iter()
                .flat_map(|p| p.to_array())
                .collect()
        };
        f64_array(py, 3, flat)
    }

    /// advance(proposed) -> StepReport: one step towards `proposed`, float64 (n, 3), one
    /// row per row of `vertices`. Raises ValueError for a wrong shape, dtype or a NaN,
    /// TrackError if the step fails; either way the mesh and attributes are unchanged.
    fn advance(&self, py: Python<'_>, proposed: &Bound<'_, PyAny>) -> PyResult<PyStepReport> {
        let proposed = points(proposed, "proposed")?;
        py.detach(|| {
            guarded("Tracker.advance", || {
                let mut state = self.lock();
                let report = state.tracker.advance(&proposed).map_err(track_error)?;
                Ok(PyStepReport { report })
            })
        })
    }

    /// set_attribute(name, values): per-vertex values, shape (n,) or (n, k), one row per
    /// row of `vertices`, carried through every later step (kept on surviving vertices,
    /// interpolated or transferred to new ones). Replaces an attribute of that name.
    fn set_attribute(&self, name: &str, values: &Bound<'_, PyAny>) -> PyResult<()> {
        let what = format!("attribute `{name}`");
        let (n, dim, one_d, flat) = attribute_values(values, &what)?;
        let mut state = self.lock();
        let slots = state.tracker.mesh().vertex_capacity();
        if n != slots {
            return Err(PyValueError::new_err(format!(
                "{what}: expected {slots} rows (one per row of `vertices`), got {n}"
            )));
        }
        guarded("Tracker.set_attribute", || {
            state
                .tracker
                .set_attribute(name, dim, &flat)
                .map_err(value_error)
        })?;
        if one_d {
            state.one_d.insert(name.to_string());
        } else {
            state.one_d.remove(name);
        }
        Ok(())
    }

    /// attribute(name) -> array: the values for the current vertex rows ((n,) or (n, k)
    /// as set). Raises KeyError for an unknown name.
    fn attribute<'py>(&self, py: Python<'py>, name: &str) -> PyResult<Bound<'py, PyAny>> {
        let state = self.lock();
        let Some((dim, values)) = state.tracker.attribute(name) else {
            let known: Vec<&str> = state
                .tracker
                .attribute_names()
                .iter()
                .map(|(n, _)| *n)
                .collect();
            return Err(pyo3::exceptions::PyKeyError::new_err(format!(
                "no attribute `{name}` (set: {known:?})"
            )));
        };
        if state.one_d.contains(name) {
            Ok(f64_vector(py, values))
        } else {
            f64_array(py, dim, values)
        }
    }

    /// Names of the attributes set.
    fn attribute_names(&self) -> Vec<String> {
        self.lock()
            .tracker
            .attribute_names()
            .into_iter()
            .map(|(n, _)| n.to_string())
            .collect()
    }

    /// remove_attribute(name) -> bool: stops carrying `name`; False if it was not set.
    fn remove_attribute(&self, name: &str) -> bool {
        let mut state = self.lock();
        state.one_d.remove(name);
        state.tracker.remove_attribute(name)
    }

    fn __repr__(&self) -> String {
        let state = self.lock();
        let mesh = state.tracker.mesh();
        format!(
            "Tracker(backend={:?}, {} vertices, {} triangles)",
            state.tracker.name(),
            mesh.num_vertices(),
            mesh.num_triangles()
        )
    }
}

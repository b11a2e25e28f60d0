//! `surftrack.Mesh` and `surftrack.ValidationReport`, `generate` and `fix`.

use std::path::PathBuf;
use std::sync::Arc;

use bench_harness::options::OptionsBuilder;
use bench_harness::scenes::{SceneOptions, build_scene};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use surftrack::grid_tracker::{FixError, FixOptions, FixReport, fix_with};
use surftrack::mesh_core::geometry::label_volumes;
use surftrack::mesh_core::io::{ReadOptions, read_mesh_with, write_mesh};
use surftrack::mesh_core::validate::{ValidateOptions, ValidationReport, validate};
use surftrack::mesh_core::{LabeledMesh, MeshError};

use crate::convert::{
    TrackError, f64_array, from_json, guarded, index_array, indices, os_error, points, to_json,
    value_error,
};
use crate::tracker::{apply_options, stage_list};

/// A labelled triangle mesh: vertices (float64, shape (n, 3)), triangles (int64, (m, 3),
/// indices into the vertices) and labels (int64, (m, 2): [front, back] per triangle; the
/// front is the material the normal (v1-v0)x(v2-v0) points into, label 0 the outside).
///
/// Meshes are values: the arrays returned are copies, and a Mesh never changes. Arrays
/// passed in are checked (shape, dtype, finite values, index range), never trusted.
#[pyclass(name = "Mesh", module = "surftrack", frozen)]
#[derive(Clone)]
pub struct PyMesh {
    pub mesh: Arc<LabeledMesh>,
}

impl PyMesh {
    pub fn new_from(mesh: LabeledMesh) -> Self {
        Self {
            mesh: Arc::new(mesh),
        }
    }
}

fn mesh_error(e: MeshError) -> PyErr {
    value_error(e)
}

#[pymethods]
impl PyMesh {
    /// Mesh(vertices, triangles, labels): builds a mesh from arrays.
    ///
    /// Raises ValueError on a wrong shape or dtype, a non-finite coordinate, an index out
    /// of range, or mismatched lengths. Whether the mesh is closed and consistently
    /// labelled is what `validate()` reports (a Tracker requires it).
    #[new]
    fn py_new(
        vertices: &Bound<'_, PyAny>,
        triangles: &Bound<'_, PyAny>,
        labels: &Bound<'_, PyAny>,
    ) -> PyResult<Self> {
        let positions = points(vertices, "vertices")?;
        let tris = indices::<3>(triangles, "triangles")?;
        let labels = indices::<2>(labels, "labels")?;
        let mesh = LabeledMesh::from_raw(positions, &tris, &labels).map_err(mesh_error)?;
        Ok(Self::new_from(mesh))
    }

    /// Mesh.read(path, stitch=False): reads a PLY (labels as face properties
    /// label_front/label_back) or OBJ (usemtl label_<front>_<back>) file; a file without
    /// labels must be a closed surface and reads as inside 1, outside 0. With stitch=True,
    /// vertices repeated at one position on open edges (every face on its own vertices,
    /// as STL-style exporters write them) become one first, and open edges are split at
    /// the open vertices lying on them (T-junctions). Raises OSError naming the
    /// problem.
    #[staticmethod]
    #[pyo3(signature = (path, stitch = false))]
    fn read(py: Python<'_>, path: PathBuf, stitch: bool) -> PyResult<Self> {
        let name = path.display().to_string();
        let options = ReadOptions {
            stitch,
            ..ReadOptions::default()
        };
        py.detach(|| {
            guarded("Mesh.read", || {
                read_mesh_with(&path, &options)
                    .map(Self::new_from)
                    .map_err(|e| os_error(&name, e))
            })
        })
    }

    /// mesh.write(path): writes PLY or OBJ by extension (dead vertex slots dropped).
    fn write(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        let name = path.display().to_string();
        let mesh = self.mesh.clone();
        py.detach(|| {
            guarded("Mesh.write", || {
                write_mesh(&mesh, &path).map_err(|e| os_error(&name, e))
            })
        })
    }

    /// Vertex positions, float64 (n, 3), one row per vertex slot (a tracker's mesh may
    /// have unused slots, referenced by no triangle; `compacted()` drops them).
    #[getter]
    fn vertices<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let flat = self
            .mesh
            .positions()
            .iter()
            .flat_map(|p| p.to_array())
            .collect();
        f64_array(py, 3, flat)
    }

    /// Triangles, int64 (m, 3), vertex indices (live triangles only).
    #[getter]
    fn triangles<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let rows: Vec<[u32; 3]> = self
            .mesh
            .triangles()
            .map(|t| self.mesh.tri(t).map(|v| v.raw()))
            .collect();
        index_array(py, &rows)
    }

    /// Labels, int64 (m, 2), [front, back] per triangle, in the order of `triangles`.
    #[getter]
    fn labels<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let rows: Vec<[u32; 2]> = self
            .mesh
            .triangles()
            .map(|t| self.mesh.labels(t).map(|l| l.raw()))
            .collect();
        index_array(py, &rows)
    }

    /// Live vertices.
    #[getter]
    fn num_vertices(&self) -> usize {
        self.mesh.num_vertices()
    }

    /// Live triangles.
    #[getter]
    fn num_triangles(&self) -> usize {
        self.mesh.num_triangles()
    }

    /// The same mesh without unused vertex slots (vertices renumbered in order).
    fn compacted(&self) -> Self {
        let mut mesh = (*self.mesh).clone();
        mesh.compact();
        Self::new_from(mesh)
    }

    /// validate(intersections=True) -> ValidationReport: topology (closed, no degenerate
    /// or duplicate triangles), labels (front != back, consistent around every edge),
    /// geometry (finite, no zero-area triangle), placement (every surface component has
    /// outside it the material it lies in: "misplaced_shells") and, if asked, exact
    /// self-intersections.
    #[pyo3(signature = (intersections = true))]
    fn validate(&self, py: Python<'_>, intersections: bool) -> PyResult<PyValidationReport> {
        let mesh = self.mesh.clone();
        let options = ValidateOptions {
            intersections,
            ..ValidateOptions::default()
        };
        py.detach(|| {
            guarded("Mesh.validate", || {
                Ok(PyValidationReport {
                    report: validate(&mesh, &options),
                })
            })
        })
    }

    /// volumes() -> {label: volume}: the volume each label encloses (the outside, label
    /// 0, gets minus the sum of the others).
    fn volumes<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let dict = PyDict::new(py);
        for (label, v) in label_volumes(&self.mesh) {
            dict.set_item(label.raw(), v)?;
        }
        Ok(dict)
    }

    fn __repr__(&self) -> String {
        format!(
            "Mesh({} vertices, {} triangles, labels {:?})",
            self.mesh.num_vertices(),
            self.mesh.num_triangles(),
            self.mesh
                .label_set()
                .iter()
                .map(|l| l.raw())
                .collect::<Vec<_>>()
        )
    }
}

/// What `Mesh.validate` found: `valid`, sizes, and per category of defect the exact count
/// (`counts`) and the first offending ids (`offenders`).
#[pyclass(name = "ValidationReport", module = "surftrack", frozen)]
pub struct PyValidationReport {
    pub report: ValidationReport,
}

impl PyValidationReport {
    /// The report as JSON (the CLI's `validate --json` form).
    fn tree(&self) -> serde_json::Value {
        serde_json::to_value(&self.report).unwrap_or_default()
    }
}

#[pymethods]
impl PyValidationReport {
    /// True when no category has an offender.
    #[getter]
    fn valid(&self) -> bool {
        self.report.is_valid()
    }

    /// Live vertices.
    #[getter]
    fn vertices(&self) -> usize {
        self.report.vertices
    }

    /// Live triangles.
    #[getter]
    fn triangles(&self) -> usize {
        self.report.triangles
    }

    /// Distinct edges.
    #[getter]
    fn edges(&self) -> usize {
        self.report.edges
    }

    /// Edges with more than two triangles (legal multi-material junctions).
    #[getter]
    fn non_manifold_edges(&self) -> usize {
        self.report.non_manifold_edges
    }

    /// {category: count} for every checked category (e.g. "boundary_edges",
    /// "inconsistent_edges", "self_intersecting_pairs").
    #[getter]
    fn counts<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let dict = PyDict::new(py);
        if let serde_json::Value::Object(map) = self.tree() {
            for (k, v) in map {
                if let Some(c) = v.get("count") {
                    dict.set_item(k, from_json(py, c)?)?;
                }
            }
        }
        Ok(dict)
    }

    /// {category: [offender, ...]} for the failing categories: the first offenders (up to
    /// 100), each naming the ids involved.
    #[getter]
    fn offenders<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let dict = PyDict::new(py);
        if let serde_json::Value::Object(map) = self.tree() {
            for (k, v) in map {
                if v.get("count").and_then(|c| c.as_u64()).unwrap_or(0) > 0
                    && let Some(items) = v.get("items")
                {
                    dict.set_item(k, from_json(py, items)?)?;
                }
            }
        }
        Ok(dict)
    }

    /// The whole report as a dict.
    fn as_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        from_json(py, &self.tree())
    }

    fn __bool__(&self) -> bool {
        self.report.is_valid()
    }

    fn __str__(&self) -> String {
        self.report.to_string()
    }

    fn __repr__(&self) -> String {
        format!("<ValidationReport {}>", self.report)
    }
}

/// generate(scene, seed=0, count=None, resolution=None, radius=None, mesh=None) -> Mesh:
/// a built-in scene's mesh (`surftrack scenes` lists them: "double-bubble", "spheres",
/// "foam", "copies" of `mesh`, ...). Raises ValueError for an unknown scene (listing
/// the known ones) or parameters the generator refuses.
#[pyfunction]
#[pyo3(signature = (scene, seed = 0, count = None, resolution = None, radius = None, mesh = None))]
pub fn generate(
    py: Python<'_>,
    scene: String,
    seed: u64,
    count: Option<usize>,
    resolution: Option<u32>,
    radius: Option<f64>,
    mesh: Option<PyRef<'_, PyMesh>>,
) -> PyResult<PyMesh> {
    let options = SceneOptions {
        seed,
        count,
        resolution,
        radius,
        mesh: mesh.map(|m| (*m.mesh).clone()),
    };
    py.detach(|| {
        guarded("generate", || {
            build_scene(&scene, &options)
                .map(PyMesh::new_from)
                .map_err(value_error)
        })
    })
}

/// What `fix` did: stage timings, cell size, triangles in and out, the untouched
/// fraction of the input, the flawed region and the validation of the output.
#[pyclass(name = "FixReport", module = "surftrack", frozen)]
pub struct PyFixReport {
    report: FixReport,
}

#[pymethods]
impl PyFixReport {
    /// True when the output passed validation.
    #[getter]
    fn valid(&self) -> bool {
        self.report.validation.is_valid()
    }

    /// The cell size used.
    #[getter]
    fn cell_size(&self) -> f64 {
        self.report.cell_size
    }

    /// Live triangles of the input.
    #[getter]
    fn triangles_in(&self) -> usize {
        self.report.triangles_in
    }

    /// Live triangles of the output.
    #[getter]
    fn triangles_out(&self) -> usize {
        self.report.triangles_out
    }

    /// Fraction of input triangles kept exactly (1 for a clean input).
    #[getter]
    fn untouched_fraction(&self) -> f64 {
        self.report.untouched_fraction
    }

    /// Cells of the final flawed region.
    #[getter]
    fn flawed_cells(&self) -> usize {
        self.report.flawed_cells
    }

    /// [(stage, seconds), ...] in pipeline order.
    #[getter]
    fn stages(&self) -> Vec<(&'static str, f64)> {
        stage_list(&self.report.stages)
    }

    /// The output's ValidationReport.
    #[getter]
    fn validation(&self) -> PyValidationReport {
        PyValidationReport {
            report: self.report.validation.clone(),
        }
    }

    /// The whole report as a dict (the CLI's `fix --json` report).
    fn as_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        from_json(py, &serde_json::to_value(&self.report).unwrap_or_default())
    }

    fn __repr__(&self) -> String {
        format!(
            "<FixReport {} -> {} triangles, {:.1}% untouched, {} flawed cells, valid={}>",
            self.report.triangles_in,
            self.report.triangles_out,
            100.0 * self.report.untouched_fraction,
            self.report.flawed_cells,
            self.report.validation.is_valid()
        )
    }
}

/// fix(mesh, cell=None, intersections=True, allow_loss=False, **options) -> (Mesh, FixReport): one-shot
/// repair / multi-material union with the grid pipeline. The input may overlap itself
/// anywhere; the output is closed, consistently labelled and intersection-free, and
/// every triangle away from the flawed cells is the input's own.
///
/// `cell` is the grid cell size (default: fitted to the thinnest material); `options` are grid
/// options by name, as `--set grid.<path>` (e.g. `resampling="global"`,
/// `**{"flaws.deep_cell_test": False}`; `__` also separates levels). `intersections`
/// checks the output for exact self-intersections in the report.
///
/// Raises ValueError for an invalid input (open, inconsistently labelled) or unknown
/// option (listing the known ones), TrackError when a stage fails or when the repair
/// would lose a material or change the union's volume beyond the tolerance (unless
/// `allow_loss`, which turns that into a warning in the report).
#[pyfunction]
#[pyo3(signature = (mesh, cell = None, intersections = true, allow_loss = false, **options))]
pub fn fix(
    py: Python<'_>,
    mesh: PyRef<'_, PyMesh>,
    cell: Option<f64>,
    intersections: bool,
    allow_loss: bool,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<(PyMesh, PyFixReport)> {
    let base = bench_harness::options::RunOptions {
        grid: FixOptions::default().params,
        ..Default::default()
    };
    let mut builder = OptionsBuilder::new(&base);
    if let Some(c) = cell {
        builder
            .set_value(
                "grid.cell_size",
                to_json(&c.into_pyobject(py)?.into_any(), "cell")?,
            )
            .map_err(value_error)?;
    }
    apply_options(&mut builder, "grid", options)?;
    let params = builder.build().map_err(value_error)?.grid;
    let fix_options = FixOptions {
        params,
        validate_intersections: intersections,
        allow_loss,
        ..FixOptions::default()
    };
    let input = mesh.mesh.clone();
    let outcome = py.detach(|| {
        guarded("fix", || {
            fix_with(&input, &fix_options).map_err(|e| match e {
                FixError::InvalidInput(_) | FixError::BadParams(_) => value_error(e),
                // A repair that would lose a material is refused with the numbers.
                FixError::Pipeline(_) | FixError::InvalidOutput(_) | FixError::Loss(_) => {
                    TrackError::new_err(e.to_string())
                }
            })
        })
    })?;
    Ok((
        PyMesh::new_from(outcome.mesh),
        PyFixReport {
            report: outcome.report,
        },
    ))
}

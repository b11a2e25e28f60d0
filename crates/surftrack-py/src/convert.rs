//! The boundary: numpy arrays checked into Rust values, Rust values back to arrays and
//! Python objects, Rust errors to Python exceptions, and panics caught before they reach
//! Python.

use std::panic::{AssertUnwindSafe, catch_unwind};

use numpy::ndarray::{Array1, Array2};
use numpy::{IntoPyArray, PyReadonlyArray2};
use pyo3::exceptions::{PyOSError, PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};
use serde_json::Value;
use surftrack::mesh_core::DVec3;
use surftrack::{BackendError, TrackError as RustTrackError};

pyo3::create_exception!(
    surftrack,
    TrackError,
    PyRuntimeError,
    "A tracker step (or a repair) failed within its bounds; the tracker keeps the mesh it \
     had before the step and stays usable."
);

/// Runs `f`, turning a Rust panic into `surftrack.TrackError` (a bug, reported as such)
/// so that no panic unwinds into Python.
pub fn guarded<T>(what: &str, f: impl FnOnce() -> PyResult<T>) -> PyResult<T> {
    match catch_unwind(AssertUnwindSafe(f)) {
        Ok(result) => result,
        Err(payload) => {
            let message = payload
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| payload.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "unknown panic".to_string());
            Err(TrackError::new_err(format!(
                "internal error in {what} (a bug, please report it): {message}"
            )))
        }
    }
}

/// A step's error as an exception: a bad proposal is the caller's `ValueError`, a stage
/// that could not complete is a `TrackError`.
pub fn track_error(e: RustTrackError) -> PyErr {
    match e {
        RustTrackError::ProposalLength { .. }
        | RustTrackError::NonFiniteProposal { .. }
        | RustTrackError::ProposalOutOfRange { .. }
        | RustTrackError::InvalidInput(_) => PyValueError::new_err(e.to_string()),
        RustTrackError::StageFailed { .. } | RustTrackError::TimeBudgetExceeded { .. } => {
            TrackError::new_err(e.to_string())
        }
    }
}

/// A construction error: unknown names and rejected meshes are `ValueError`s.
pub fn backend_error(e: BackendError) -> PyErr {
    match e {
        BackendError::Unavailable { .. } => PyRuntimeError::new_err(e.to_string()),
        _ => PyValueError::new_err(e.to_string()),
    }
}

/// Any error whose message is the whole story, as a `ValueError`.
pub fn value_error(e: impl std::fmt::Display) -> PyErr {
    PyValueError::new_err(e.to_string())
}

/// A file error, as `OSError` naming the file.
pub fn os_error(path: &str, e: impl std::fmt::Display) -> PyErr {
    PyOSError::new_err(format!("{path}: {e}"))
}

/// `numpy.asarray(obj)` with its dtype kind (`f`, `i`, `u`, `b`, …) and shape.
fn as_array<'py>(obj: &Bound<'py, PyAny>) -> PyResult<(Bound<'py, PyAny>, String, Vec<usize>)> {
    let np = PyModule::import(obj.py(), "numpy")?;
    let arr = np
        .call_method1("asarray", (obj,))
        .map_err(|e| PyValueError::new_err(format!("not convertible to an array: {e}")))?;
    let dtype = arr.getattr("dtype")?;
    let kind: String = dtype.getattr("kind")?.extract()?;
    let shape: Vec<usize> = arr.getattr("shape")?.extract()?;
    Ok((arr, kind, shape))
}

/// The dtype's name, for messages.
fn dtype_name(arr: &Bound<'_, PyAny>) -> String {
    arr.getattr("dtype")
        .and_then(|d| d.str())
        .map(|s| s.to_string())
        .unwrap_or_else(|_| "?".into())
}

/// A real `(n, cols)` array as f64 rows (integers are exact; bool, complex, object and
/// string dtypes are refused), every value finite.
fn real_rows(
    obj: &Bound<'_, PyAny>,
    what: &str,
    cols: Option<usize>,
) -> PyResult<(usize, usize, Vec<f64>)> {
    let (arr, kind, shape) = as_array(obj)?;
    if !matches!(kind.as_str(), "f" | "i" | "u") {
        return Err(PyValueError::new_err(format!(
            "{what}: expected a float64 array, got dtype {}",
            dtype_name(&arr)
        )));
    }
    let (n, k, arr) = match (shape.as_slice(), cols) {
        ([n, k], Some(c)) if *k == c => (*n, *k, arr),
        ([n, k], None) => (*n, *k, arr),
        ([n], None) => (*n, 1, arr.call_method1("reshape", ((*n, 1usize),))?),
        _ => {
            let want = match cols {
                Some(c) => format!("(n, {c})"),
                None => "(n,) or (n, k)".into(),
            };
            return Err(PyValueError::new_err(format!(
                "{what}: expected shape {want}, got {shape:?}"
            )));
        }
    };
    let arr = arr.call_method1("astype", ("float64",))?;
    let view: PyReadonlyArray2<f64> = arr.extract()?;
    let mut out = Vec::with_capacity(n * k);
    for (i, row) in view.as_array().outer_iter().enumerate() {
        for &x in row {
            if !x.is_finite() {
                return Err(PyValueError::new_err(format!(
                    "{what}: row {i} is not finite: {:?}",
                    row.to_vec()
                )));
            }
            out.push(x);
        }
    }
    Ok((n, k, out))
}

/// An `(n, 3)` array of finite points.
pub fn points(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Vec<DVec3>> {
    let (_, _, flat) = real_rows(obj, what, Some(3))?;
    Ok(flat.chunks_exact(3).map(DVec3::from_slice).collect())
}

/// A per-vertex attribute array, `(n,)` or `(n, k)`: its width, whether it was 1-D, and
/// the values row by row.
pub fn attribute_values(
    obj: &Bound<'_, PyAny>,
    what: &str,
) -> PyResult<(usize, usize, bool, Vec<f64>)> {
    let (_, _, shape) = as_array(obj)?;
    let one_d = shape.len() == 1;
    let (n, k, flat) = real_rows(obj, what, None)?;
    Ok((n, k, one_d, flat))
}

/// An integer `(m, N)` array of non-negative 32-bit indices.
pub fn indices<const N: usize>(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Vec<[u32; N]>> {
    let (arr, kind, shape) = as_array(obj)?;
    if !matches!(kind.as_str(), "i" | "u") {
        return Err(PyValueError::new_err(format!(
            "{what}: expected an integer array, got dtype {}",
            dtype_name(&arr)
        )));
    }
    // An empty list reads as shape (0,): no rows.
    let m = match shape.as_slice() {
        [m, k] if *k == N => *m,
        [0] => 0,
        _ => {
            return Err(PyValueError::new_err(format!(
                "{what}: expected shape (m, {N}), got {shape:?}"
            )));
        }
    };
    if m == 0 {
        return Ok(Vec::new());
    }
    // uint64 beyond i64 would wrap in astype: compare against the bound in numpy first.
    let too_big: bool = arr
        .call_method0("max")?
        .call_method1("__gt__", (u32::MAX,))?
        .is_truthy()?;
    let negative: bool = arr
        .call_method0("min")?
        .call_method1("__lt__", (0,))?
        .is_truthy()?;
    if too_big || negative {
        return Err(PyValueError::new_err(format!(
            "{what}: indices must lie in [0, 2³²), got values from {} to {}",
            arr.call_method0("min")?,
            arr.call_method0("max")?
        )));
    }
    let arr = arr.call_method1("astype", ("int64",))?;
    let view: PyReadonlyArray2<i64> = arr.extract()?;
    Ok(view
        .as_array()
        .outer_iter()
        .map(|row| std::array::from_fn(|j| row[j] as u32))
        .collect())
}

/// Rows of `cols` values as an `(n, cols)` float64 array.
pub fn f64_array<'py>(py: Python<'py>, cols: usize, flat: Vec<f64>) -> PyResult<Bound<'py, PyAny>> {
    let n = flat.len() / cols.max(1);
    let arr = Array2::from_shape_vec((n, cols), flat).map_err(value_error)?;
    Ok(arr.into_pyarray(py).into_any())
}

/// A flat vector as a 1-D float64 array.
pub fn f64_vector<'py>(py: Python<'py>, flat: Vec<f64>) -> Bound<'py, PyAny> {
    Array1::from_vec(flat).into_pyarray(py).into_any()
}

/// Rows of indices as an `(m, N)` int64 array.
pub fn index_array<'py, const N: usize>(
    py: Python<'py>,
    rows: &[[u32; N]],
) -> PyResult<Bound<'py, PyAny>> {
    let flat: Vec<i64> = rows.iter().flat_map(|r| r.map(i64::from)).collect();
    let arr = Array2::from_shape_vec((rows.len(), N), flat).map_err(value_error)?;
    Ok(arr.into_pyarray(py).into_any())
}

/// A Python value (bool, int, float, str, None, list/tuple, dict with str keys) as JSON,
/// for options set by keyword.
pub fn to_json(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Value> {
    if obj.is_none() {
        return Ok(Value::Null);
    }
    if obj.is_instance_of::<PyBool>() {
        return Ok(Value::Bool(obj.extract()?));
    }
    if obj.is_instance_of::<PyInt>() {
        if let Ok(i) = obj.extract::<i64>() {
            return Ok(Value::from(i));
        }
        return Ok(Value::from(obj.extract::<u64>().map_err(value_error)?));
    }
    if obj.is_instance_of::<PyFloat>() {
        let x: f64 = obj.extract()?;
        return serde_json::Number::from_f64(x)
            .map(Value::Number)
            .ok_or_else(|| PyValueError::new_err(format!("{what}: {x} is not finite")));
    }
    if obj.is_instance_of::<PyString>() {
        return Ok(Value::String(obj.extract()?));
    }
    if obj.is_instance_of::<PyList>() || obj.is_instance_of::<PyTuple>() {
        let items: Vec<Bound<'_, PyAny>> = obj.try_iter()?.collect::<PyResult<_>>()?;
        return items
            .iter()
            .map(|x| to_json(x, what))
            .collect::<PyResult<Vec<_>>>()
            .map(Value::Array);
    }
    if let Ok(dict) = obj.cast::<PyDict>() {
        let mut map = serde_json::Map::new();
        for (k, v) in dict.iter() {
            let key: String = k.extract().map_err(|_| {
                PyValueError::new_err(format!("{what}: table keys must be strings"))
            })?;
            let value = to_json(&v, &format!("{what}.{key}"))?;
            map.insert(key, value);
        }
        return Ok(Value::Object(map));
    }
    // numpy scalars and anything else with a float value.
    if let Ok(x) = obj.call_method0("item") {
        return to_json(&x, what);
    }
    Err(PyValueError::new_err(format!(
        "{what}: cannot use a {} as an option value",
        obj.get_type().name()?
    )))
}

/// JSON as Python objects (dicts, lists, numbers, strings, None).
pub fn from_json<'py>(py: Python<'py>, value: &Value) -> PyResult<Bound<'py, PyAny>> {
    Ok(match value {
        Value::Null => py.None().into_bound(py),
        Value::Bool(b) => PyBool::new(py, *b).to_owned().into_any(),
        Value::Number(n) => match (n.as_i64(), n.as_u64()) {
            (Some(i), _) => i.into_pyobject(py)?.into_any(),
            (_, Some(u)) => u.into_pyobject(py)?.into_any(),
            _ => n.as_f64().unwrap_or(f64::NAN).into_pyobject(py)?.into_any(),
        },
        Value::String(s) => PyString::new(py, s).into_any(),
        Value::Array(a) => {
            let list = PyList::empty(py);
            for x in a {
                list.append(from_json(py, x)?)?;
            }
            list.into_any()
        }
        Value::Object(m) => {
            let dict = PyDict::new(py);
            for (k, v) in m {
                dict.set_item(k, from_json(py, v)?)?;
            }
            dict.into_any()
        }
    })
}

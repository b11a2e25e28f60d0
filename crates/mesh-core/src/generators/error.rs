//! Errors of the scene generators, and the parameter checks that raise them.
//!
//! Every generator checks its parameters up front and names the generator and the
//! parameter in the error, so a command line or a test harness can report "double_bubble:
//! radius = NaN must be finite and > 0" instead of producing a broken mesh.

use glam::DVec3;

use crate::error::MeshError;

/// What went wrong generating a scene.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum GeneratorError {
    /// A parameter is outside its valid range (non-positive size, zero count, NaN, …).
    #[error("{generator}: {parameter} = {value} is invalid: must be {expected}")]
    InvalidParameter {
        /// The generator that refused it.
        generator: &'static str,
        /// The parameter's name.
        parameter: &'static str,
        /// The value given, formatted.
        value: String,
        /// What the value must satisfy.
        expected: &'static str,
    },
    /// Rejection sampling could not place every object within its attempt budget.
    #[error("{generator}: placed only {placed} of {requested} objects in {attempts} attempts")]
    CannotPlace {
        /// The generator that gave up.
        generator: &'static str,
        /// How many objects were placed.
        placed: usize,
        /// How many were asked for.
        requested: usize,
        /// How many random candidates were tried.
        attempts: usize,
    },
    /// Every random configuration tried was too close to degenerate to mesh robustly.
    #[error("{generator}: every one of {attempts} seed configurations was near-degenerate")]
    Degenerate {
        /// The generator that gave up.
        generator: &'static str,
        /// How many configurations were tried.
        attempts: usize,
    },
    /// An implicit function returned NaN or an infinity.
    #[error("implicit function is not finite at {at}")]
    NonFiniteField {
        /// The grid point where it was evaluated.
        at: DVec3,
    },
    /// Material labels would exceed the `u32` label space.
    #[error("{generator}: labels exceed the u32 range")]
    LabelOverflow {
        /// The generator whose labels overflowed.
        generator: &'static str,
    },
    /// The assembled arrays were refused by [`crate::LabeledMesh::from_raw`].
    #[error(transparent)]
    Mesh(#[from] MeshError),
}

/// Fails unless `value` is finite and strictly positive.
pub(crate) fn check_positive(
    generator: &'static str,
    parameter: &'static str,
    value: f64,
) -> Result<(), GeneratorError> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(invalid(generator, parameter, value, "finite and > 0"))
    }
}

/// Fails unless every coordinate of `value` is finite.
pub(crate) fn check_finite(
    generator: &'static str,
    parameter: &'static str,
    value: DVec3,
) -> Result<(), GeneratorError> {
    if value.is_finite() {
        Ok(())
    } else {
        Err(invalid(generator, parameter, value, "finite"))
    }
}

/// Fails unless the box `[min, max]` is finite with `min < max` on every axis.
pub(crate) fn check_box(
    generator: &'static str,
    min: DVec3,
    max: DVec3,
) -> Result<(), GeneratorError> {
    check_finite(generator, "box minimum", min)?;
    check_finite(generator, "box maximum", max)?;
    if min.cmplt(max).all() {
        Ok(())
    } else {
        Err(invalid(
            generator,
            "box",
            format!("[{min}, {max}]"),
            "non-empty (min < max on every axis)",
        ))
    }
}

/// Builds an [`GeneratorError::InvalidParameter`].
pub(crate) fn invalid(
    generator: &'static str,
    parameter: &'static str,
    value: impl std::fmt::Display,
    expected: &'static str,
) -> GeneratorError {
    GeneratorError::InvalidParameter {
        generator,
        parameter,
        value: value.to_string(),
        expected,
    }
}

//! Errors of flow construction.

/// A flow parameter out of its domain, caught when the flow is built so that stepping
/// never has to check (and never produces NaN from a bad parameter).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum FlowError {
    /// A parameter has an invalid value.
    #[error("{flow}: parameter `{parameter}` = {value} is invalid: expected {expected}")]
    InvalidParameter {
        /// Which flow was being built.
        flow: &'static str,
        /// Which parameter.
        parameter: &'static str,
        /// The value given, printed.
        value: String,
        /// What was expected instead.
        expected: &'static str,
    },
}

/// Shorthand for [`FlowError::InvalidParameter`].
pub(crate) fn invalid(
    flow: &'static str,
    parameter: &'static str,
    value: impl std::fmt::Debug,
    expected: &'static str,
) -> FlowError {
    FlowError::InvalidParameter {
        flow,
        parameter,
        value: format!("{value:?}"),
        expected,
    }
}

/// Accepts finite numbers.
pub(crate) fn check_finite(
    flow: &'static str,
    parameter: &'static str,
    value: f64,
) -> Result<f64, FlowError> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(invalid(flow, parameter, value, "a finite number"))
    }
}

/// Accepts finite, strictly positive numbers.
pub(crate) fn check_positive(
    flow: &'static str,
    parameter: &'static str,
    value: f64,
) -> Result<f64, FlowError> {
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(invalid(flow, parameter, value, "a finite number > 0"))
    }
}

/// Accepts points and vectors with finite coordinates.
pub(crate) fn check_finite_vec(
    flow: &'static str,
    parameter: &'static str,
    value: glam::DVec3,
) -> Result<glam::DVec3, FlowError> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(invalid(flow, parameter, value, "finite coordinates"))
    }
}

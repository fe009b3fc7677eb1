//! The one error type of the core. Every variant names the offending field and the rule it broke,
//! so the bindings can turn it into a Python `ValueError` without adding words of their own.

use thiserror::Error;

/// Result alias used throughout the core.
pub type Result<T> = std::result::Result<T, RfError>;

#[derive(Debug, Clone, PartialEq, Error)]
pub enum RfError {
    /// A value breaks a rule (non-finite, out of range, inconsistent with another field).
    #[error("{field}: {rule}")]
    InvalidValue { field: String, rule: String },
    /// An array has the wrong length or shape.
    #[error("{field}: expected {expected}, got {actual}")]
    Shape {
        field: String,
        expected: String,
        actual: String,
    },
    /// A TOML airframe description could not be read.
    #[error("{origin}: {message}")]
    Parse { origin: String, message: String },
}

impl RfError {
    pub fn invalid(field: impl Into<String>, rule: impl Into<String>) -> Self {
        RfError::InvalidValue {
            field: field.into(),
            rule: rule.into(),
        }
    }

    pub fn shape(
        field: impl Into<String>,
        expected: impl Into<String>,
        actual: impl Into<String>,
    ) -> Self {
        RfError::Shape {
            field: field.into(),
            expected: expected.into(),
            actual: actual.into(),
        }
    }
}

/// Rejects NaN and infinities, naming the field.
pub(crate) fn require_finite(field: &str, value: f64) -> Result<()> {
    if value.is_finite() {
        Ok(())
    } else {
        Err(RfError::invalid(
            field,
            format!("must be finite, got {value}"),
        ))
    }
}

/// Rejects NaN, infinities and negative values, naming the field.
pub(crate) fn require_non_negative(field: &str, value: f64) -> Result<()> {
    require_finite(field, value)?;
    if value < 0.0 {
        return Err(RfError::invalid(
            field,
            format!("must be >= 0, got {value}"),
        ));
    }
    Ok(())
}

/// Rejects non-finite entries of a slice, naming the first offending index.
pub(crate) fn require_all_finite(field: &str, values: &[f64]) -> Result<()> {
    match values.iter().position(|v| !v.is_finite()) {
        None => Ok(()),
        Some(i) => Err(RfError::invalid(
            format!("{field}[{i}]"),
            format!("must be finite, got {}", values[i]),
        )),
    }
}

pub(crate) fn require_len(field: &str, values: &[f64], expected: usize) -> Result<()> {
    require_entries(field, values, expected, "one per rotor")
}

/// Rejects a slice whose length is not `expected`; `what` says what each entry is for.
pub(crate) fn require_entries(
    field: &str,
    values: &[f64],
    expected: usize,
    what: &str,
) -> Result<()> {
    if values.len() == expected {
        Ok(())
    } else {
        Err(RfError::shape(
            field,
            format!("{expected} entries ({what})"),
            values.len().to_string(),
        ))
    }
}

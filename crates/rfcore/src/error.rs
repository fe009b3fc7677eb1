//! The one error type of the core. Every variant names the offending field and the rule it broke,
//! so the bindings can turn it into a Python `ValueError` without adding words of their own.
//! Also the rules every field check uses, among them the accepted magnitudes below.
//!
//! # Accepted magnitudes (one decision for the whole core)
//! A double between 0 and 2.2e-308 is *subnormal*: it has lost precision and its reciprocal is
//! infinite (1 / 1e-310 = inf). An airframe of mass 1e-310, accepted as "> 0", put that infinity
//! into the hover model and the scale-free rank's SVD never converged. So:
//! - **Scales the model divides by** (`require_scale`, `require_scale_or_zero`) lie in
//!   [`MIN_SCALE`, `MAX_SCALE`] = [1e-15, 1e15] in SI units (zero where the field allows it):
//!
//!   | field | divided by in | real vehicles | values the tests use |
//!   |---|---|---|---|
//!   | `mass_kg` | `1 / m` (rigid body, hover model `J_f`), Ke's and Lanzon's laws | 8e-5 kg (RoboBee) to ~1e4 kg | 5e-4 to 1.5e3 (presets scaled by 1e-3 to 1e3) |
//!   | `inertia_kg_m2` | `J^-1` (rigid body, hover model, Ke, Lanzon) | ~1e-10 to ~1e5 kg m^2 | 4.11e-14 to 5.99e12 (rank of C(A, B) in any unit) |
//!   | `gravity_m_s2` (0 allowed) | Lanzon's `u3` (tilt set points) | 1.6 (Moon) to 274 (Sun's surface) | 9.81, 10 |
//!   | `time_constant_s` (0: no lag), Ke's `epsilon_s` | `exp(-h / tau)`, `1 / tau` (step-size guard), the filter's `(x - f) / eps` | 1e-4 to 1 s | 0.01 to 0.06 |
//!   | `dt_s` (simulation, Ke) | `duration / dt`, `MAX_RATE_STEP / h`, `exp(-dt / eps)` | 1e-5 to 1 s | 0.0025 (400 Hz) and the like |
//!   | `thrust_coefficient_n_s2` (0: speed not modelled) | `sqrt(f / k_f)` (rotor spin) | 1e-9 to 1e-3 N s^2 | 1e-5 |
//!   | Lanzon's `arm_length_m`, `drag_torque_ratio_m`, `rotational_drag_n_m_s` | eq. (9)'s `tq / l`, `tr / d`, `r0 = m g d / k_r` | 1e-3 to 10 | 0.255, 2.4e-3, 4.4e-3 |
//!   | `sensing.imu_rate_hz`, `sensing.position_rate_hz` (at most 32 kHz, 1 kHz) | the sample period `1 / rate` (a subnormal rate's is infinite: building the simulator never returned and grew without bound) | 1 to 32,000 Hz | 5 to 1,000 Hz |
//!   | `sensing.gyro_range_rad_s` (at most 1,000 rad/s) | the clamp and the estimator's saturation walk `(s range)^2` | 4 to 70 rad/s (+-250 to +-4000 deg/s) | 34.9 to 1,000 rad/s |
//!
//!   Every real value sits at least four decades inside; every value the tests and the papers
//!   use is accepted; and any product or quotient of up to twenty such scales is a normal,
//!   finite double (1e+-300), so nothing the model forms from them (`m g`, `J / m`, `J^-1`,
//!   `J omega^2`, `r0`) overflows or turns subnormal.
//! - **Numbers a unit-free rule equilibrates or a rate divides by** (`require_normal`: rotor
//!   positions and arm lengths, `k_mu`, the entries, weights and regularisation of an allocation
//!   problem, Ke's weights, the variable-pitch coefficients `k1..k4`; rate limits are positive and
//!   normal or infinite) are zero or normal. The analysis and the allocator divide by their magnitudes (row and column scaling
//!   by powers of two) and are tested exact from 1e-160 to 1e300, so no tighter bound is needed;
//!   the allocator refuses magnitudes above 1e300 (the power of two nearest 1.5e308 is infinite),
//!   and sums are checked for overflow where they are formed (`f_min, f_max, g_vec: too large`).
//! - Everything else (angles, thrust bounds, efficiencies, states, gains, set points) only
//!   multiplies or is compared: finite is the rule.

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
    /// An iterative method reached its iteration cap without converging (an input it cannot
    /// settle, e.g. a matrix near the limits of double precision), instead of running forever.
    #[error("{field}: {method} did not converge within its cap of {cap} iterations")]
    IterationLimit {
        field: String,
        method: String,
        cap: usize,
    },
    /// The caller cancelled the call through its [`crate::cancel::Cancel`] token (Ctrl-C in
    /// Python): nothing is returned, nothing half-done is kept.
    #[error("interrupted: the call was cancelled")]
    Interrupted,
}

impl RfError {
    pub fn invalid(field: impl Into<String>, rule: impl Into<String>) -> Self {
        RfError::InvalidValue {
            field: field.into(),
            rule: rule.into(),
        }
    }

    pub fn iteration_limit(
        field: impl Into<String>,
        method: impl Into<String>,
        cap: usize,
    ) -> Self {
        RfError::IterationLimit {
            field: field.into(),
            method: method.into(),
            cap,
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

/// Smallest physical scale the model divides by, SI (module docs).
pub const MIN_SCALE: f64 = 1e-15;
/// Largest physical scale the model divides by, SI (module docs).
pub const MAX_SCALE: f64 = 1e15;

/// A physical scale the model divides by: finite, `> 0`, and in [[`MIN_SCALE`], [`MAX_SCALE`]]
/// (`unit` names its SI unit in the message).
pub(crate) fn require_scale(field: &str, value: f64, unit: &str) -> Result<()> {
    require_finite(field, value)?;
    if value <= 0.0 {
        return Err(RfError::invalid(field, format!("must be > 0, got {value}")));
    }
    require_scale_range(field, value, unit)
}

/// [`require_scale`] where zero is allowed and means "none" (no lag, no rotor-speed model).
pub(crate) fn require_scale_or_zero(field: &str, value: f64, unit: &str) -> Result<()> {
    require_non_negative(field, value)?;
    if value == 0.0 {
        return Ok(());
    }
    require_scale_range(field, value, unit)
}

fn require_scale_range(field: &str, value: f64, unit: &str) -> Result<()> {
    if (MIN_SCALE..=MAX_SCALE).contains(&value) {
        Ok(())
    } else {
        Err(RfError::invalid(
            field,
            format!(
                "must lie in [{MIN_SCALE:e}, {MAX_SCALE:e}] {unit} (a scale the model divides \
                 by; subnormal and absurd magnitudes are refused), got {value:e}"
            ),
        ))
    }
}

/// Finite, and zero or a normal double (`|x| >= 2.2e-308`): a subnormal has no precision left and
/// its reciprocal overflows, so it is refused rather than read as a scale (module docs).
pub(crate) fn require_normal(field: &str, value: f64) -> Result<()> {
    require_finite(field, value)?;
    if value == 0.0 || value.is_normal() {
        Ok(())
    } else {
        Err(RfError::invalid(
            field,
            format!(
                "must be 0 or a normal number (|x| >= {:e}), got the subnormal {value:e}",
                f64::MIN_POSITIVE
            ),
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

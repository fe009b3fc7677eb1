//! rfcore: the pure-Rust core of rotorfault.
//!
//! - [`airframe`]: multirotor geometry, thrust limits, efficiencies, TOML presets.
//! - [`acai`]: the Available Control Authority Index (Du et al., Theorem 3) for any dimension.
//! - [`controllability`]: Du's 9-step test procedure and failure tables.
//! - [`allocation`], [`active_set`], [`clarabel_qp`]: constrained control allocation (Ke eq. (33)),
//!   exact and fast, with Clarabel as the reference and for attainable-set queries.
//! - [`rigid_body`]: 6-DOF Newton-Euler dynamics and the RK4 step (the simulator's bottom layer).
//!
//! Units are SI throughout (N, m, kg, s, rad) and carried in names (`max_thrust_n`).

pub mod acai;
pub mod active_set;
pub mod actuator;
pub mod airframe;
pub mod allocation;
pub mod clarabel_qp;
pub mod combinations;
pub mod controllability;
pub mod controller;
pub mod error;
pub mod fault_schedule;
pub mod ftc;
pub mod rigid_body;
pub mod simulation;
pub mod vehicle;

pub use acai::{acai_from_matrix, AcaiFormula, AcaiValues, FacetNormals, RANK_RTOL, ZERO_RTOL};
pub use airframe::{Airframe, Rotor, SpinDirection, DEFAULT_GRAVITY_M_S2};
pub use controllability::{
    failure_table, ControlAxes, ControllabilityAnalysis, ControllabilityReport, FailureCase,
    Verdict,
};
pub use error::{Result, RfError};

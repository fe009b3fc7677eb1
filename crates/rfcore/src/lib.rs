//! rfcore: the pure-Rust core of rotorfault, in rooms by concept.
//!
//! - [`airframe`], [`state`], [`error`]: the shared vocabulary (geometry and thrust limits, the
//!   vehicle state, errors that name the field and the rule, the accepted magnitudes).
//! - [`cancel`]: the token a caller sets to stop a long call (Ctrl-C), polled in every long loop.
//! - [`analysis`]: controllability and the Available Control Authority Index (Du et al.).
//! - [`allocation`]: constrained control allocation (Ke eq. (33)): the exact active set, Clarabel
//!   as the reference, the weighted pseudo-inverse.
//! - [`control`]: the [`control::Controller`] trait and the built-in controllers (linear laws,
//!   allocated laws, one file per paper's controller).
//! - [`flight`]: rigid body + RK4, actuators, vehicle forces, the closed-loop simulation.
//!
//! Dependencies run one way (checked by `tests/architecture.rs`): `analysis` uses only
//! `airframe`; `allocation` uses neither `flight` nor `control`; `control` uses `allocation`,
//! never `flight`; `flight` may use all of them. Units are SI throughout and carried in names.

pub mod airframe;
pub mod allocation;
pub mod analysis;
pub mod cancel;
pub mod control;
pub mod error;
#[doc(hidden)]
pub mod fixtures;
pub mod flight;
pub mod state;

pub use airframe::{Airframe, Rotor, RotorPlacement, SpinDirection, DEFAULT_GRAVITY_M_S2};
pub use cancel::Cancel;
pub use error::{Result, RfError};

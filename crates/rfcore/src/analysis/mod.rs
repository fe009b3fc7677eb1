//! Controllability analysis (Du et al., JGCD 2015): the Available Control Authority Index
//! ([`acai`]), the 9-step test procedure and failure tables ([`controllability`]), the failure
//! combinations they enumerate ([`combinations`]), the one rank rule with its capped SVD
//! ([`rank`]), their printed forms ([`text`]), and relaxed hover (Mueller and D'Andrea: flying on by spinning,
//! [`relaxed_hover`]). Depends only on [`crate::airframe`] (and the shared `error` and `cancel`).

pub mod acai;
pub mod combinations;
pub mod controllability;
mod cross_product;
pub mod facet_lanes;
pub mod rank;
pub mod relaxed_hover;
pub mod text;

pub use acai::{
    acai_from_matrix, acai_from_matrix_cancellable, acai_from_matrix_with_hover,
    equilibrating_row_scale, AcaiBatch, AcaiFormula, AcaiResult, AcaiValues, FacetNormals,
    HoverPoint, RANK_RTOL, ZERO_RTOL,
};
pub use controllability::{
    failure_table, is_fully_actuated, ControlAxes, ControllabilityAnalysis, ControllabilityReport,
    FailureCase, Verdict,
};
pub use facet_lanes::LanePath;
pub use rank::{numerical_rank, scale_free_rank, svd_iteration_cap};

//! Controllability analysis (Du et al., JGCD 2015): the Available Control Authority Index
//! ([`acai`]), the 9-step test procedure and failure tables ([`controllability`]), and the
//! failure combinations they enumerate ([`combinations`]); relaxed hover (Mueller and D'Andrea:
//! flying on by spinning, [`relaxed_hover`]). Depends only on [`crate::airframe`].

pub mod acai;
pub mod combinations;
pub mod controllability;
pub mod relaxed_hover;

pub use acai::{
    acai_from_matrix, acai_from_matrix_with_hover, equilibrating_row_scale, scale_free_rank,
    AcaiBatch, AcaiFormula, AcaiResult, AcaiValues, FacetNormals, HoverPoint, RANK_RTOL, ZERO_RTOL,
};
pub use controllability::{
    failure_table, is_fully_actuated, ControlAxes, ControllabilityAnalysis, ControllabilityReport,
    FailureCase, Verdict,
};

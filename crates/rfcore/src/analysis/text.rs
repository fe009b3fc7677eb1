//! The printed forms of the analysis' results, one for every caller: the Python API's tables,
//! commands and reports call these through the bindings, so an ACAI reads the same wherever it
//! is printed (4 decimals like Du's tables, its formula named: `ACAI eq13`, `ACAI facet-margin`).

use crate::analysis::acai::{AcaiFormula, HoverPoint};
use crate::analysis::controllability::{ControlAxes, ControllabilityReport};

/// How a printed ACAI names its formula: `ACAI eq13` or `ACAI facet-margin`.
pub fn acai_label(formula: AcaiFormula) -> String {
    format!("ACAI {}", formula.name())
}

/// 4 decimals like the paper; `undefined` for an infinite value (rank B_f < n); a star where the
/// number reads as non-negative (eq. (13)'s 0) but the hover wrench lies outside the attainable
/// set. `nan` as Python prints it (no result is NaN; a caller's value may be).
pub fn format_acai(value: f64, hover: HoverPoint) -> String {
    if value.is_nan() {
        return "nan".to_string();
    }
    if value.is_infinite() {
        return "undefined".to_string();
    }
    if value >= 0.0 && hover == HoverPoint::Outside {
        format!("{value:.4}*")
    } else {
        format!("{value:.4}")
    }
}

/// `value` as Python's `format(value, "g")` writes it (6 significant digits, trailing zeros
/// dropped, exponent form below 1e-4 and from 1e6): how an efficiency is printed.
pub fn format_general(value: f64) -> String {
    if value.is_nan() {
        return "nan".to_string();
    }
    if value.is_infinite() {
        return if value > 0.0 { "inf" } else { "-inf" }.to_string();
    }
    if value == 0.0 {
        return if value.is_sign_negative() { "-0" } else { "0" }.to_string();
    }
    // The exponent after rounding to 6 significant digits decides the form, as in Python.
    let scientific = format!("{value:.5e}");
    let (mantissa, exponent) = scientific.split_once('e').unwrap_or((&scientific, "0"));
    let exponent: i32 = exponent.parse().unwrap_or(0);
    if !(-4..6).contains(&exponent) {
        let sign = if exponent < 0 { '-' } else { '+' };
        format!(
            "{}e{sign}{:02}",
            strip_zeros(mantissa),
            exponent.unsigned_abs()
        )
    } else {
        let decimals = usize::try_from(5 - exponent).unwrap_or(0);
        strip_zeros(&format!("{value:.decimals$}")).to_string()
    }
}

fn strip_zeros(number: &str) -> &str {
    if number.contains('.') {
        number.trim_end_matches('0').trim_end_matches('.')
    } else {
        number
    }
}

/// Du's test as the API prints it: the question (airframe, efficiency, axes), the two ranks,
/// the ACAI named by its formula and the verdict.
pub fn controllability_text(report: &ControllabilityReport, airframe: &str) -> String {
    let axes = match report.axes {
        ControlAxes::ThrustRollPitch => "thrust, roll, pitch (yaw given up)",
        ControlAxes::ThrustRollPitchYaw => "thrust, roll, pitch, yaw",
        ControlAxes::Wrench => "force and torque (6-D wrench)",
    };
    let mut acai = if report.acai.is_infinite() {
        "undefined (-inf)".to_string()
    } else {
        format_acai(report.acai, report.hover)
    };
    if acai.ends_with('*') {
        acai.push_str(
            " (eq. (13) prints 0 although the hover wrench lies outside the attainable set)",
        );
    }
    let efficiency: Vec<String> = report
        .efficiency
        .iter()
        .map(|&e| format_general(e))
        .collect();
    let label = acai_label(report.formula);
    let width = label.len().max("rank C(A, B)".len());
    [
        format!(
            "{airframe}: efficiency = [{}], axes = {axes}",
            efficiency.join(", ")
        ),
        format!(
            "  {:<width$} = {} of {}",
            "rank C(A, B)", report.controllability_rank, report.state_dimension
        ),
        format!(
            "  {:<width$} = {} of {}",
            "rank B_f", report.effectiveness_rank, report.virtual_control_dimension
        ),
        format!("  {label:<width$} = {acai}"),
        format!("  {:<width$} = {}", "verdict", report.verdict.code()),
    ]
    .join("\n")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn general_format_matches_python() {
        // Each pair is Python's format(value, "g").
        for (value, text) in [
            (1.0, "1"),
            (0.5, "0.5"),
            (0.123456789, "0.123457"),
            (1e-5, "1e-05"),
            (0.0001, "0.0001"),
            (0.00012345678, "0.000123457"),
            (123456.0, "123456"),
            (1234567.0, "1.23457e+06"),
            (999999.5, "1e+06"),
            (-0.0, "-0"),
            (1e-300, "1e-300"),
            (0.3, "0.3"),
        ] {
            assert_eq!(format_general(value), text, "{value}");
        }
    }

    #[test]
    fn acai_reads_with_four_decimals_and_marks_eq13_outside() {
        assert_eq!(format_acai(1.129472, HoverPoint::Inside), "1.1295");
        assert_eq!(format_acai(0.0, HoverPoint::Outside), "0.0000*");
        assert_eq!(format_acai(-0.5, HoverPoint::Outside), "-0.5000");
        assert_eq!(
            format_acai(f64::NEG_INFINITY, HoverPoint::RankDeficient),
            "undefined"
        );
        assert_eq!(acai_label(AcaiFormula::FacetMargin), "ACAI facet-margin");
    }
}

//! Du et al. Tables II and III from the shipped presets (the same TOML files Python reads).

use rfcore::analysis::{failure_table, AcaiFormula, ControlAxes, ControllabilityAnalysis, Verdict};
use rfcore::fixtures::{preset, presets_dir};
use rfcore::{Airframe, Cancel};

fn single_failure_acai(name: &str, formula: AcaiFormula) -> (f64, Vec<f64>) {
    let airframe = preset(name);
    let analysis =
        ControllabilityAnalysis::new(&airframe, ControlAxes::ThrustRollPitchYaw).unwrap();
    let healthy = analysis.acai(&[1.0; 6], formula).unwrap();
    let failed = (0..6)
        .map(|k| {
            let mut eta = [1.0; 6];
            eta[k] = 0.0;
            analysis.acai(&eta, formula).unwrap()
        })
        .collect();
    (healthy, failed)
}

/// Table values are printed to 4 decimals: agree to half a unit in the last place.
const TABLE_TOL: f64 = 0.5e-4;

#[test]
fn du_table_ii_pnpnpn() {
    let (healthy, failed) = single_failure_acai("hexa-pnpnpn", AcaiFormula::Eq13);
    assert!((healthy - 1.4861).abs() < TABLE_TOL, "{healthy}");
    for (k, rho) in failed.iter().enumerate() {
        // Exactly zero, not -0.0 and not a rounding residue.
        assert!(
            *rho == 0.0 && rho.is_sign_positive(),
            "rotor {} failed: {rho}",
            k + 1
        );
    }
}

#[test]
fn du_table_iii_ppnnpn() {
    let (healthy, failed) = single_failure_acai("hexa-ppnnpn", AcaiFormula::Eq13);
    assert!((healthy - 1.1295).abs() < TABLE_TOL, "{healthy}");
    let expected = [0.7221, 0.4510, 0.4510, 0.7221, 0.0, 0.0];
    for (k, (rho, want)) in failed.iter().zip(expected).enumerate() {
        assert!(
            (rho - want).abs() < TABLE_TOL,
            "rotor {} failed: {rho} vs {want}",
            k + 1
        );
    }
    assert_eq!(failed[4], 0.0);
    assert_eq!(failed[5], 0.0);
}

#[test]
fn facet_margin_agrees_inside_and_sees_the_gap_outside() {
    let (healthy, failed) = single_failure_acai("hexa-ppnnpn", AcaiFormula::FacetMargin);
    assert!((healthy - 1.1295).abs() < TABLE_TOL);
    for k in 0..4 {
        assert!((failed[k] - [0.7221, 0.4510, 0.4510, 0.7221][k]).abs() < TABLE_TOL);
    }
    // Rotor 5 or 6 failed: G violates a facet inequality by 0.2133 (confirmed by an LP and a
    // convex hull in tests/papers/test_du_paper.py).
    assert!((failed[4] + 0.2133).abs() < TABLE_TOL, "{}", failed[4]);
    assert!((failed[5] + 0.2133).abs() < TABLE_TOL, "{}", failed[5]);
    // PNPNPN single failures really are on the boundary.
    let (_, failed) = single_failure_acai("hexa-pnpnpn", AcaiFormula::FacetMargin);
    assert!(failed.iter().all(|&rho| rho == 0.0), "{failed:?}");
}

#[test]
fn procedure_reports_ranks_and_verdicts() {
    let airframe = preset("hexa-ppnnpn");
    let analysis =
        ControllabilityAnalysis::new(&airframe, ControlAxes::ThrustRollPitchYaw).unwrap();
    let report = analysis
        .report(&[1.0, 1.0, 1.0, 1.0, 0.0, 1.0], AcaiFormula::Eq13)
        .unwrap();
    assert_eq!(report.controllability_rank, 8);
    assert_eq!(report.effectiveness_rank, 4);
    // Table III prints 0 (eq. (13)), but hover is infeasible: G is outside, not on the boundary.
    assert_eq!(report.acai, 0.0);
    assert_eq!(report.verdict, Verdict::HoverOutside);
    let report = analysis
        .report(&[0.0, 1.0, 1.0, 1.0, 1.0, 1.0], AcaiFormula::Eq13)
        .unwrap();
    assert_eq!(report.verdict, Verdict::Controllable);
    // Three rotors left cannot span four axes.
    let report = analysis
        .report(&[0.0, 0.0, 0.0, 1.0, 1.0, 1.0], AcaiFormula::Eq13)
        .unwrap();
    assert_eq!(report.effectiveness_rank, 3);
    assert_eq!(report.acai, f64::NEG_INFINITY);
    assert_eq!(report.verdict, Verdict::EffectivenessRankDeficient);
}

#[test]
fn failure_table_counts_and_matches_single_evaluations() {
    let airframe = preset("hexa-ppnnpn");
    let table = failure_table(&airframe, 2, AcaiFormula::Eq13, &Cancel::never()).unwrap();
    assert_eq!(table.len(), 1 + 6 + 15);
    assert!(table[0].failed.is_empty());
    assert_eq!(table[1].failed, vec![0]);
    assert!((table[1].all_axes.acai - 0.7221).abs() < TABLE_TOL);
    assert_eq!(table[7].failed, vec![0, 1]);
    assert!(failure_table(&airframe, 7, AcaiFormula::Eq13, &Cancel::never()).is_err());
}

#[test]
fn every_preset_parses() {
    let mut count = 0;
    for entry in std::fs::read_dir(presets_dir()).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "toml") {
            let name = path.file_stem().unwrap().to_string_lossy().to_string();
            let airframe = preset(&name);
            assert_eq!(airframe.name(), name, "file name and name field agree");
            let again = Airframe::from_toml_str(&airframe.to_toml_string(), "round trip").unwrap();
            assert_eq!(again, airframe, "{name} survives a TOML round trip");
            count += 1;
        }
    }
    assert!(count >= 7);
}

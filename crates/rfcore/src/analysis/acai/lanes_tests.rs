//! The batch's lanes kernel ([`crate::analysis::facet_lanes`]) against the scalar path.

use super::*;
use crate::analysis::facet_lanes::LANES;

/// The lanes kernel (both compiled forms the CPU runs) against the scalar `evaluate`, row by
/// row, bit for bit: the Fig. 4 grid with failed rotors, and octocopter rows with zeros,
/// a rank-deficient row and a tail shorter than a pass.
#[test]
fn lanes_kernel_equals_the_scalar_path_bit_for_bit() {
    let levels: Vec<f64> = (0..=25).map(|i| f64::from(i) * 0.04).collect();
    let mut hexa_grid = Vec::new();
    for &e1 in &levels {
        for &e2 in &levels {
            for &e5 in &levels {
                hexa_grid.extend_from_slice(&[e1, e2, 1.0, 1.0, e5, 1.0]);
            }
        }
    }
    let mut octo_rows: Vec<f64> = (0..(3 * LANES + 5) * 8)
        .map(|i| [0.0, 0.3, 1.0, 0.77, 0.05, 0.0, 1.0, 0.5, 0.9][(i * 7 + i / 8) % 9])
        .collect();
    octo_rows[..8].copy_from_slice(&[1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0]);
    let paths: Vec<LanePath> = [LanePath::Portable, LanePath::Avx2]
        .into_iter()
        .filter(|p| p.is_available())
        .collect();
    assert_eq!(paths[0], LanePath::Portable, "the fallback always runs");
    for (name, etas) in [("hexa-pnpnpn", hexa_grid), ("octo-x", octo_rows)] {
        // The preset read directly: `fixtures` imports the allocation room, which imports this.
        let path = format!(
            "{}/../../python/rotorfault/presets/{name}.toml",
            env!("CARGO_MANIFEST_DIR")
        );
        let text = std::fs::read_to_string(&path).unwrap();
        let airframe = crate::airframe::Airframe::from_toml_str(&text, name).unwrap();
        let normals = FacetNormals::new(&airframe.nominal_effectiveness_matrix()).unwrap();
        let (f_min, f_max, g) = (
            airframe.min_thrust_n(),
            airframe.max_thrust_n(),
            airframe.hover_wrench(),
        );
        let rows = etas.len() / normals.m;
        let scalar: Vec<AcaiValues> = etas
            .chunks_exact(normals.m)
            .map(|eta| normals.evaluate(eta, &f_min, &f_max, &g))
            .collect();
        assert!(
            scalar.iter().any(|v| v.eq13 == f64::NEG_INFINITY),
            "{name}: a rank-deficient row"
        );
        if name == "hexa-pnpnpn" {
            assert!(
                scalar.iter().any(|v| v.eq13 == 0.0),
                "the grid's ACAI = 0 rows"
            );
        }
        for &path in &paths {
            let (mut eq13, mut margin) = (vec![f64::NAN; rows], vec![f64::NAN; rows]);
            normals.evaluate_rows(&etas, &f_min, &f_max, &g, path, &mut eq13, &mut margin);
            for (i, v) in scalar.iter().enumerate() {
                assert_eq!(
                    (eq13[i].to_bits(), margin[i].to_bits()),
                    (v.eq13.to_bits(), v.facet_margin.to_bits()),
                    "{name} {path:?} row {i}: ({}, {}) vs {v:?}",
                    eq13[i],
                    margin[i]
                );
            }
        }
    }
}

//! Test and benchmark support: the presets that ship in the Python package, read from the source
//! tree (the one place the core's tests and benches find them). Not part of the API.

use std::path::PathBuf;

use crate::airframe::Airframe;

/// `python/rotorfault/presets` of this source tree.
pub fn presets_dir() -> PathBuf {
    PathBuf::from(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../python/rotorfault/presets"
    ))
}

/// The text of `presets/{relative}` (e.g. `"quad-x.toml"`, `"ftc/ke-hil.toml"`).
pub fn preset_text(relative: &str) -> String {
    let path = presets_dir().join(relative);
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// The preset airframe `name` (e.g. `"hexa-pnpnpn"`).
pub fn preset(name: &str) -> Airframe {
    Airframe::from_toml_str(&preset_text(&format!("{name}.toml")), name)
        .unwrap_or_else(|e| panic!("preset {name}: {e}"))
}

//! Fixtures shared by the unit tests: the sorting station of seed 004.

use crate::bundle::PlantBundle;
use std::path::PathBuf;

/// `layouts/sorting-station`, found from the crate's manifest directory.
pub(crate) fn station_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../layouts/sorting-station")
}

/// The sorting station, loaded from its folder; panics (in tests only) on any loading
/// problem other than the static property (6) check, which the constraint tests cover.
pub(crate) fn station() -> PlantBundle {
    let (bundle, problems) = match PlantBundle::load(&station_dir()) {
        Ok(v) => v,
        Err(p) => panic!(
            "cannot load the sorting station: {}",
            crate::diag::render(&p)
        ),
    };
    let unexpected: Vec<_> = problems
        .iter()
        .filter(|p| p.code != "V0106")
        .cloned()
        .collect();
    assert!(
        unexpected.is_empty(),
        "{}",
        crate::diag::render(&unexpected)
    );
    bundle
}

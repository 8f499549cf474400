//! Fixtures shared by the unit tests: the sorting station of seed 004.

use crate::bundle::PlantBundle;
use crate::diag::codes;
use crate::frame::Frame;
use crate::symbols::{Symbols, Var};
use std::path::PathBuf;

/// `layouts/sorting-station`, found from the crate's manifest directory.
pub(crate) fn station_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../layouts/sorting-station")
}

/// The station's first layout file, written for the emulator the components replaced:
/// a fixture of that emulator's tests and of the identity tests.
pub(crate) fn station_layout_file() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("src/emulator/layout/sorting-station.ron")
}

/// The station's turntable cell, derived from its `components.ron`.
pub(crate) fn station_layout() -> crate::emulator::Layout {
    let desc = crate::machine::Components::load(&station_dir().join("components.ron"))
        .expect("the station's components load");
    crate::emulator::Layout::from_components(&desc).expect("the station is a turntable cell")
}

mod paper;

/// A copy of the station's folder (programs and scenarios included) in a fresh
/// temporary directory `vigie-<tag>-<pid>`.
pub(crate) fn station_copy(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("vigie-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    paper::copy_dir(&station_dir(), &dir);
    dir
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
        .filter(|p| p.code != codes::PROPERTY_6_VIOLATED.id)
        .cloned()
        .collect();
    assert!(
        unexpected.is_empty(),
        "{}",
        crate::diag::render(&unexpected)
    );
    bundle
}

/// Sets one variable of a frame (at t, or at t-1 for a previous value).
pub(crate) fn set_var(frame: &mut Frame, var: Var, value: bool) {
    let table = if var.prev {
        &mut frame.prev
    } else {
        &mut frame.now
    };
    table[var.space as usize].set(var.index as usize, value);
}

/// The variable `name` (`A4*` for its previous value); panics on an unknown name.
pub(crate) fn var(symbols: &Symbols, name: &str) -> Var {
    let prev = name.ends_with('*');
    let (space, index) = symbols
        .lookup(name.trim_end_matches('*'))
        .unwrap_or_else(|| panic!("unknown variable `{name}`"));
    Var { space, index, prev }
}

/// A frame with the named variables set (`A4*` for a previous value), all else 0.
pub(crate) fn frame_with(symbols: &Symbols, ones: &[&str]) -> Frame {
    let mut f = Frame::new(symbols.sizes());
    for name in ones {
        set_var(&mut f, var(symbols, name), true);
    }
    f
}

/// A folder of the tests' own, removed when it drops (read through it as a `Path`).
pub(crate) struct Scratch(pub(crate) PathBuf);

impl std::ops::Deref for Scratch {
    type Target = std::path::Path;
    fn deref(&self) -> &std::path::Path {
        &self.0
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// A copy of the station with external device monitoring (issue 17): the station
/// itself has it (KM0, YV0, their mirrors and every drive's, `CSk1`..`CSk16`).
pub(crate) fn edm_station(tag: &str) -> Scratch {
    Scratch(station_copy(tag))
}

/// A copy of the station as the paper has it: no safety contactor, no safety valve, no
/// mirror contact, no `CSk*` monomial, pushes damage at the first millimetre (to show
/// what external device monitoring changes, and for the checks that enumerate the
/// paper's twelve variables).
pub(crate) fn paper_station(tag: &str) -> Scratch {
    let dir = station_copy(tag);
    paper::strip_device_monitoring(&dir);
    Scratch(dir)
}

/// The paper's station (see [`paper_station`]), loaded: its twelve context variables
/// make the filter's exhaustive checks small.
pub(crate) fn paper_bundle() -> PlantBundle {
    let dir = paper_station("paper-bundle");
    match PlantBundle::load(&dir) {
        Ok((bundle, _)) => bundle,
        Err(p) => panic!(
            "cannot load the paper's station: {}",
            crate::diag::render(&p)
        ),
    }
}

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

/// A copy of the station's folder (programs and scenarios included) in a fresh
/// temporary directory `vigie-<tag>-<pid>`.
pub(crate) fn station_copy(tag: &str) -> PathBuf {
    fn copy_dir(from: &std::path::Path, to: &std::path::Path) {
        std::fs::create_dir_all(to).unwrap();
        for e in std::fs::read_dir(from).unwrap() {
            let e = e.unwrap();
            if e.file_type().unwrap().is_dir() {
                copy_dir(&e.path(), &to.join(e.file_name()));
            } else {
                std::fs::copy(e.path(), to.join(e.file_name())).unwrap();
            }
        }
    }
    let dir = std::env::temp_dir().join(format!("vigie-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    copy_dir(&station_dir(), &dir);
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

/// A copy of the station with external device monitoring (issue 17): a safety contactor
/// KM0 on the conveyor and roller drives' supply, a safety valve YV0 on the turntable's
/// air, a mirror contact on each of them and on every drive (`A0_fb`..`A6_fb`,
/// `KM0_fb`, `YV0_fb`), sixteen monomials `CSk*` that cut the supply of a welded or dead
/// drive, YV0 in the table's actuator partition, and a 10 mm push tolerance. All of it
/// plant data: no code knows these names.
pub(crate) fn edm_station(tag: &str) -> Scratch {
    let dir = station_copy(tag);
    let edit = |file: &str, f: &dyn Fn(String) -> String| {
        let path = dir.join(file);
        let text = std::fs::read_to_string(&path).unwrap();
        let new = f(text.clone());
        assert_ne!(new, text, "{file} unchanged: its anchor moved");
        std::fs::write(path, new).unwrap();
    };
    let drives = ["A0", "A1", "A2", "A3", "A4", "A5", "A6"];
    let supply = |a: &str| if a == "A4" { "YV0" } else { "KM0" };
    let mut mirrors = String::new();
    let mut map = String::new();
    let mut csk = String::from("\n");
    for (k, a) in drives.iter().chain(&["KM0", "YV0"]).enumerate() {
        let d = 11 + k;
        mirrors.push_str(&format!(
            "        (id: \"{a}_fb\", kind: Sensor, description: \"{a} closed (mirror contact)\", address: Some(DiscreteInput({d})), feedback_of: Some(\"{a}\")),\n"
        ));
        map.push_str(&format!(
            "        (signal: \"{a}_fb\", address: DiscreteInput({d})),\n"
        ));
    }
    for (k, a) in drives.iter().enumerate() {
        let s = supply(a);
        csk.push_str(&format!(
            "CSk{} = {s} . {a}_fb . /{a}*   # {a} welded: cut {s}\nCSk{} = {s} . {a}* . /{a}_fb   # {a} dead: cut {s}\n",
            2 * k + 1,
            2 * k + 2
        ));
    }
    csk.push_str("CSk15 = KM0 . KM0* . /KM0_fb   # KM0 dead: every output off until the repair\n");
    csk.push_str("CSk16 = YV0 . YV0* . /YV0_fb   # YV0 dead: every output off until the repair\n");
    let anchor = "        (id: \"A0\", kind: Actuator";
    edit("plant.ron", &|t| {
        t.replacen(anchor, &format!("{mirrors}{anchor}"), 1).replacen(
            "    ],\n)",
            "        (id: \"KM0\", kind: Actuator, description: \"Safety contactor of the drives\", address: Some(Coil(7)), supplies: [\"A0\", \"A1\", \"A2\", \"A3\", \"A5\", \"A6\"], held_on: true, safe: One),\n\
             \x20       (id: \"YV0\", kind: Actuator, description: \"Safety valve of the turntable's air\", address: Some(Coil(8)), supplies: [\"A4\"], held_on: true, safe: One),\n    ],\n)",
            1,
        )
    });
    edit("constraints.txt", &|t| t + &csk);
    edit("io-map.ron", &|t| {
        t.replacen(
            "    ],\n)",
            &format!("{map}        (signal: \"KM0\", address: Coil(7)),\n        (signal: \"YV0\", address: Coil(8)),\n    ],\n)"),
            1,
        )
    });
    edit("diagnosers.ron", &|t| {
        t.replacen(
            "stop: true, actuators: [\"A4\"]",
            "stop: true, actuators: [\"A4\", \"YV0\"]",
            1,
        )
    });
    edit("layout.ron", &|t| {
        t.replacen(
            "    shear_margin_mm: 2,\n",
            "    shear_margin_mm: 2,\n    push_tolerance_mm: 10,\n",
            1,
        )
    });
    Scratch(dir)
}

//! The paper's sorting station derived from the shipped one, for the tests that need
//! its exact shape (eleven sensors, seven actuators, seventeen constraints): the shipped
//! station adds external device monitoring (issue 17). Shared by the core's unit tests
//! and the integration tests (included there by path), so it uses `std` only.

use std::path::Path;

/// Copies the folder `from` into `to`, recursively.
pub(crate) fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).expect("create the copy's folder");
    for e in std::fs::read_dir(from).expect("read the folder to copy") {
        let e = e.expect("folder entry");
        if e.file_type().expect("entry type").is_dir() {
            copy_dir(&e.path(), &to.join(e.file_name()));
        } else {
            std::fs::copy(e.path(), to.join(e.file_name())).expect("copy a file");
        }
    }
}

/// Takes the device monitoring out of a copy of the station in `dir`: the safety
/// contactor KM0, the safety valve YV0, the mirror contacts (`*_fb`), the `CSk*`
/// monomials, YV0 in the table's actuator partition and the push tolerance (pushes
/// damage at the first millimetre, as the paper's station has it). Panics when a file
/// has none of it (the station changed shape: the tests would compare nothing).
pub(crate) fn strip_device_monitoring(dir: &Path) {
    let edm = |l: &str| {
        l.contains("_fb")
            || l.contains("\"KM0\"")
            || l.contains("\"YV0\"")
            || l.starts_with("CSk")
            || l.contains("push_tolerance:")
    };
    for file in [
        "plant.ron",
        "constraints.txt",
        "io-map.ron",
        "components.ron",
    ] {
        let path = dir.join(file);
        let text = std::fs::read_to_string(&path).expect("read a station file");
        let kept: Vec<&str> = text.lines().filter(|l| !edm(l.trim_start())).collect();
        assert_ne!(
            kept.len(),
            text.lines().count(),
            "{file}: no device monitoring to remove"
        );
        std::fs::write(&path, kept.join("\n") + "\n").expect("write a station file");
    }
    let path = dir.join("diagnosers.ron");
    let text = std::fs::read_to_string(&path).expect("read diagnosers.ron");
    let paper = text.replace("actuators: [\"A4\", \"YV0\"]", "actuators: [\"A4\"]");
    assert_ne!(
        paper, text,
        "diagnosers.ron: YV0 not in the table's partition"
    );
    std::fs::write(&path, paper).expect("write diagnosers.ron");
}

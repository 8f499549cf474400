use super::*;
use crate::test_support::station_dir;

/// A copy of the sorting station's folder (programs included) in a fresh directory.
fn station_copy(name: &str) -> PathBuf {
    crate::test_support::station_copy(&format!("bundle-{name}"))
}

fn load(dir: &Path) -> (PlantBundle, Vec<Problem>) {
    match PlantBundle::load(dir) {
        Ok(v) => v,
        Err(p) => panic!("{}", crate::diag::render(&p)),
    }
}

fn codes(problems: &[Problem]) -> Vec<&str> {
    problems.iter().map(|p| p.code).collect()
}

#[test]
fn the_station_is_protected() {
    let (b, problems) = load(&station_dir());
    assert!(b.unprotected().is_none());
    assert!(!codes(&problems).contains(&"V0110"));
}

#[test]
fn no_constraint_file_is_accepted_with_a_loud_warning() {
    let dir = station_copy("absent");
    let path = dir.join("constraints.txt");
    std::fs::remove_file(&path).unwrap();
    let (b, problems) = load(&dir);
    let warning = format!(
        "{}:1:1: warning[V0110]: the plant is unprotected: {} does not exist, so the filter lets every command through",
        path.display(),
        path.display()
    );
    assert_eq!(
        problems.iter().map(ToString::to_string).collect::<Vec<_>>(),
        std::slice::from_ref(&warning)
    );
    assert!(!problems[0].is_error());
    assert_eq!(b.unprotected().map(|p| p.to_string()), Some(warning));
    assert!(b.constraints.constraints.is_empty());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_constraint_file_with_no_constraint_is_accepted_with_a_loud_warning() {
    let dir = station_copy("empty");
    let path = dir.join("constraints.txt");
    for text in [
        "",
        "\n\n",
        "# every constraint commented out\n# CSs1 = 2P . A0\n   \n",
    ] {
        std::fs::write(&path, text).unwrap();
        let (b, problems) = load(&dir);
        assert_eq!(
            problems.iter().map(ToString::to_string).collect::<Vec<_>>(),
            [format!(
                "{}:1:1: warning[V0110]: the plant is unprotected: {} holds no constraint, so the filter lets every command through",
                path.display(),
                path.display()
            )],
            "{text:?}"
        );
        assert!(b.unprotected().is_some());
    }
    // Every line rejected: the errors, and the plant is unprotected as well.
    std::fs::write(&path, "CSs1 = 2P . A9\nnot a constraint\n").unwrap();
    let (b, problems) = load(&dir);
    assert_eq!(codes(&problems), ["V0110", "V0101", "V0108"]);
    assert!(b.unprotected().is_some());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn no_fallback_is_reported_at_the_conflicting_constraints_lines() {
    let dir = station_copy("conflict");
    let path = dir.join("constraints.txt");
    // In C0, A0 and A1 must be ON and not both ON: no output vector.
    std::fs::write(
        &path,
        "# conflict\n\n  X2 = C0 . /A0\nCSs6 = C4 . C6 . A2\nX1 = C0 . A0 . A1\nX3 = C0 . /A1\n",
    )
    .unwrap();
    let (_, problems) = load(&dir);
    let errors: Vec<&Problem> = problems.iter().filter(|p| p.is_error()).collect();
    assert_eq!(errors.len(), 1, "{}", crate::diag::render(&problems));
    let p = errors[0];
    assert_eq!(p.code, "V0107");
    assert_eq!(p.location, Some(crate::diag::Location::new(&path, 3, 3)));
    assert!(
        p.message
            .starts_with("no output vector satisfies every constraint: X1, X2, X3 when "),
        "{}",
        p.message
    );
    assert!(
        p.message
            .ends_with(" (X2 on line 3, X1 on line 5, X3 on line 6)"),
        "{}",
        p.message
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// Writes a sparse 50 MiB file at `path` (no disk, no memory).
fn sparse_50_mib(path: &Path) {
    std::fs::File::create(path)
        .unwrap()
        .set_len(50 * 1024 * 1024)
        .unwrap();
}

#[test]
fn a_50_mib_file_in_the_folder_refuses_it_naming_the_file() {
    let dir = station_copy("large");
    for name in [
        "constraints.txt",
        "plant.ron",
        "observers.ron",
        "invariants.txt",
        "components.ron",
        "diagnosers.ron",
        "tasks.ron",
        "programs/reference.ron",
    ] {
        let path = dir.join(name);
        let saved = std::fs::read(&path).unwrap();
        sparse_50_mib(&path);
        let Err(problems) = PlantBundle::load(&dir) else {
            panic!("{name}: a 50 MiB file was accepted");
        };
        assert_eq!(
            problems.iter().map(ToString::to_string).collect::<Vec<_>>(),
            [format!(
                "error[V0003]: {} is 52428800 bytes (50.0 MiB), more than the limit of 8388608 bytes (8 MiB): not read",
                path.display()
            )],
            "{name}"
        );
        std::fs::write(&path, saved).unwrap();
    }
    load(&dir);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn every_loader_of_the_bundle_refuses_a_large_file_on_its_own() {
    // `from_plant` (used with the diagnosers) and the constraint loaders do not rely on
    // the folder check of `load`.
    let dir = station_copy("large-parts");
    let plant = Plant::load(&dir.join("plant.ron")).unwrap();
    for name in ["observers.ron", "constraints.txt", "invariants.txt"] {
        let path = dir.join(name);
        let saved = std::fs::read(&path).unwrap();
        sparse_50_mib(&path);
        let (_, problems) = PlantBundle::from_plant(&dir, plant.clone(), &[]);
        let too_large = problems.iter().find(|p| p.code == "V0003");
        assert!(
            too_large.is_some_and(|p| p.message.starts_with(&path.display().to_string())),
            "{name}: {}",
            crate::diag::render(&problems)
        );
        std::fs::write(&path, saved).unwrap();
    }
    sparse_50_mib(&dir.join("plant.ron"));
    let Err(problems) = Plant::load(&dir.join("plant.ron")) else {
        panic!("a 50 MiB plant.ron was accepted");
    };
    assert_eq!(codes(&problems), ["V0003"]);
    let _ = std::fs::remove_dir_all(&dir);
}

#[cfg(unix)]
#[test]
fn a_device_in_the_folder_is_not_read() {
    // `observers.ron` pointing at `/dev/zero` (0 bytes, never ends) refuses the folder.
    if !Path::new("/dev/zero").exists() {
        return;
    }
    let dir = station_copy("device");
    let path = dir.join("observers.ron");
    std::fs::remove_file(&path).unwrap();
    std::os::unix::fs::symlink("/dev/zero", &path).unwrap();
    let Err(problems) = PlantBundle::load(&dir) else {
        panic!("a device was read as observers.ron");
    };
    assert_eq!(
        problems.iter().map(ToString::to_string).collect::<Vec<_>>(),
        [format!(
            "error[V0002]: cannot read {}: not a regular file (a device, a pipe or a socket)",
            path.display()
        )]
    );
    // `from_plant` alone (the diagnosers' path) does not read it either.
    let plant = Plant::load(&dir.join("plant.ron")).unwrap();
    let (_, problems) = PlantBundle::from_plant(&dir, plant, &[]);
    assert_eq!(problems[0].code, "V0002");
    let _ = std::fs::remove_dir_all(&dir);
}

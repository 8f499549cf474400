//! A plant folder: `plant.ron`, `observers.ron`, `constraints.txt` (and, for the
//! emulator and the control runtime, `layout.ron` and `programs/`).

use crate::constraints::ConstraintSet;
use crate::diag::Problem;
use crate::diag::codes;
use crate::observers::Observers;
use crate::plant::Plant;
use crate::symbols::Symbols;
use std::path::{Path, PathBuf};

/// Everything the filter needs about one plant.
#[derive(Clone, Debug)]
pub struct PlantBundle {
    /// The folder it was loaded from.
    pub dir: PathBuf,
    /// Signals.
    pub plant: Plant,
    /// Names of inputs, outputs, observers and auxiliaries.
    pub symbols: Symbols,
    /// Observers.
    pub observers: Observers,
    /// Safety constraints.
    pub constraints: ConstraintSet,
    /// Situations the plant cannot reach under the filter (`invariants.txt`).
    pub invariants: ConstraintSet,
    /// Property (6) conflicts shown unreachable by an invariant.
    pub discharged: Vec<crate::constraints::Discharged>,
    /// What the load's check of a fallback in every reachable context proved (per
    /// output component, with support sizes); `None` when it found a context without
    /// any (a `V0107` among the problems).
    pub fallback: Option<crate::filter::FallbackReport>,
    /// Timed task specifications (`tasks.ron`), when the plant has them; their outputs
    /// (`<task>:running`, `:interrupted`, `:infeasible`) are auxiliary variables.
    pub tasks: Option<crate::tasks::TaskSet>,
    /// The sensors' timed plausibility rules, compiled (`plausible` in `plant.ron`).
    pub plausibility: crate::plausibility::Plausibility,
}

/// The files of a plant folder its loaders may read (besides `programs/*.ron`), each
/// checked against [`crate::diag::MAX_FILE_BYTES`] before anything is read.
pub const FOLDER_FILES: [&str; 12] = [
    "plant.ron",
    "components.ron",
    "observers.ron",
    "constraints.txt",
    "invariants.txt",
    "tasks.ron",
    "regions.ron",
    "layout.ron",
    "diagnosers.ron",
    "faults.ron",
    "exercises.ron",
    "io-map.ron",
];

/// The problems of the folder's files that its loaders must not read: larger than
/// [`crate::diag::MAX_FILE_BYTES`] (`V0003`), or a device, a pipe or a socket (`V0002`),
/// found from their metadata only ([`crate::diag::check_size`]).
pub fn refused_files(dir: &Path) -> Vec<Problem> {
    let programs = std::fs::read_dir(dir.join("programs"))
        .map(|entries| {
            let mut v: Vec<PathBuf> = entries
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| p.extension().is_some_and(|x| x == "ron"))
                .collect();
            v.sort();
            v
        })
        .unwrap_or_default();
    FOLDER_FILES
        .iter()
        .map(|f| dir.join(f))
        .chain(programs)
        .filter_map(|p| crate::diag::check_size(&p).err())
        .collect()
}

impl PlantBundle {
    /// Loads a plant folder. Returns the bundle (possibly partial) with every problem
    /// found, or only problems when the plant file itself cannot be used.
    /// A file of the folder larger than [`crate::diag::MAX_FILE_BYTES`], or not a
    /// regular file, refuses the folder before any file is read ([`refused_files`]).
    pub fn load(dir: &Path) -> Result<(Self, Vec<Problem>), Vec<Problem>> {
        let refused = refused_files(dir);
        if !refused.is_empty() {
            return Err(refused);
        }
        let plant = Plant::load(&dir.join("plant.ron"))?;
        let (tasks, mut problems) = crate::tasks::TaskSet::load_optional(dir);
        let aux = tasks
            .as_ref()
            .map(crate::tasks::TaskSet::aux_names)
            .unwrap_or_default();
        let (mut bundle, mut more) = Self::from_plant(dir, plant, &aux);
        bundle.tasks = tasks;
        problems.append(&mut more);
        Ok((bundle, problems))
    }

    /// Builds a bundle around a loaded plant; `aux` names are declared as auxiliary
    /// variables before the observers and constraints are resolved (diagnoser flags,
    /// interval variables, estimates, task monitor outputs).
    pub fn from_plant(dir: &Path, plant: Plant, aux: &[String]) -> (Self, Vec<Problem>) {
        let mut symbols = plant.symbols();
        for name in crate::plausibility::suspect_names(&plant).iter().chain(aux) {
            let _ = symbols.declare(name, crate::symbols::Space::Aux);
        }
        let mut problems = Vec::new();
        let observers_path = dir.join("observers.ron");
        let (observers, mut p) = match crate::diag::check_size(&observers_path) {
            Ok(()) => Observers::load(&observers_path, &mut symbols),
            Err(p) => (Observers::empty(), vec![p]),
        };
        problems.append(&mut p);
        let constraints_path = dir.join("constraints.txt");
        let exists = std::fs::symlink_metadata(&constraints_path).is_ok();
        let constraints_at = problems.len();
        let (mut constraints, mut p) = if exists {
            ConstraintSet::load(&constraints_path, &symbols)
        } else {
            (ConstraintSet::default(), Vec::new())
        };
        problems.append(&mut p);
        // A suspect sensor (an implausible edge held) is read as possibly either value.
        problems.extend(crate::plausibility::suspect_constraints(
            &mut constraints,
            &plant,
            &symbols,
        ));
        let (invariants, mut p) =
            ConstraintSet::load_invariants(&dir.join("invariants.txt"), &symbols);
        problems.append(&mut p);
        let (mut p, discharged) = constraints.check_property_6(&symbols, &invariants);
        problems.append(&mut p);
        let plausibility = match crate::plausibility::Plausibility::new(&plant, &symbols) {
            Ok(p) => p,
            Err(mut p) => {
                for q in &mut p {
                    q.location.get_or_insert_with(|| {
                        crate::diag::Location::new(&dir.join("plant.ron"), 1, 1)
                    });
                }
                problems.append(&mut p);
                crate::plausibility::Plausibility::default()
            }
        };
        let filter = crate::filter::Filter::for_plant(&constraints, &plant);
        let fallback = match crate::filter::fallback_report(&filter, &symbols, &invariants) {
            Ok(report) => Some(report),
            Err((err, witness)) => {
                problems.push(conflict_problem(
                    &constraints,
                    &constraints_path,
                    &err,
                    &witness,
                ));
                None
            }
        };
        let bundle = Self {
            dir: dir.to_path_buf(),
            plant,
            symbols,
            observers,
            constraints,
            invariants,
            discharged,
            fallback,
            tasks: None,
            plausibility,
        };
        // Said before the other problems of the constraints: it matters most.
        if let Some(warning) = bundle.unprotected() {
            problems.insert(constraints_at, warning);
        }
        (bundle, problems)
    }

    /// The `V0110` warning when no safety constraint protects the plant: its
    /// `constraints.txt` is absent, empty, or every line of it was rejected (the stops
    /// the diagnosers add, `DSTOP_…`, are not safety constraints). The filter then lets
    /// every command through. The load reports it among its problems, and the console
    /// shows it as a banner.
    pub fn unprotected(&self) -> Option<Problem> {
        let path = self.dir.join("constraints.txt");
        let generated = |c: &crate::constraints::Constraint| {
            crate::pop::coop::is_diagnoser_stop(&c.id) && c.location.file != path
        };
        if !self.constraints.constraints.iter().all(generated) {
            return None;
        }
        let exists = std::fs::symlink_metadata(&path).is_ok();
        Some(unprotected_warning(&path, exists))
    }
}

/// The `V0110` warning: no constraint protects the plant.
fn unprotected_warning(path: &Path, exists: bool) -> Problem {
    let why = if exists {
        "holds no constraint"
    } else {
        "does not exist"
    };
    Problem::warning(
        codes::PLANT_UNPROTECTED.id,
        format!(
            "the plant is unprotected: {} {why}, so the filter lets every command through",
            path.display()
        ),
        Some(crate::diag::Location::new(path, 1, 1)),
    )
}

/// The `V0107` error of a context with no fallback vector, at the first (in file
/// order) of the conflicting constraints, the message giving the line of each.
fn conflict_problem(
    set: &ConstraintSet,
    path: &Path,
    err: &crate::filter::SpecError,
    witness: &str,
) -> Problem {
    let mut located: Vec<&crate::constraints::Constraint> = err
        .constraints
        .iter()
        .filter_map(|id| set.get(id))
        .collect();
    located.sort_by_key(|c| (c.location.line, c.location.column));
    let lines = located
        .iter()
        .map(|c| format!("{} on line {}", c.id, c.location.line))
        .collect::<Vec<_>>()
        .join(", ");
    let location = located.first().map_or_else(
        || crate::diag::Location::new(path, 1, 1),
        |c| c.location.clone(),
    );
    Problem::error(
        codes::NO_FALLBACK.id,
        format!("{err} when {witness} ({lines})"),
        Some(location),
    )
}

#[cfg(test)]
mod tests;

//! A plant folder: `plant.ron`, `observers.ron`, `constraints.txt` (and, for the
//! emulator and the control runtime, `layout.ron` and `programs/`).

use crate::constraints::ConstraintSet;
use crate::diag::Problem;
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
    /// Timed task specifications (`tasks.ron`), when the plant has them; their outputs
    /// (`<task>:running`, `:interrupted`, `:infeasible`) are auxiliary variables.
    pub tasks: Option<crate::tasks::TaskSet>,
}

impl PlantBundle {
    /// Loads a plant folder. Returns the bundle (possibly partial) with every problem
    /// found, or only problems when the plant file itself cannot be used.
    pub fn load(dir: &Path) -> Result<(Self, Vec<Problem>), Vec<Problem>> {
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
        for name in aux {
            let _ = symbols.declare(name, crate::symbols::Space::Aux);
        }
        let mut problems = Vec::new();
        let (observers, mut p) = Observers::load(&dir.join("observers.ron"), &mut symbols);
        problems.append(&mut p);
        let (constraints, mut p) = ConstraintSet::load(&dir.join("constraints.txt"), &symbols);
        problems.append(&mut p);
        let (invariants, mut p) =
            ConstraintSet::load_invariants(&dir.join("invariants.txt"), &symbols);
        problems.append(&mut p);
        let (mut p, discharged) = constraints.check_property_6(&symbols, &invariants);
        problems.append(&mut p);
        let filter = crate::filter::Filter::for_plant(&constraints, &plant);
        if let Err((err, witness)) =
            crate::filter::check_fallback_exists(&filter, &symbols, &invariants)
        {
            problems.push(Problem::error(
                "V0107",
                format!("{err} when {witness}"),
                Some(crate::diag::Location::new(
                    &dir.join("constraints.txt"),
                    1,
                    1,
                )),
            ));
        }
        (
            Self {
                dir: dir.to_path_buf(),
                plant,
                symbols,
                observers,
                constraints,
                invariants,
                discharged,
                tasks: None,
            },
            problems,
        )
    }
}

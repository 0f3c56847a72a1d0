//! The checks of one plan as tasks, in whatever order and on whatever
//! thread the application runs them: the cheap checks first (the geometric
//! ones run only when the cheap ones allow), then the costly ones, the
//! longest first; each task keeps its findings in its own slot, and
//! [`Tasks::merged`] puts them together in the one fixed order of
//! [`super::merge`]. A new check is a module and one [`Task`] here.

use std::sync::OnceLock;

use super::{first_layer, merge, Cheap, Costly, Finding};
use crate::base::toolpath::Toolpath;
use crate::generate::model::Recipe;

/// One check to run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Task {
    /// The machine's limits, speeds and flows, cross-sections, events.
    Cheap,
    /// Strings that rest on nothing, and bridges ([`super::support`]).
    Support,
    /// The first layer's area on the bed (half of [`first_layer`]).
    FirstLayerArea,
    /// The head meeting printed filament ([`super::collision`]).
    Collision,
    /// The first layer's contacts (the other half of [`first_layer`]).
    FirstLayerContacts,
    /// Runs of moves too short for the firmware ([`super::starvation`]).
    Starvation,
}

impl Task {
    /// The order tasks are taken in: the cheap checks (the geometric ones
    /// wait for them), then the longest first, so the last to finish is a
    /// short one; the first layer in two halves, each shorter than the
    /// support check.
    pub(crate) const ORDER: [Task; 6] = [
        Task::Cheap,
        Task::Support,
        Task::FirstLayerArea,
        Task::Collision,
        Task::FirstLayerContacts,
        Task::Starvation,
    ];

    /// Whether it needs the cheap checks' verdict ([`Tasks::geometric`]):
    /// its grids grow with the extent and the cross-sections.
    pub(crate) fn geometric(self) -> bool {
        !matches!(self, Task::Cheap | Task::Starvation)
    }
}

/// The checks of one plan, each task's result in its own slot (see the
/// module comment).
pub(crate) struct Tasks<'a> {
    recipe: &'a Recipe,
    paths: Vec<&'a Toolpath>,
    allowed: Vec<String>,
    cheap: OnceLock<Cheap>,
    starvation: OnceLock<Vec<Finding>>,
    support: OnceLock<Vec<Finding>>,
    collision: OnceLock<Vec<Finding>>,
    /// The first layer's strings on the bed, found by whichever half comes
    /// first, and the halves' results.
    bed: OnceLock<first_layer::Bed>,
    contacts: OnceLock<Vec<Option<first_layer::Contact>>>,
    areas: OnceLock<Vec<u64>>,
    /// The first layer's findings and footprints, from both halves, made
    /// once however often the findings are merged.
    first_layer: OnceLock<(Vec<Finding>, Vec<first_layer::Footprint>)>,
}

impl<'a> Tasks<'a> {
    /// The checks of `paths` printed from `recipe`; `allowed` are the codes
    /// silenced (an error of theirs does not stop the costly checks).
    pub(crate) fn new(
        recipe: &'a Recipe,
        paths: Vec<&'a Toolpath>,
        allowed: Vec<String>,
    ) -> Tasks<'a> {
        Tasks {
            recipe,
            paths,
            allowed,
            cheap: OnceLock::new(),
            starvation: OnceLock::new(),
            support: OnceLock::new(),
            collision: OnceLock::new(),
            bed: OnceLock::new(),
            contacts: OnceLock::new(),
            areas: OnceLock::new(),
            first_layer: OnceLock::new(),
        }
    }

    /// Whether the geometric checks run: `None` until [`Task::Cheap`] has.
    pub(crate) fn geometric(&self) -> Option<bool> {
        self.cheap.get().map(|c| c.geometric)
    }

    /// Runs `task`. A geometric task runs after [`Task::Cheap`] (the caller
    /// orders them, see [`Task::geometric`]), and only when it allows.
    pub(crate) fn run(&self, task: Task) {
        let (recipe, paths) = (self.recipe, &self.paths[..]);
        let nozzle = recipe.printer.nozzle_diameter;
        if task.geometric() && self.geometric() != Some(true) {
            return;
        }
        match task {
            Task::Cheap => {
                let _ = self.cheap.set(super::cheap(recipe, paths, &self.allowed));
            }
            Task::Starvation => {
                let _ = self.starvation.set(super::starvation::check(recipe, paths));
            }
            Task::Support => {
                let _ = self.support.set(super::support::check(recipe, paths));
            }
            Task::Collision => {
                let _ = self.collision.set(super::collision::check(recipe, paths));
            }
            Task::FirstLayerContacts => {
                let bed = self.bed.get_or_init(|| first_layer::Bed::of(paths, nozzle));
                let min_h = first_layer::min_height(recipe);
                let _ = self.contacts.set(bed.contacts(paths, min_h));
            }
            Task::FirstLayerArea => {
                let bed = self.bed.get_or_init(|| first_layer::Bed::of(paths, nozzle));
                let _ = self.areas.set(bed.areas(paths, nozzle));
            }
        }
    }

    /// The findings in the one fixed order, and the footprints; every task
    /// must have run.
    pub(crate) fn merged(&self) -> (Vec<Finding>, Vec<first_layer::Footprint>) {
        let cheap = self.cheap.get().expect("the cheap checks ran");
        let cheap = Cheap {
            findings: cheap.findings.clone(),
            pattern: cheap.pattern.clone(),
            geometric: cheap.geometric,
        };
        let take = |s: &OnceLock<Vec<Finding>>| s.get().cloned().unwrap_or_default();
        let mut costly = Costly {
            starvation: take(&self.starvation),
            support: take(&self.support),
            collision: take(&self.collision),
            ..Costly::default()
        };
        if let (Some(c), Some(a)) = (self.contacts.get(), self.areas.get()) {
            let (f, p) = self
                .first_layer
                .get_or_init(|| first_layer::findings(self.recipe, &self.paths, c, a));
            (costly.first_layer, costly.footprints) = (f.clone(), p.clone());
        }
        merge(cheap, costly)
    }

    /// Whether the findings, every task done, fail a build at this
    /// strictness (the codes silenced left out).
    pub(crate) fn fail(&self, strict: bool) -> bool {
        let (mut all, _) = self.merged();
        super::apply_allow(&mut all, &self.allowed);
        !super::failing(&all, strict).is_empty()
    }
}

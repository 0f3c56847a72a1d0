//! `p3dp mesh`: the toolpath as solid beads (see [`crate::output::mesh`]);
//! as with `preview`, a recipe that fails its checks is meshed too.

use std::path::PathBuf;

use super::{file_stem, make_parent, non_empty, recipe_name, Builds};
use crate::base::error::{Error, Result};

/// What `mesh` takes from the command line.
#[derive(Clone, Debug, Default)]
pub(crate) struct Options {
    /// The one recipe and how it is built.
    pub(crate) builds: Builds,
    /// `-o FILE.stl|FILE.3mf|FILE.obj` (default ./NAME.stl).
    pub(crate) output: Option<PathBuf>,
}

/// Writes the mesh; the errors met.
pub(crate) fn run(a: &Options) -> Vec<Error> {
    match write(a) {
        Ok(()) => Vec::new(),
        Err(e) => vec![e],
    }
}

fn write(a: &Options) -> Result<()> {
    let recipe = &a.builds.recipes[0];
    let out = match &a.output {
        Some(o) => o.clone(),
        None => PathBuf::from(format!("{}.stl", file_stem(&recipe_name(recipe)?))),
    };
    non_empty("-o", Some(&out))?;
    crate::output::mesh::write::Format::of(&out)?;
    let outs = [("-o".to_string(), out.clone())];
    crate::output::file::check_distinct(&outs, &a.builds.inputs())?;
    let p = a.builds.plan_one(&outs)?;
    make_parent(&out)?;
    crate::sayln!("{}", crate::output::mesh::write::write(&p, &out)?);
    Ok(())
}

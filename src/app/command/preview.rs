//! `p3dp preview`: the toolpath drawn to a PNG image or an HTML viewer; a
//! recipe that fails its checks is drawn too (`--color findings` shows
//! where).

use std::path::PathBuf;

use super::{file_stem, make_parent, non_empty, recipe_name, Builds};
use crate::app::pipeline;
use crate::base::error::{Error, Result};
use crate::machine::size::Size;
use crate::output::preview::{ColorMode, View};

/// What `preview` takes from the command line.
#[derive(Clone, Debug, Default)]
pub(crate) struct Options {
    /// The one recipe and how it is built.
    pub(crate) builds: Builds,
    /// `-o FILE.png|FILE.html` (default ./NAME.png).
    pub(crate) output: Option<PathBuf>,
    /// `--view`.
    pub(crate) view: View,
    /// `--color`.
    pub(crate) color: ColorMode,
    /// `--size WxH`.
    pub(crate) size: Size,
    /// `--bare`: the model alone.
    pub(crate) bare: bool,
}

/// Draws the preview; the errors met.
pub(crate) fn run(a: &Options) -> Vec<Error> {
    match draw(a) {
        Ok(()) => Vec::new(),
        Err(e) => vec![e],
    }
}

fn draw(a: &Options) -> Result<()> {
    let opts = crate::output::preview::Options {
        view: a.view,
        color: a.color,
        size: a.size,
        bare: a.bare,
    };
    let recipe = &a.builds.recipes[0];
    let out = match &a.output {
        Some(o) => o.clone(),
        None => PathBuf::from(format!("{}.png", file_stem(&recipe_name(recipe)?))),
    };
    crate::output::preview::Format::of(&out)?;
    non_empty("-o", Some(&out))?;
    let outs = [("-o".to_string(), out.clone())];
    crate::output::file::check_distinct(&outs, &a.builds.inputs())?;
    let p = a.builds.plan_one(&outs)?;
    make_parent(&out)?;
    crate::sayln!("{}", pipeline::preview(&p, &out, &opts)?.write()?);
    Ok(())
}

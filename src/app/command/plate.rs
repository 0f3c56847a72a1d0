//! `p3dp plate RECIPE[*N]… [--sweep …]`: a plate from the command line,
//! for shell scripts: the same [`PlateSpec`] a plate file gives (its
//! entries the recipes, each `N` times, every one with the `--sweep`
//! variants), built as `p3dp build` builds one: the same bytes as the plate
//! file written the same way.

use std::path::PathBuf;
use std::sync::Arc;

use crate::base::error::{Error, Result};
use crate::recipe::resolve::plate::{PlateEntry, PlateSpec, MAX_COPIES};

/// What `plate` takes from the command line.
#[derive(Clone, Debug, Default)]
pub(crate) struct Options {
    /// `RECIPE` or `RECIPE*N`, in order.
    pub(crate) recipes: Vec<String>,
    /// `--name`: the plate's.
    pub(crate) name: String,
    /// `--sweep NAME=VALUES`: variants on the plate, for every recipe.
    pub(crate) sweeps: Vec<(String, Vec<String>)>,
    /// How it is built and written (its `builds` hold `--set`, `--printer`…).
    pub(crate) build: super::build::Options,
}

/// The plate the command line describes.
pub(crate) fn spec(o: &Options) -> Result<PlateSpec> {
    if o.recipes.is_empty() {
        return Err(Error::input(
            "",
            "no recipe given; expected RECIPE or RECIPE*N (N copies), one or more",
        ));
    }
    crate::base::safe_text::check("--name", &o.name)?;
    if o.name.trim().is_empty() {
        return Err(Error::input("--name", "expected a non-empty name"));
    }
    let mut entries = Vec::with_capacity(o.recipes.len());
    for arg in &o.recipes {
        let (file, copies) = copies(arg)?;
        entries.push(PlateEntry {
            recipe: PathBuf::from(file),
            name: None,
            copies,
            sets: Vec::new(),
            sweeps: o.sweeps.clone(),
            at: None,
            place: arg.clone(),
        });
    }
    Ok(PlateSpec {
        name: o.name.clone(),
        printer: None,
        material: None,
        allow: Vec::new(),
        entries,
        dir: PathBuf::new(),
        named: true,
    })
}

/// `RECIPE*N`: the file and N (1 without `*N`).
fn copies(arg: &str) -> Result<(&str, u32)> {
    let Some((file, n)) = arg.rsplit_once('*') else {
        return Ok((arg, 1));
    };
    match n.parse::<u32>() {
        Ok(k) if (1..=MAX_COPIES).contains(&k) && !file.is_empty() => Ok((file, k)),
        _ => Err(Error::input(
            arg,
            format!("`{n}` is not a number of copies; expected RECIPE*N with N from 1 to {MAX_COPIES}, e.g. pot.yaml*4"),
        )),
    }
}

/// `p3dp plate`: builds the plate as `p3dp build` builds one recipe.
pub(crate) fn run(o: &Options) -> Vec<Error> {
    let spec = match spec(o) {
        Ok(s) => s,
        Err(e) => return vec![e],
    };
    let mut b = o.build.clone();
    b.builds.plate = Some(Arc::new(spec));
    super::build::run(&b)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn recipes_and_their_copies() {
        assert_eq!(copies("pot.yaml").unwrap(), ("pot.yaml", 1));
        assert_eq!(copies("a/pot.yaml*4").unwrap(), ("a/pot.yaml", 4));
        assert!(copies("pot.yaml*0").is_err());
        assert!(copies("pot.yaml*x").is_err());
        let o = Options {
            recipes: vec!["pot.yaml*2".into(), "vase.yaml".into()],
            name: "pots".into(),
            sweeps: vec![("h".into(), vec!["1".into(), "2".into()])],
            ..Options::default()
        };
        let s = spec(&o).unwrap();
        assert_eq!(s.entries.len(), 2);
        assert_eq!(s.entries[0].copies, 2);
        assert_eq!(s.entries[1].sweeps, o.sweeps);
        assert!(s.named);
    }
}

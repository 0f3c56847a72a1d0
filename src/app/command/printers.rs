//! `p3dp printers`: the built-in printer profiles; `p3dp printers list
//! FILE` and `p3dp printers import FILE`: a slicer's printer presets.

use std::path::PathBuf;

use crate::base::error::{Error, Result};
use crate::base::input::Reads;
use crate::recipe::preset::{self, Source};

/// `p3dp printers`: one line per built-in profile (name, flavour, bed,
/// origin of recipe (0, 0, 0), nozzle and filament), under a header line.
pub(crate) fn list() -> String {
    use crate::base::format::fmt_num;
    use crate::recipe::profile::built_in_names;
    let mut out = format!(
        "{:<14} {:<8} {:<26} {:<14} {:<7} {}\n",
        "NAME", "FLAVOUR", "BED", "ORIGIN", "NOZZLE", "FILAMENT"
    );
    for name in built_in_names() {
        let p = crate::recipe::profile::built_in(name).expect("built-in profiles parse");
        let origin = p.origin.map(fmt_num).join(", ");
        out.push_str(&format!(
            "{:<14} {:<8} {:<26} {:<14} {:<7} {}\n",
            name,
            p.flavor.name(),
            p.bed.describe(),
            origin,
            fmt_num(p.nozzle_diameter),
            fmt_num(p.filament_diameter)
        ));
    }
    out.push_str("Use one with --printer NAME, or a YAML file (--printer FILE; `inherits: NAME` starts from a built-in one),\nor a slicer's printer preset (--printer FILE.ini|FILE.json; `p3dp printers import` makes it a YAML file).\n");
    out
}

/// `p3dp printers list FILE [--filaments]`: the printer (filament) presets
/// a slicer's file holds, one a line.
pub(crate) fn presets(kind: preset::Kind, file: &std::path::Path) -> Result<String> {
    let names = preset::list_of(kind, file, &Reads::default())?;
    let mut out = String::new();
    for n in names {
        out.push_str(&crate::base::safe_text::one_line(&n));
        out.push('\n');
    }
    Ok(out)
}

/// What `p3dp printers import` is asked.
#[derive(Clone, Debug, Default)]
pub(crate) struct Import {
    /// Where the preset is.
    pub(crate) source: Source,
    /// `-o OUT.yaml`; standard output when `None`.
    pub(crate) output: Option<PathBuf>,
}

/// `p3dp printers import FILE`: the preset as a p3dp printer profile
/// (YAML), checked by loading it as `--printer` would, written to `-o` (the
/// preset and its parents never overwritten) or returned for standard
/// output; the import's notes go to standard error.
pub(crate) fn import(opts: &Import) -> Result<Option<String>> {
    let reads = Reads::default();
    let p = preset::load(&opts.source, &reads)?;
    let imported = preset::map::import(&p)?;
    // the same checks as a build's: the profile loads and validates
    let printer = crate::recipe::profile::from_raw(imported.raw.clone(), &p.file)?;
    for note in &imported.notes {
        crate::tell!("note: {}\n", crate::base::safe_text::one_line(note));
    }
    let yaml = imported.yaml();
    let Some(out) = &opts.output else {
        return Ok(Some(yaml));
    };
    let inputs: Vec<(String, PathBuf)> = reads
        .files()
        .into_iter()
        .map(|f| ("the preset".to_string(), f))
        .collect();
    crate::output::file::check_distinct(&[("-o".to_string(), out.clone())], &inputs)?;
    super::make_parent(out)?;
    crate::output::file::write_atomic(out, |f| {
        use std::io::Write;
        f.write_all(yaml.as_bytes()).map_err(|e| {
            Error::io_from(
                out.display().to_string(),
                format!("cannot write the profile: {e}"),
                &e,
            )
        })
    })?;
    crate::tell!(
        "wrote {} (printer `{}`); use it with --printer {}\n",
        out.display(),
        crate::base::safe_text::one_line(&printer.name),
        out.display()
    );
    Ok(None)
}

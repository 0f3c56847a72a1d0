//! `p3dp printers`: the built-in printer profiles.

/// `p3dp printers`: one line per built-in profile (name, flavour, bed,
/// origin of recipe (0, 0, 0), nozzle and filament), under a header line.
pub(crate) fn list() -> String {
    use crate::base::format::fmt_num;
    use crate::machine::Printer;
    use crate::recipe::profile::built_in_names;
    let mut out = format!(
        "{:<13} {:<8} {:<26} {:<14} {:<7} {}\n",
        "NAME", "FLAVOUR", "BED", "ORIGIN", "NOZZLE", "FILAMENT"
    );
    for name in built_in_names() {
        let p = Printer::built_in(name).expect("built-in profiles parse");
        let origin = p.origin.map(fmt_num).join(", ");
        out.push_str(&format!(
            "{:<13} {:<8} {:<26} {:<14} {:<7} {}\n",
            name,
            p.flavor.name(),
            p.bed.describe(),
            origin,
            fmt_num(p.nozzle_diameter),
            fmt_num(p.filament_diameter)
        ));
    }
    out.push_str("Use one with --printer NAME, or a YAML file (--printer FILE; `inherits: NAME` starts from a built-in one).\n");
    out
}

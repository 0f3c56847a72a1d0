//! The `output-package` warning (`analyse::check::package`) on the
//! built-in profiles: which package each printer's firmware reads. Here,
//! not beside it: the check's folder holds no printer names (the test of
//! `p3dp explain` reads its hyphenated strings as check codes).

use crate::analyse::check::package::{output_package, Packed};
use crate::base::finding::Severity;
use crate::machine::{Flavor, Printer};

fn printer(name: &str) -> Printer {
    crate::recipe::profile::built_in(name).unwrap()
}

#[test]
fn bgcode_suits_buddy_printers_only() {
    for p in ["prusa-mk4s", "prusa-mk4", "prusa-mini", "prusa-core-one"] {
        assert_eq!(output_package(Packed::Bgcode, &printer(p)), None, "{p}");
    }
    for p in ["prusa-mk3s", "ender3", "voron-350", "bambu-a1"] {
        let f = output_package(Packed::Bgcode, &printer(p)).unwrap_or_else(|| panic!("{p}"));
        assert_eq!((f.code, f.severity), ("output-package", Severity::Warning));
        assert!(f.message.contains(&format!("`{p}`")), "{}", f.message);
    }
    // a profile that says it writes binary G-code is taken at its word
    let mut p = printer("generic-220");
    p.binary_gcode = true;
    assert_eq!(output_package(Packed::Bgcode, &p), None);
    // an input shaper preset's model, MK4IS
    let mut p = printer("prusa-mk4");
    p.model = "MK4IS".into();
    assert_eq!(output_package(Packed::Bgcode, &p), None);
}

#[test]
fn a_gcode_3mf_suits_bambu_printers_only() {
    for p in ["bambu-a1", "bambu-a1-mini", "bambu-x1c", "bambu-p1s"] {
        assert_eq!(output_package(Packed::Bambu, &printer(p)), None, "{p}");
    }
    for p in ["prusa-mk4s", "creality-k1", "generic-220"] {
        let f = output_package(Packed::Bambu, &printer(p)).unwrap_or_else(|| panic!("{p}"));
        assert!(f.message.contains("Bambu"), "{}", f.message);
    }
    // a profile of the bambu flavour, or a model of theirs as the
    // makers' presets name it
    let mut p = printer("generic-220");
    p.flavor = Flavor::Bambu;
    assert_eq!(output_package(Packed::Bambu, &p), None);
    for model in ["Bambu Lab H2D", "Bambu Lab A1 mini", "BL-P001"] {
        let mut p = printer("generic-220");
        p.model = model.into();
        assert_eq!(output_package(Packed::Bambu, &p), None, "{model}");
    }
}

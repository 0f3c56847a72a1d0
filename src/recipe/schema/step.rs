//! A step as written: deformations, modulations, subdivision, translation.

use serde::Deserialize;

use super::num::{Num, Num3};

/// `keep:` of a modulation.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
#[allow(missing_docs)]
pub enum RawKeep {
    Flow,
    Speed,
}

/// The keys of `deform_xyz` and `deform_cylinder`.
#[derive(Clone, Debug, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
#[allow(missing_docs)]
pub struct RawDeform {
    #[serde(default)]
    pub position: Option<Num3>,
    #[serde(default)]
    pub cross_section: Option<Num>,
    #[serde(default)]
    pub speed: Option<Num>,
}

/// A step as written.
#[derive(Clone, Debug, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
#[allow(missing_docs)]
pub enum RawStep {
    DeformXyz(RawDeform),
    DeformCylinder(RawDeform),
    ModulateCylinder {
        factor: Num,
        #[serde(default)]
        keep: Option<RawKeep>,
    },
    ModulateMap {
        #[serde(default)]
        image: Option<String>,
        #[serde(default)]
        text: Option<String>,
        u: Num,
        v: Num,
        #[serde(default)]
        dark: Option<Num>,
        #[serde(default)]
        light: Option<Num>,
        #[serde(default)]
        threshold: Option<Num>,
        #[serde(default)]
        keep: Option<RawKeep>,
    },
    Subdivide {
        max_length: Num,
    },
    Translate(Num3),
}

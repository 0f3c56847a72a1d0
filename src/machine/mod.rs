//! The machine model: a printer profile (bed, flavour, head, planner
//! limits, check thresholds, thumbnail sizes) and a material. Data only:
//! [`crate::recipe::profile`] reads profiles from YAML.

pub(crate) mod firmware;
pub(crate) mod head;
pub(crate) mod kinematics;
pub(crate) mod limits;
pub(crate) mod material;
pub(crate) mod printer;
pub(crate) mod size;
pub(crate) mod travel;

pub(crate) use head::{CheckLimits, Gantry, Head};
pub(crate) use kinematics::Kinematics;
pub(crate) use material::{Material, FAN_START_Z};
pub(crate) use printer::{Bed, Extrusion, Flavor, Printer, Retraction};
pub(crate) use size::Size;

//! The machine model: a printer profile (bed, flavour, head, planner
//! limits, check thresholds, thumbnail sizes) and a material. Data only:
//! [`crate::recipe::profile`] reads profiles from YAML.

pub mod head;
pub mod kinematics;
pub mod limits;
pub mod material;
pub mod printer;
pub mod size;
pub mod travel;

pub use head::{CheckLimits, Head};
pub use kinematics::{Kinematics, Limits};
pub use material::{Material, FAN_START_Z};
pub use printer::{Bed, Envelope, Extrusion, Flavor, Printer, Retraction, PLACEHOLDERS, VARIABLES};
pub use size::Size;

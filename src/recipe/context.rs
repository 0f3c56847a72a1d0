//! What loading one recipe shares with the command that asked for it,
//! passed down explicitly (no state of a thread's own): the files it read,
//! and what a long-running command keeps from one build for the next (the
//! solids' z-buffers, the parts made).

use crate::base::input::Reads;
use crate::generate::assembly::Parts;
use crate::generate::primitive::solid::Reusing;

/// The context of one load: [`Context::default`] keeps nothing for later.
#[derive(Debug, Default)]
pub struct Context {
    /// Every file the load read or tried (recipe, includes, images, SVGs,
    /// printer profiles and what they inherit).
    pub reads: Reads,
    /// The z-buffers of the build before, for its solids to start from
    /// (`p3dp watch`).
    pub(crate) zbuffers: Option<Reusing>,
    /// The parts of the build before, each taken back when its inputs are
    /// unchanged (`p3dp watch`).
    pub(crate) parts: Option<Parts>,
}

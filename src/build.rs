//! Writing a plan: its G-code (with the printer's thumbnails), hashed as it
//! goes, and the stats of what was written.

use std::io::{self, Write};

use crate::error::{Error, Result};
use crate::gcode::{Emitter, MoveStats};
pub use crate::model::make_part;
use crate::output::HashWriter;
pub use crate::plan::{plan, Options, Plan};
use crate::stats::{PartStats, Stats};
use crate::toolpath::Toolpath;

impl Plan {
    /// Writes the G-code to `out`.
    pub fn write_gcode<W: Write>(&self, out: W) -> Result<(W, MoveStats)> {
        let io =
            |e: io::Error| Error::io_from(&self.path, format!("cannot write the G-code: {e}"), &e);
        let top = self.top_z();
        let mut em = Emitter::new(out, &self.recipe, self.threads);
        em.thumbnails = crate::preview::thumbnail::blocks(self)?;
        let fan_events = |t: &Toolpath| {
            t.events
                .iter()
                .any(|(_, e)| matches!(e, crate::toolpath::Event::Fan { .. }))
        };
        if self.paths.iter().any(fan_events) {
            em.manual_fan();
        }
        em.start(&self.recipe, top)?;
        for tp in &self.paths {
            em.part(tp).map_err(io)?;
        }
        em.finish(&self.recipe, top)
    }

    /// Writes the G-code to `out`, hashing it, and returns the stats.
    pub fn render<W: Write>(&self, out: W) -> Result<Stats> {
        let (hw, moves) = self.write_gcode(HashWriter::new(out))?;
        let (digest, bytes) = hw.finish();
        let parts = self
            .paths
            .iter()
            .zip(&moves.estimate.parts)
            .map(|(t, pt)| PartStats {
                name: t.name.clone(),
                strings: t.len(),
                print_time_s: pt.times.planned,
                time_lost_s: pt.times.lost(),
            })
            .collect();
        let mut stats = Stats::new(
            &self.path,
            &self.recipe,
            &moves,
            parts,
            digest,
            bytes,
            self.findings.clone(),
        );
        stats.first_layer = self.footprints.clone();
        Ok(stats)
    }
}

//! `p3dp check`: every check of every job, printed; nothing written.

use super::{job_label, plural, Builds};
use crate::app::batch;
use crate::base::error::Error;

/// `p3dp check`: runs every check and prints the findings; writes nothing.
pub(crate) fn run(c: &Builds) -> Vec<Error> {
    let jobs = match c.jobs() {
        Ok(j) => j,
        Err(e) => return vec![e],
    };
    let results = batch::run_parallel(
        jobs.len(),
        |k| {
            let mut p = c.prepared(&jobs[k], &[])?;
            crate::app::pipeline::check(&mut p, &c.allow);
            Ok(p)
        },
        || {},
    );
    let mut errors = Vec::new();
    for (job, r) in jobs.iter().zip(results) {
        match r {
            Ok(p) => {
                crate::sayln!(
                    "{}: {}",
                    job_label(job),
                    crate::analyse::check::summary(&p.findings)
                );
                for f in &p.findings {
                    crate::sayln!("  {} [{}]: {}", f.severity.word(), f.code, f.message);
                }
                let failing = p.failing(c.strict).len();
                if failing > 0 {
                    errors.push(Error::check(
                        &p.path,
                        format!("{failing} check{} failed", plural(failing)),
                    ));
                } else if let Err(e) = p.frame_ok() {
                    // the profile's start or end G-code: unsafe for this print
                    errors.push(e);
                }
            }
            Err(e) => errors.push(e),
        }
    }
    errors
}

//! `p3dp check`: every check of every job, printed; nothing written.

use super::{job_label, plural, Builds};
use crate::app::batch;
use crate::base::error::{Error, Result};

/// `p3dp check`: runs every check and prints the findings; writes nothing.
pub(crate) fn run(c: &Builds) -> Vec<Error> {
    let jobs = match c.jobs() {
        Ok(j) => j,
        Err(e) => return vec![e],
    };
    // a sweep's variants all resolved before any is checked
    let unresolved = c.refuse_unresolved(&jobs);
    if !unresolved.is_empty() {
        return unresolved;
    }
    // each variant's plan let go as soon as it is checked: only its lines
    // and its verdict are kept until they are printed, in order
    let results = batch::run_parallel(
        jobs.len(),
        |k| -> Result<(String, Option<Error>)> {
            let mut p = c.prepared(&jobs[k], &[])?;
            crate::app::pipeline::check(&mut p, &c.allow);
            let mut lines = format!(
                "{}: {}\n",
                job_label(&jobs[k]),
                crate::analyse::check::summary(&p.findings)
            );
            for f in &p.findings {
                lines.push_str(&format!(
                    "  {} [{}]: {}\n",
                    f.severity.word(),
                    f.code,
                    f.message
                ));
            }
            let failing = p.failing(c.strict).len();
            let verdict = if failing > 0 {
                Some(Error::check(
                    &p.path,
                    format!("{failing} check{} failed", plural(failing)),
                ))
            } else {
                // the profile's start or end G-code: unsafe for this print
                p.frame_ok().err()
            };
            Ok((lines, verdict))
        },
        || {},
    );
    let mut errors = Vec::new();
    for r in results {
        match r {
            Ok((lines, verdict)) => {
                crate::say!("{lines}");
                errors.extend(verdict);
            }
            Err(e) => errors.push(e),
        }
    }
    errors
}

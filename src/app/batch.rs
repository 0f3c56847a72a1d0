//! Batch builds: `--sweep` expansion into variants, and running jobs in parallel.
//!
//! Every job is independent and deterministic, so the bytes a job writes do
//! not depend on how many threads run or in which order jobs finish.

use std::path::PathBuf;

use crate::base::error::{Error, Result};
pub(crate) use crate::recipe::params::parse_sweep;

/// One build: a recipe, its `--set` values, and the sweep values that name it.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Job {
    /// The recipe file.
    pub(crate) recipe: PathBuf,
    /// `--set` overrides, sweep values last.
    pub(crate) sets: Vec<(String, String)>,
    /// This variant's sweep values, in `--sweep` order.
    pub(crate) sweep: Vec<(String, String)>,
    /// The printer it is built for in place of the recipe's (a lock entry's);
    /// `--printer` overrides it.
    pub(crate) printer: Option<String>,
}

/// Most builds one command may make: recipes × the product of the sweeps.
pub(crate) const MAX_VARIANTS: u64 = 10_000;

/// Refuses a batch of more than [`MAX_VARIANTS`] builds, before any is made.
pub(crate) fn check_count(recipes: usize, sweeps: &[(String, Vec<String>)]) -> Result<()> {
    let n = sweeps
        .iter()
        .fold(recipes as u64, |n, (_, v)| n.saturating_mul(v.len() as u64));
    if n > MAX_VARIANTS {
        let sizes: Vec<String> = sweeps.iter().map(|(_, v)| v.len().to_string()).collect();
        return Err(Error::input(
            "--sweep",
            format!(
                "{recipes} recipe(s) × {} values make {n} builds; expected at most {MAX_VARIANTS}",
                sizes.join(" × ")
            ),
        ));
    }
    Ok(())
}

/// Every recipe × the cartesian product of the sweeps (first sweep outermost).
pub(crate) fn expand(
    recipes: &[PathBuf],
    sets: &[(String, String)],
    sweeps: &[(String, Vec<String>)],
) -> Vec<Job> {
    let combos = crate::recipe::resolve::plate::variants(sweeps);
    recipes
        .iter()
        .flat_map(|r| {
            combos.iter().map(move |sweep| Job {
                recipe: r.clone(),
                sets: sets.iter().chain(sweep).cloned().collect(),
                sweep: sweep.clone(),
                printer: None,
            })
        })
        .collect()
}

/// The errors of a batch's variants that could not be resolved
/// (`results`, one per job), each said once, before anything is built:
///
/// - one about a sweep's value (`--set NAME=VALUE` as the params read it)
///   names `--sweep NAME=VALUE`, the values that failed alike listed
///   together (`--sweep n=1,2`), however many variants hold them;
/// - any other names in its help the variants it holds in (none when it
///   holds in all of its recipe's).
///
/// Each one's help says that no variant was built, after the help it had
/// (its own, or the one `derived` from its message, which is left as it
/// is). Empty when every variant resolved.
pub(crate) fn unresolved(
    jobs: &[Job],
    results: Vec<Result<()>>,
    derived: impl Fn(&Error) -> Option<String>,
) -> Vec<Error> {
    // the error with no variant in it, the sweep's name (none: not a
    // value's), the values or variants it holds in, and how many variants
    // its recipe has
    let mut groups: Vec<(Error, Option<String>, Vec<String>, usize)> = Vec::new();
    for (job, r) in jobs.iter().zip(results) {
        let Err(e) = r else { continue };
        // the sweep's values are the last of the job's sets
        let tail = &job.sets[job.sets.len().saturating_sub(job.sweep.len())..];
        let swept = tail
            .iter()
            .find(|(n, v)| e.place.as_deref() == Some(&format!("--set {n}={v}")));
        let (name, item) = match swept {
            Some((n, v)) => (Some(n.clone()), v.clone()),
            None => (None, variant_label(job)),
        };
        let same = |(g, gn, _, _): &&mut (Error, Option<String>, Vec<String>, usize)| {
            *gn == name
                && g.file == e.file
                && g.message == e.message
                && g.help == e.help
                && (name.is_some() || (g.place == e.place && g.line == e.line))
        };
        match groups.iter_mut().find(same) {
            Some((_, _, items, _)) if items.contains(&item) => {}
            Some((_, _, items, _)) => items.push(item),
            None => {
                let of_recipe = jobs.iter().filter(|j| j.recipe == job.recipe).count();
                groups.push((e, name, vec![item], of_recipe));
            }
        }
    }
    groups
        .into_iter()
        .map(|(e, name, items, of_recipe)| {
            let mut e = match &name {
                Some(n) => Error {
                    place: Some(format!("--sweep {n}={}", items.join(","))),
                    ..e
                },
                None => e,
            };
            let note = if name.is_none() && items.len() < of_recipe {
                format!("with --sweep {}; no variant was built", listed(&items))
            } else {
                "no variant was built".to_string()
            };
            let help = match e
                .help
                .as_deref()
                .map(str::to_string)
                .or_else(|| derived(&e))
            {
                Some(h) => format!("{h}; {note}"),
                None => note,
            };
            e.help = Some(help.into_boxed_str());
            e
        })
        .collect()
}

/// A job's sweep values as `--sweep` gives them: `a=1 b=x`.
fn variant_label(job: &Job) -> String {
    let tail = &job.sets[job.sets.len().saturating_sub(job.sweep.len())..];
    let v: Vec<String> = tail.iter().map(|(n, v)| format!("{n}={v}")).collect();
    v.join(" ")
}

/// At most three variants, then how many there are.
fn listed(items: &[String]) -> String {
    if items.len() <= 3 {
        return items.join(", ");
    }
    format!("{}, … ({} variants)", items[..3].join(", "), items.len())
}

/// Runs `f(0..n)` side by side on the pool; results in index order.
/// `tick` is called after each job finishes (for a progress bar).
pub(crate) fn run_parallel<T: Send>(
    n: usize,
    f: impl Fn(usize) -> T + Sync + Send,
    tick: impl Fn() + Sync + Send,
) -> Vec<T> {
    let jobs: Vec<usize> = (0..n).collect();
    crate::base::par::map(&jobs, |&k| {
        let r = f(k);
        tick();
        r
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sweeps_list_and_range() {
        let (n, v) = parse_sweep("cycles=3,4,5,6").unwrap();
        assert_eq!(n, "cycles");
        assert_eq!(v, ["3", "4", "5", "6"]);
        let (_, v) = parse_sweep("amplitude=1..3:0.5").unwrap();
        assert_eq!(v, ["1", "1.5", "2", "2.5", "3"]);
        let (_, v) = parse_sweep("a=0..0.3:0.1").unwrap();
        assert_eq!(v, ["0", "0.1", "0.2", "0.3"]);
        assert!(parse_sweep("a=3..1:1").is_err());
        assert!(parse_sweep("a=1..2:0").is_err());
        assert!(parse_sweep("a").is_err());
    }

    #[test]
    fn a_range_without_a_step_steps_by_one_as_for_does() {
        let (_, v) = parse_sweep("cycles=3..7").unwrap();
        assert_eq!(v, ["3", "4", "5", "6", "7"]);
        let (_, v) = parse_sweep("a=0.5..2").unwrap();
        assert_eq!(v, ["0.5", "1.5"]);
        let e = parse_sweep("a=x..2").unwrap_err();
        assert!(e.message.contains("not a number"), "{e}");
    }

    #[test]
    fn cartesian_product_first_sweep_outermost() {
        let sweeps = vec![
            ("a".to_string(), vec!["1".to_string(), "2".to_string()]),
            (
                "b".to_string(),
                vec!["x".to_string(), "y".to_string(), "z".to_string()],
            ),
        ];
        let jobs = expand(
            &[PathBuf::from("r.yaml")],
            &[("c".into(), "0".into())],
            &sweeps,
        );
        assert_eq!(jobs.len(), 6);
        assert_eq!(
            jobs[1].sweep,
            [("a".into(), "1".into()), ("b".into(), "y".into())]
        );
        assert_eq!(jobs[3].sets[0], ("c".to_string(), "0".to_string()));
    }

    #[test]
    fn parallel_results_in_order() {
        let r = crate::base::par::on_threads(4, || run_parallel(50, |k| k * k, || {}));
        assert_eq!(r, (0..50).map(|k| k * k).collect::<Vec<_>>());
    }
}

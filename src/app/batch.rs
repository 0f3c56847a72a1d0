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

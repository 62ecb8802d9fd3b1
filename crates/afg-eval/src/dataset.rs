//! The fixed test datasets: `datasets/n{N}.jsonl` under the repository root, 100
//! instances each, drawn from the paper's distribution with seeds `N · 10^6 + i`.
//!
//! # Examples
//! ```
//! use afg_eval::dataset;
//! assert_eq!(dataset::seed(60, 7), 60_000_007);
//! let first = dataset::generate(20)?.remove(0);
//! assert_eq!((first.num_robots(), first.num_tasks()), (20, dataset::TASKS));
//! # Ok::<(), afg_eval::EvalError>(())
//! ```

use std::path::{Path, PathBuf};

use afg_game::{GeneratorConfig, Instance};

use crate::EvalError;

/// Robot counts of Table I (the training scales as well).
pub const TABLE1_SIZES: [usize; 3] = [20, 60, 100];
/// Robot counts of Table II.
pub const TABLE2_SIZES: [usize; 2] = [500, 1000];
/// Robot counts of the committed datasets.
pub const SIZES: [usize; 5] = [20, 60, 100, 500, 1000];
/// Instances per dataset.
pub const INSTANCES: usize = 100;
/// Tasks per instance (the paper's M).
pub const TASKS: usize = afg_game::GeneratorConfig::PAPER_TASKS;

/// Seed of instance `index` of the dataset with `robots` robots: `robots · 10^6 + index`.
pub fn seed(robots: usize, index: usize) -> u64 {
    (robots * 1_000_000 + index) as u64
}

/// The dataset for `robots` robots as the generator makes it.
///
/// # Errors
/// [`EvalError::Game`] for a robot count the generator refuses (0).
pub fn generate(robots: usize) -> Result<Vec<Instance>, EvalError> {
    (0..INSTANCES)
        .map(|i| Ok(GeneratorConfig::paper(robots, TASKS, seed(robots, i)).generate()?))
        .collect()
}

/// Path of the committed dataset for `robots` robots under the repository `root`.
pub fn path(root: &Path, robots: usize) -> PathBuf {
    root.join("datasets").join(format!("n{robots}.jsonl"))
}

/// The committed dataset for `robots` robots under the repository `root`.
///
/// # Errors
/// [`EvalError::Dataset`] if the file is missing or is not a dataset.
pub fn load(root: &Path, robots: usize) -> Result<Vec<Instance>, EvalError> {
    let p = path(root, robots);
    afg_game::io::read_dataset(&p).map_err(|source| EvalError::Dataset {
        path: p.display().to_string(),
        source,
    })
}

/// The first `count` instances of the committed dataset for `robots` robots, with
/// the optimum's welfare of each (the denominators of "% of OPT").
///
/// # Errors
/// As [`load`], and [`crate::optima`]'s.
///
/// # Examples
/// ```no_run
/// use std::path::Path;
/// let (instances, opt) = afg_eval::dataset::first_with_optima(Path::new("."), 20, 5)?;
/// assert_eq!((instances.len(), opt.len()), (5, 5));
/// # Ok::<(), afg_eval::EvalError>(())
/// ```
pub fn first_with_optima(
    root: &Path,
    robots: usize,
    count: usize,
) -> Result<(Vec<Instance>, Vec<f64>), EvalError> {
    let instances: Vec<Instance> = load(root, robots)?.into_iter().take(count).collect();
    let opt = crate::optima(&instances)?;
    Ok((instances, opt))
}

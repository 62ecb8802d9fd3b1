//! `docs/RESULTS.md` and the README's copy of its tables: the marked block, the whole
//! document and the assignment map beside it.

use std::fmt::Write as _;
use std::path::Path;

use afg_baseline::{Allocator, Method, Optimum};
use afg_learn::policy::LearnedPolicy;

use super::{Tables, headline, models_table};
use afg_eval::{EvalError, dataset, figures};

use crate::ModelSpec;

/// The line before the tables in `docs/RESULTS.md` and `README.md`.
pub const BEGIN: &str = "<!-- reproduce-tables:begin -->";
/// The line after them.
pub const END: &str = "<!-- reproduce-tables:end -->";

/// The tables between the [`BEGIN`] and [`END`] markers of `text`, if it has them.
///
/// # Examples
/// ```
/// use xtask::tables::{BEGIN, END, block, with_block};
/// let readme = format!("intro\n{BEGIN}\nold\n{END}\nrest\n");
/// assert_eq!(block(&readme).as_deref(), Some("old\n"));
/// let new = with_block(&readme, "| new |\n").unwrap();
/// assert_eq!(block(&new).as_deref(), Some("| new |\n"));
/// assert!(new.starts_with("intro\n") && new.ends_with("\nrest\n"));
/// assert_eq!(block("no markers"), None);
/// ```
pub fn block(text: &str) -> Option<String> {
    match (text.find(BEGIN), text.find(END)) {
        (Some(b), Some(e)) if b < e => Some(text[b + BEGIN.len()..e].trim_start().to_owned()),
        _ => None,
    }
}

/// `text` with the block between its markers replaced by `tables`; `None` if it has
/// no markers.
pub fn with_block(text: &str, tables: &str) -> Option<String> {
    match (text.find(BEGIN), text.find(END)) {
        (Some(b), Some(e)) if b < e => Some(format!(
            "{}{BEGIN}\n{tables}{END}{}",
            &text[..b],
            &text[e + END.len()..]
        )),
        _ => None,
    }
}

/// How the tables were made, for the header of `docs/RESULTS.md`.
#[derive(Clone, Copy, Debug)]
pub struct RunInfo {
    /// Made with `--quick`.
    pub quick: bool,
    /// Minutes the whole run took.
    pub minutes: f64,
    /// Threads the instances ran on.
    pub threads: usize,
}

/// The whole of `docs/RESULTS.md`: a header saying how it was made, the tables
/// (`tables`, the Markdown of `res`) between the markers, the headline and the table
/// of committed models under the repository `root`.
///
/// # Errors
/// A committed model whose manifest or config cannot be read.
pub fn results_document(
    res: &Tables,
    tables: &str,
    run: RunInfo,
    root: &Path,
) -> Result<String, EvalError> {
    let mut md = String::new();
    let _ = writeln!(md, "# Results\n");
    let _ = writeln!(
        md,
        "Made by `cargo xtask reproduce-tables{}` on {} ({}-core CPU), committed datasets `datasets/` and committed weights `models/`. Defaults: eps = max(2, N/M), no capacities, beta = 1, M = 5 (see decisions.md). Instances run in parallel, one per core; each time / instance is one instance's wall time on one core (`RAYON_NUM_THREADS=1` runs them one after another). The whole run took {:.1} min.\n",
        if run.quick { " --quick" } else { "" },
        std::env::consts::ARCH,
        run.threads,
        run.minutes
    );
    md.push_str(BEGIN);
    md.push('\n');
    md.push_str(tables);
    md.push_str(END);
    md.push('\n');
    let _ = writeln!(md, "\n{}", headline(&res.table1));
    md.push_str(&models_table(root)?);
    Ok(md)
}

/// Instance 0 of the N = 100 test set: OPT beside AFGNet_DDQN (or GRAPE DA while no
/// N = 100 model is committed), as an SVG map ([`figures::assignments_svg`]).
///
/// # Errors
/// A missing dataset or model, or a failed allocation.
pub fn assignment_map_svg(root: &Path) -> Result<String, EvalError> {
    let inst = dataset::load(root, 100)?.swap_remove(0);
    let opt = Optimum.allocate(&inst)?.assignment;
    let spec = ModelSpec::afgnet_ddqn(100);
    let run = spec.run_dir(root);
    let (label, other) = if run.has_weights() {
        let policy = LearnedPolicy::load(&run.weights())?;
        (spec.label(), policy.allocate(&inst)?.assignment)
    } else {
        (
            format!("{} (no N = 100 model yet)", Method::Da.label()),
            Method::Da.allocator(0).allocate(&inst)?.assignment,
        )
    };
    figures::assignments_svg(&inst, &[(Method::Opt.label(), &opt), (&label, &other)])
}

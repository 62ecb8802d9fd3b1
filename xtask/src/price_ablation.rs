//! What each part of the price model adds (ours): the untrained structure (Nearest),
//! Q\* regression on the expert's states, with DAgger, and with the one-shot price loss,
//! sequential and one-shot, at several scales.

use std::fmt::Write as _;
use std::path::Path;

use afg_baseline::{Allocator, Method};
use afg_learn::{price::PriceMode, run::RunDir};
use serde::Serialize;

use afg_eval::{EvalError, dataset, evaluate};

use crate::{PriceSpec, PriceTraining};

/// The scales of the ablation table.
pub const SIZES: [usize; 4] = [20, 60, 100, 1000];

/// One row of the ablation table: % of OPT, sequential and one-shot, per scale.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PriceAblationRow {
    /// What the model was trained with.
    pub method: String,
    /// The command that trained it (`None` for the untrained structure).
    pub command: Option<String>,
    /// `(N, sequential, one-shot)` for each of [`SIZES`].
    pub percent_of_opt: Vec<(usize, f64, f64)>,
}

/// The ablation rows whose models are committed under `root`, on the first
/// `instances` of each test set in [`SIZES`].
///
/// # Errors
/// A missing dataset, a committed model without its run summary, or a model that
/// cannot be loaded.
pub fn price_ablation(root: &Path, instances: usize) -> Result<Vec<PriceAblationRow>, EvalError> {
    let mut sets = Vec::new();
    for n in SIZES {
        let (insts, opt) = dataset::first_with_optima(root, n, instances)?;
        sets.push((n, insts, opt));
    }
    let mut rows = Vec::new();
    // The untrained structure (all prices 0: Nearest), then each training.
    let trainings = std::iter::once(None).chain(PriceTraining::ALL.map(Some));
    for training in trainings {
        let (label, policies, command): (_, Vec<Box<dyn Allocator>>, _) = match training {
            None => (
                "untrained (all prices 0: Nearest) — the structure alone",
                vec![Method::Nearest.allocator(0)],
                None,
            ),
            Some(training) => {
                let spec =
                    |mode| PriceSpec::new(PriceSpec::TRAINED_AT, mode).with_training(training);
                let [sequential, one_shot] = [PriceMode::Sequential, PriceMode::OneShot].map(spec);
                if !sequential.model_path(root).exists() {
                    continue;
                }
                let manifest = RunDir::new(sequential.dir(root)).manifest()?;
                let policies: Vec<Box<dyn Allocator>> = vec![
                    Box::new(sequential.load(root)?),
                    Box::new(one_shot.load(root)?),
                ];
                (training.describe(), policies, Some(manifest.command))
            }
        };
        let mut percent_of_opt = Vec::new();
        for (n, insts, opt) in &sets {
            let score = |p: &dyn Allocator| -> Result<f64, EvalError> {
                Ok(evaluate(label, p, insts, opt)?.percent_of_opt)
            };
            let sequential = score(policies[0].as_ref())?;
            let one_shot = match policies.get(1) {
                Some(p) => score(p.as_ref())?,
                None => sequential,
            };
            percent_of_opt.push((*n, sequential, one_shot));
        }
        rows.push(PriceAblationRow {
            method: label.to_owned(),
            command,
            percent_of_opt,
        });
    }
    Ok(rows)
}

/// The ablation table in Markdown, with the commands under it.
///
/// # Examples
/// ```
/// use xtask::price_ablation::{PriceAblationRow, price_ablation_markdown};
/// let row = PriceAblationRow {
///     method: "structure alone".into(),
///     command: None,
///     percent_of_opt: vec![(20, 92.5, 92.5), (60, 98.6, 98.6), (100, 99.1, 99.1), (1000, 99.8, 99.8)],
/// };
/// let md = price_ablation_markdown(&[row], 3);
/// assert!(md.contains("| structure alone | 92.50 % | 92.50 % | 98.60 % |"));
/// ```
pub fn price_ablation_markdown(rows: &[PriceAblationRow], instances: usize) -> String {
    let mut s = format!(
        "### The price model (ours): what each part adds — % of OPT, sequential / one-shot, first {instances} instances of each test set\n\n| method |"
    );
    for n in SIZES {
        let _ = write!(s, " N = {n} sequential | N = {n} one-shot |");
    }
    s += "\n|---|";
    s += &"---|".repeat(2 * SIZES.len());
    s.push('\n');
    for r in rows {
        let _ = write!(s, "| {} |", r.method);
        for (_, seq, one) in &r.percent_of_opt {
            let _ = write!(s, " {seq:.2} % | {one:.2} % |");
        }
        s.push('\n');
    }
    s += "\nCommands: ";
    let commands: Vec<String> = rows
        .iter()
        .filter_map(|r| r.command.as_ref().map(|c| format!("`{c}`")))
        .collect();
    s += &commands.join(", ");
    s += ".\n\n";
    s
}

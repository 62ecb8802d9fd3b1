//! What a validation of the greedy policy reports.

use serde::{Deserialize, Serialize};

/// The greedy policy of a network on the validation set.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Validation {
    /// Mean welfare.
    pub welfare: f64,
    /// Mean of welfare / OPT, in percent.
    pub percent_of_opt: f64,
    /// Mean over instances of the share of robots on the most common task. Near 1 the
    /// policy has collapsed onto one task index; OPT's share is far lower (about 0.3 in
    /// the paper's distribution at M = 5).
    pub largest_task_share: f64,
}

impl Validation {
    /// Share of robots on one task above which a validation counts as collapsed.
    pub const COLLAPSE_SHARE: f64 = 0.6;

    /// Whether most robots went to one task ([`Validation::COLLAPSE_SHARE`]).
    pub fn collapsed(&self) -> bool {
        self.largest_task_share > Self::COLLAPSE_SHARE
    }
}

//! The time limit as the search checks it.

use std::cell::Cell;
use std::time::{Duration, Instant};

/// The share of [`TeamOptimum::time_limit`](super::TeamOptimum::time_limit) after which the root's solve stops.
const ROOT_SHARE: f64 = 0.75;

/// A time limit that the search checks between steps: it is near when the time spent
/// plus the longest step between two checks so far (the root's solve before the first
/// check aside: that stops at [`ROOT_SHARE`] of the limit) reaches it.
pub(super) struct Deadline {
    limit: Option<Duration>,
    pub(super) start: Instant,
    last: Cell<Option<Instant>>,
    longest: Cell<Duration>,
}

impl Deadline {
    pub(super) fn new(limit: Option<Duration>) -> Self {
        Deadline {
            limit,
            start: Instant::now(),
            last: Cell::new(None),
            longest: Cell::new(Duration::ZERO),
        }
    }

    /// Whether the root's solve should stop where it is: [`ROOT_SHARE`] of the limit
    /// spent (what follows a stopped root — its bound, an assignment — reads the costs
    /// once or twice more).
    pub(super) fn root_over(&self) -> bool {
        (self.limit).is_some_and(|limit| self.start.elapsed() >= limit.mul_f64(ROOT_SHARE))
    }

    /// Whether the next step would likely end past the limit.
    pub(super) fn near(&self) -> bool {
        let now = Instant::now();
        if let Some(last) = self.last.replace(Some(now)) {
            self.longest.set(self.longest.get().max(now - last));
        }
        self.limit
            .is_some_and(|limit| now - self.start + self.longest.get() >= limit)
    }
}

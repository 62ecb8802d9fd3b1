//! The columns of the transportation problem: what each task (or the void) is, and
//! what its members are worth — a concave value function, its envelope from a team
//! threshold on, a Lagrangian penalty, or nothing.

use afg_game::ValueFunction;

/// What a column of the problem is.
#[derive(Clone, Copy)]
pub(in crate::optimum) enum Column {
    /// A task: its slots' values and its capacity (in robots of the instance).
    Task { value: Slots, capacity: usize },
    /// The void task: cost 0, every member worth 0, room for all.
    Void,
    /// No task (one that was removed): no room.
    Closed,
}

/// What a task column's members are worth: a concave value function F less a
/// `penalty` once it earns, whose first `flat` members are each worth
/// `(F(flat) − penalty) / flat` (the concave envelope of F earned only from `flat`
/// members on, spread over them), plus `bonus` each (a large bonus forces them in), or
/// nothing at all (`worthless`: a task that may not earn). Concave in every case:
/// without a penalty since `F(k) / k ≥ F(k + 1) − F(k)`, with one by the choice of
/// `flat` ([`Slots::penalised`]) or the bonus.
#[derive(Clone, Copy, Debug)]
pub(in crate::optimum) struct Slots {
    value: ValueFunction,
    flat: usize,
    bonus: f64,
    penalty: f64,
    worthless: bool,
    /// What each of the first `flat` members is worth (kept: read at every slot).
    share: f64,
}

impl Slots {
    /// F's own marginal values.
    pub(in crate::optimum) fn concave(value: ValueFunction) -> Self {
        Slots {
            value,
            flat: 0,
            bonus: 0.0,
            penalty: 0.0,
            worthless: false,
            share: 0.0,
        }
    }

    /// The envelope of F earned from `k` members on, with `bonus` on each of the first
    /// `k`.
    pub(in crate::optimum) fn envelope(value: ValueFunction, k: usize, bonus: f64) -> Self {
        Slots {
            flat: k,
            bonus,
            ..Slots::concave(value)
        }
        .shared()
    }

    /// The same slots less `penalty` once the task earns (a staffed task's: its first
    /// members carry a bonus that keeps them concave).
    pub(in crate::optimum) fn less(self, penalty: f64) -> Self {
        Slots { penalty, ..self }.shared()
    }

    /// The same slots with `share` set from the others.
    fn shared(self) -> Self {
        let share = if self.flat == 0 {
            0.0
        } else {
            (self.value.value(self.flat) - self.penalty) / self.flat as f64 + self.bonus
        };
        Slots { share, ..self }
    }

    /// The concave envelope of `max(0, F(n) − penalty)` earned from `k` members on, at
    /// most `capacity`, and the size n* at which it meets that function first (its
    /// first n* members worth `(F(n*) − penalty) / n*` each, n* the best such share in
    /// `k..=capacity`); worthless, with n* = 0, where F never exceeds the penalty.
    pub(in crate::optimum) fn penalised(
        value: ValueFunction,
        k: usize,
        penalty: f64,
        capacity: usize,
    ) -> (Self, usize) {
        // (F(n) − penalty) / n rises while n F'(n) − F(n) + penalty > 0, then falls.
        let share = |n: usize| (value.value(n) - penalty) / n as f64;
        let mut flat = k;
        while flat < capacity && share(flat + 1) > share(flat) {
            flat += 1;
        }
        if k > capacity || share(flat) <= 0.0 {
            return (Slots::worthless(value), 0);
        }
        (Slots::envelope(value, flat, 0.0).less(penalty), flat)
    }

    /// Members worth nothing.
    pub(in crate::optimum) fn worthless(value: ValueFunction) -> Self {
        Slots {
            worthless: true,
            ..Slots::concave(value)
        }
    }

    /// What the first n members are worth together.
    pub(in crate::optimum) fn value(&self, n: usize) -> f64 {
        if self.worthless || n == 0 {
            0.0
        } else if n <= self.flat {
            n as f64 * self.share
        } else {
            self.value.value(n) - self.penalty + self.flat as f64 * self.bonus
        }
    }

    /// What the n-th member (n ≥ 1) is worth.
    #[inline]
    pub(in crate::optimum) fn marginal(&self, n: usize) -> f64 {
        if self.worthless {
            0.0
        } else if n <= self.flat {
            self.share
        } else {
            self.value.marginal(n)
        }
    }
}

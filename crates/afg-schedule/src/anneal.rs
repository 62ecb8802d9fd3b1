//! Simulated annealing on the order of the tasks.
//!
//! A plan is an order; the decoder staffs each task in turn, so every change to the
//! order is replayed from the first position it touches, with the fleets before each
//! position kept from the last accepted plan. Moves: take one task or a block of up to
//! four out and put it back nearby, or swap two nearby tasks.

use std::time::Instant;

use rand::Rng;
use rand_chacha::ChaCha8Rng;

use crate::decode::{Decoder, Fleet};

/// An order of the tasks with the fleet before each of its positions.
pub(crate) struct Plan<'a> {
    decoder: &'a Decoder,
    pub(crate) order: Vec<usize>,
    before: Vec<Fleet>,
    /// Waiting beyond `max_wait` before each position.
    overwait: Vec<f64>,
    cost: Cost,
    ready: Vec<(f64, usize)>,
    team: Vec<usize>,
}

/// The price of a unit of waiting beyond `max_wait`, in units of makespan.
const OVERWAIT_PRICE: f64 = 4.0;

/// A plan's makespan, its robots' mean return and its waiting beyond `max_wait`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Cost {
    pub(crate) makespan: f64,
    mean_back: f64,
    pub(crate) overwait: f64,
}

impl Cost {
    /// What the search minimises: the makespan, a little of the mean return (a slope
    /// across the makespan's plateaus, where only the last robot home counts), and a
    /// price on waiting too long.
    fn value(self) -> f64 {
        self.makespan + 0.05 * self.mean_back + OVERWAIT_PRICE * self.overwait
    }

    /// Valid plans first, then by value.
    pub(crate) fn better_than(self, other: Cost) -> bool {
        match (self.overwait > 0.0, other.overwait > 0.0) {
            (false, true) => true,
            (true, false) => false,
            _ => self.value() < other.value() - 1e-12,
        }
    }
}

impl<'a> Plan<'a> {
    /// The plan of `order`.
    pub(crate) fn new(decoder: &'a Decoder, order: Vec<usize>) -> Self {
        let mut plan = Plan {
            decoder,
            before: vec![decoder.start(); order.len() + 1],
            overwait: vec![0.0; order.len() + 1],
            order,
            cost: Cost::default(),
            ready: Vec::new(),
            team: Vec::new(),
        };
        plan.cost = plan.replay(0, true);
        plan
    }

    /// What the plan costs.
    pub(crate) fn cost(&self) -> Cost {
        self.cost
    }

    /// Decodes from position `from` on; with `keep`, stores the fleets it passes.
    fn replay(&mut self, from: usize, keep: bool) -> Cost {
        let mut fleet = self.before[from].clone();
        let mut overwait = self.overwait[from];
        for p in from..self.order.len() {
            let j = self.order[p];
            let (start, over) = self
                .decoder
                .staff(&fleet, j, &mut self.ready, &mut self.team);
            overwait += over;
            self.decoder.assign(&mut fleet, j, start, &self.team);
            if keep {
                self.before[p + 1].clone_from(&fleet);
                self.overwait[p + 1] = overwait;
            }
        }
        let (makespan, mean_back) = self.decoder.score(&fleet);
        Cost {
            makespan,
            mean_back,
            overwait,
        }
    }
}

/// One change to the order: take `len` tasks out at `from` and put them back at `to`, or
/// swap two.
#[derive(Clone, Copy)]
enum Move {
    Shift { from: usize, len: usize, to: usize },
    Swap(usize, usize),
}

impl Move {
    fn draw(m: usize, rng: &mut ChaCha8Rng) -> Self {
        let near = |p: usize, rng: &mut ChaCha8Rng| {
            let span = 12.min(m - 1) as i64;
            (p as i64 + rng.random_range(-span..=span)).clamp(0, m as i64 - 1) as usize
        };
        let a = rng.random_range(0..m);
        if rng.random_bool(0.3) {
            return Move::Swap(a, near(a, rng));
        }
        let len = if rng.random_bool(0.7) {
            1
        } else {
            rng.random_range(1..=4.min(m))
        };
        let from = a.min(m - len);
        Move::Shift {
            from,
            len,
            to: near(from, rng).min(m - len),
        }
    }

    /// Applies the move; returns the first position it changed.
    fn apply(self, order: &mut [usize]) -> usize {
        match self {
            Move::Swap(a, b) => {
                order.swap(a, b);
                a.min(b)
            }
            Move::Shift { from, len, to } if to < from => {
                order[to..from + len].rotate_right(len);
                to
            }
            Move::Shift { from, len, to } => {
                order[from..to + len].rotate_left(len);
                from
            }
        }
    }

    fn undo(self, order: &mut [usize]) {
        match self {
            Move::Swap(a, b) => order.swap(a, b),
            Move::Shift { from, len, to } if to < from => order[to..from + len].rotate_left(len),
            Move::Shift { from, len, to } => order[from..to + len].rotate_right(len),
        }
    }
}

/// Anneals until the deadline or the step budget (whichever comes first); leaves the best
/// order found in `plan` and returns the steps taken.
pub(crate) fn anneal(
    plan: &mut Plan,
    rng: &mut ChaCha8Rng,
    deadline: Option<Instant>,
    max_steps: Option<u64>,
) -> u64 {
    let m = plan.order.len();
    if m < 2 {
        return 0;
    }
    let clock = Instant::now();
    let total = deadline.map(|d| d.saturating_duration_since(clock).as_secs_f64());
    let (hot, cold) = (0.02 * plan.cost.makespan, 0.0005 * plan.cost.makespan);
    let (mut best_order, mut best) = (plan.order.clone(), plan.cost);
    let (mut step, mut progress) = (0u64, 0.0);
    loop {
        if let Some(n) = max_steps {
            if step >= n {
                break;
            }
            progress = step as f64 / n as f64;
        }
        if let (0, Some(d), Some(t)) = (step % 8, deadline, total) {
            let now = Instant::now();
            if now >= d {
                break;
            }
            progress = f64::max(progress, (now - clock).as_secs_f64() / t);
        }
        step += 1;
        let temperature = hot * (cold / hot).powf(progress);
        let mv = Move::draw(m, rng);
        let from = mv.apply(&mut plan.order);
        let delta = plan.replay(from, false).value() - plan.cost.value();
        if delta <= 0.0 || rng.random::<f64>() < (-delta / temperature).exp() {
            plan.cost = plan.replay(from, true);
            if plan.cost.better_than(best) {
                best = plan.cost;
                best_order.clone_from(&plan.order);
            }
        } else {
            mv.undo(&mut plan.order);
        }
    }
    plan.order = best_order;
    plan.cost = plan.replay(0, true);
    step
}

//! Simulated annealing on the order of the tasks.
//!
//! A plan is an order; the decoder staffs each task in turn, so every change to the
//! order is replayed from the first position it touches, with the fleets before each
//! position kept from the last accepted plan. Moves: put a task just before or after
//! one of the tasks nearest it on the map (so that the team of one can go on to the
//! other), take one task or a block of up to four out and put it back nearby in the
//! order, or swap two nearby tasks.

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
    /// The fleets and waiting of the last [`Plan::trial`], where it wrote them: they
    /// become the plan's own when it is accepted.
    trial_fleets: Vec<Fleet>,
    trial_overwait: Vec<f64>,
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
            trial_fleets: vec![decoder.start(); order.len() + 1],
            trial_overwait: vec![0.0; order.len() + 1],
            order,
            cost: Cost::default(),
            ready: Vec::new(),
            team: Vec::new(),
        };
        plan.replay_all();
        plan
    }

    /// What the plan costs.
    pub(crate) fn cost(&self) -> Cost {
        self.cost
    }

    /// Decodes the order from position `from` on, the plan's fleets kept as they are
    /// and the ones it passes written to the trial's. Past `changed` (the last position
    /// a move touched), a fleet equal to the plan's own at the same place means the rest
    /// of the plan is as it was: the decode stops there and the cost is the plan's.
    /// `changed` at or past the end decodes it all.
    fn trial(&mut self, from: usize, changed: usize) -> Trial {
        self.trial_fleets[from].clone_from(&self.before[from]);
        self.trial_overwait[from] = self.overwait[from];
        for p in from..self.order.len() {
            let j = self.order[p];
            let (done, next) = self.trial_fleets.split_at_mut(p + 1);
            let (fleet, after) = (&done[p], &mut next[0]);
            let (start, over) = self
                .decoder
                .staff(fleet, j, &mut self.ready, &mut self.team);
            after.clone_from(fleet);
            self.decoder.assign(after, j, start, &self.team);
            let overwait = self.trial_overwait[p] + over;
            self.trial_overwait[p + 1] = overwait;
            if p == changed && overwait == self.overwait[p + 1] && *after == self.before[p + 1] {
                return Trial {
                    cost: self.cost,
                    from,
                    end: p + 1,
                };
            }
        }
        let (makespan, mean_back) = self.decoder.score(&self.trial_fleets[self.order.len()]);
        Trial {
            cost: Cost {
                makespan,
                mean_back,
                overwait: self.trial_overwait[self.order.len()],
            },
            from,
            end: self.order.len() + 1,
        }
    }

    /// Makes the last trial's fleets the plan's own (the order already is).
    fn accept(&mut self, trial: Trial) {
        let changed = trial.from + 1..trial.end;
        self.before[changed.clone()].swap_with_slice(&mut self.trial_fleets[changed.clone()]);
        self.overwait[changed.clone()].swap_with_slice(&mut self.trial_overwait[changed]);
        self.cost = trial.cost;
    }

    /// Decodes the whole order into the plan.
    fn replay_all(&mut self) {
        let trial = self.trial(0, usize::MAX);
        self.accept(trial);
    }
}

/// What decoding a changed order found: its cost, and the positions `from + 1..end`
/// whose fleets it wrote.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Trial {
    cost: Cost,
    from: usize,
    end: usize,
}

/// One change to the order: take `len` tasks out at `from` and put them back at `to`, or
/// swap two.
#[derive(Clone, Copy)]
enum Move {
    Shift { from: usize, len: usize, to: usize },
    Swap(usize, usize),
}

/// How many of a task's nearest tasks a move may put it beside.
const NEIGHBOURS: usize = 8;
/// The share of moves that put a task beside a neighbour on the map.
const BESIDE_SHARE: f64 = 0.4;

impl Move {
    fn draw(order: &[usize], neighbours: &[Vec<usize>], rng: &mut ChaCha8Rng) -> Self {
        let m = order.len();
        if rng.random_bool(BESIDE_SHARE)
            && let Some(mv) = Move::beside(order, neighbours, rng)
        {
            return mv;
        }
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

    /// Moves a task to just after or just before one of its `neighbours` (None for a
    /// task with none).
    fn beside(order: &[usize], neighbours: &[Vec<usize>], rng: &mut ChaCha8Rng) -> Option<Self> {
        let from = rng.random_range(0..order.len());
        let near = &neighbours[order[from]];
        if near.is_empty() {
            return None;
        }
        let other = near[rng.random_range(0..near.len())];
        let at = order.iter().position(|&j| j == other)?;
        // `to` is where the task stands once moved: past `from`, the neighbour's own
        // place moves up by one when the task leaves.
        let to = at + usize::from(rng.random_bool(0.5)) - usize::from(at > from);
        Some(Move::Shift { from, len: 1, to })
    }

    /// The last position the move changes.
    fn last(self) -> usize {
        match self {
            Move::Swap(a, b) => a.max(b),
            Move::Shift { from, len, to } => from.max(to) + len - 1,
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
    let neighbours = plan.decoder.neighbours(NEIGHBOURS);
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
        let mv = Move::draw(&plan.order, &neighbours, rng);
        let from = mv.apply(&mut plan.order);
        let changed = mv.last();
        let trial = plan.trial(from, changed);
        let delta = trial.cost.value() - plan.cost.value();
        if delta <= 0.0 || rng.random::<f64>() < (-delta / temperature).exp() {
            plan.accept(trial);
            if plan.cost.better_than(best) {
                best = plan.cost;
                best_order.clone_from(&plan.order);
            }
        } else {
            mv.undo(&mut plan.order);
        }
    }
    plan.order = best_order;
    plan.replay_all();
    step
}

#[cfg(test)]
mod tests {
    use rand::SeedableRng;
    use rand::seq::SliceRandom;

    use super::*;
    use crate::{Family, Generate};

    fn decoder(seed: u64) -> Decoder {
        let inst = Generate {
            family: Family::Dcmrta,
            robots: 6,
            tasks: 14,
            seed,
        }
        .instance()
        .unwrap();
        Decoder::new(&inst, 10.0)
    }

    /// A replay that stops where the fleet meets the plan's own costs what a replay to
    /// the end costs, on random moves of random plans.
    #[test]
    fn a_replay_that_stops_early_costs_what_a_full_one_does() {
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let (mut stopped, mut checked) = (0, 0);
        for seed in 0..20 {
            let decoder = decoder(seed);
            let neighbours = decoder.neighbours(NEIGHBOURS);
            let mut plan = Plan::new(&decoder, (0..14).collect());
            for _ in 0..200 {
                let mv = Move::draw(&plan.order, &neighbours, &mut rng);
                let from = mv.apply(&mut plan.order);
                let full = plan.trial(from, usize::MAX);
                let early = plan.trial(from, mv.last());
                assert_eq!(early.cost, full.cost);
                checked += 1;
                stopped += usize::from(early.end < full.end);
                if rng.random_bool(0.5) {
                    plan.accept(early);
                    assert_eq!(plan.cost, full.cost);
                } else {
                    mv.undo(&mut plan.order);
                }
            }
            // the stored fleets stay the plan's own: a decode from every position
            // costs what the whole plan does
            let cost = plan.cost;
            for from in 0..14 {
                assert_eq!(plan.trial(from, usize::MAX).cost, cost);
            }
        }
        assert!(stopped > checked / 10, "{stopped} of {checked}");
    }

    /// A move beside a neighbour leaves the task next to that neighbour in the order.
    #[test]
    fn a_move_beside_a_neighbour_puts_the_task_next_to_it() {
        let mut rng = ChaCha8Rng::seed_from_u64(2);
        let decoder = decoder(3);
        let neighbours = decoder.neighbours(3);
        for (j, near) in neighbours.iter().enumerate() {
            assert_eq!(near.len(), 3);
            let far = |o: usize| decoder.time(j, o);
            assert!(near.windows(2).all(|w| far(w[0]) <= far(w[1])));
            assert!(
                (0..14)
                    .filter(|o| *o != j && !near.contains(o))
                    .all(|o| far(o) >= far(near[2]))
            );
        }
        for _ in 0..500 {
            let mut order: Vec<usize> = (0..14).collect();
            order.shuffle(&mut rng);
            let mv = Move::beside(&order, &neighbours, &mut rng).unwrap();
            let Move::Shift { from, len: 1, to } = mv else {
                panic!("a shift of one task")
            };
            let task = order[from];
            mv.apply(&mut order);
            assert_eq!(order[to], task);
            let beside = [to.checked_sub(1), Some(to + 1)];
            assert!(
                beside
                    .iter()
                    .flatten()
                    .any(|&p| p < 14 && neighbours[task].contains(&order[p])),
                "{task} at {to} in {order:?}"
            );
        }
    }
}

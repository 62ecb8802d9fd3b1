//! A task's best team on its own at given robot weights: a covering knapsack over its
//! candidates, by dynamic programming.

use afg_game::{Instance, RobotId, TaskId};

/// What a task's team must be at a node.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Role {
    /// Staffed: it earns.
    Earn,
    /// Open: it earns, or holds at most `capacity` robots and earns nothing.
    Either { capacity: usize },
    /// Unstaffed: at most `room` robots, and it earns nothing.
    Idle { room: usize },
}

/// One task at a node: its skill needs ([`skill_needs`]), its threshold, its role, the
/// robots free to join it and those the node fixed there.
pub(super) struct TaskAt<'c> {
    pub(super) j: TaskId,
    pub(super) needs: Vec<(usize, usize)>,
    pub(super) threshold: usize,
    pub(super) capacity: usize,
    pub(super) role: Role,
    pub(super) candidates: &'c [usize],
    pub(super) fixed: &'c [usize],
}

/// How much of each skill task j requires (skill, units), where it requires some.
pub(super) fn skill_needs(inst: &Instance, j: TaskId) -> Vec<(usize, usize)> {
    (inst.requires(j).iter().enumerate())
        .filter(|&(_, &r)| r > 0)
        .map(|(s, &r)| (s, r as usize))
        .collect()
}

impl TaskAt<'_> {
    /// Whether its programme fills at most `max_work` cells (states × counts ×
    /// candidates), and its states fit a `u16`.
    pub(super) fn fits(&self, max_work: usize) -> bool {
        let states = (self.needs.iter()).try_fold(1usize, |n, &(_, r)| n.checked_mul(r + 1));
        let robots = self.candidates.len() + self.fixed.len() + 1;
        states.is_some_and(|s| {
            s <= usize::from(u16::MAX) && s.saturating_mul(robots * robots) <= max_work
        })
    }
}

/// The dynamic programme's buffers, kept between tasks.
#[derive(Default)]
pub(super) struct Programme {
    cost: Vec<f64>,
    next: Vec<f64>,
    /// Per layer, state and count: the state it came from where the layer's robot
    /// was taken (`u16::MAX`: not taken).
    from: Vec<u16>,
    layers: Vec<usize>,
    fillers: Vec<usize>,
}

/// Task `at`'s best team at robot weights `w` (cost plus price): its worth (F of its
/// size where it earns, less its members' weights; minus infinity where it may hold no
/// team), its members written to `members`.
pub(super) fn best_team(
    inst: &Instance,
    at: &TaskAt,
    w: &[f64],
    dp: &mut Programme,
    members: &mut Vec<usize>,
) -> f64 {
    let limit = match at.role {
        Role::Earn => None,
        Role::Either { capacity } => Some(capacity),
        Role::Idle { room } => Some(room),
    };
    let idle = limit.map_or(f64::NEG_INFINITY, |limit| {
        idle_team(at, w, limit, dp, members)
    });
    if matches!(at.role, Role::Idle { .. }) {
        return idle;
    }
    let kept = members.len();
    let earn = earning_team(inst, at, w, dp, members);
    if earn > idle {
        members.drain(..kept);
        earn
    } else {
        members.truncate(kept);
        idle
    }
}

/// The best team of at most `limit` robots that earns nothing: the fixed robots and
/// every other candidate that gains, the most gaining first (written to `members`).
fn idle_team(
    at: &TaskAt,
    w: &[f64],
    limit: usize,
    dp: &mut Programme,
    members: &mut Vec<usize>,
) -> f64 {
    members.clear();
    if at.fixed.len() > limit {
        return f64::NEG_INFINITY;
    }
    dp.fillers.clear();
    (dp.fillers).extend(at.candidates.iter().filter(|&&i| w[i] < 0.0));
    dp.fillers.sort_by(|&a, &b| w[a].total_cmp(&w[b]));
    dp.fillers.truncate(limit - at.fixed.len());
    members.extend(at.fixed.iter().chain(&dp.fillers));
    -members.iter().map(|&i| w[i]).sum::<f64>()
}

/// The best earning team (appended to `members`): the programme over the fixed robots
/// and the candidates holding a skill the task requires, then the cheapest of its
/// other candidates.
fn earning_team(
    inst: &Instance,
    at: &TaskAt,
    w: &[f64],
    dp: &mut Programme,
    members: &mut Vec<usize>,
) -> f64 {
    let needs = &at.needs;
    let value = inst.value_function(at.j);
    let holds = |i: usize| {
        let q = inst.skills(RobotId(i as u32));
        needs.iter().any(|&(s, _)| q[s] > 0)
    };
    dp.layers.clear();
    dp.layers.extend(at.fixed);
    let optional = dp.layers.len();
    dp.layers
        .extend(at.candidates.iter().filter(|&&i| holds(i)));
    dp.fillers.clear();
    (dp.fillers).extend(at.candidates.iter().filter(|&&i| !holds(i)));
    dp.fillers.sort_by(|&a, &b| w[a].total_cmp(&w[b]));
    let states: usize = needs.iter().map(|&(_, r)| r + 1).product();
    // A team larger than its least earning core (at most its threshold, or one robot
    // per unit it requires) holds only members it could lose and still earn; each is
    // worth keeping only where F's marginal there pays its weight, and F is concave: no
    // more such members than candidates that cheap (and the robots fixed there).
    let core = at.threshold.max(needs.iter().map(|&(_, r)| r).sum());
    let marginal = value.value(core + 1) - value.value(core);
    let cheap = (at.candidates.iter())
        .filter(|&&i| w[i] <= marginal)
        .count();
    let counts = (at
        .capacity
        .min(dp.layers.len())
        .min(core + cheap + at.fixed.len()))
        + 1;
    fill(inst, needs, states, counts, optional, w, dp);
    // The covering members (c of them), then the f cheapest other candidates.
    let full = states - 1;
    let mut best = (f64::NEG_INFINITY, 0, 0);
    for c in 0..counts {
        let mut weight = dp.cost[full * counts + c];
        if !weight.is_finite() {
            continue;
        }
        for f in 0..=dp.fillers.len().min(at.capacity - c) {
            if f > 0 {
                weight += w[dp.fillers[f - 1]];
            }
            if c + f >= at.threshold.max(1) && value.value(c + f) - weight > best.0 {
                best = (value.value(c + f) - weight, c, f);
            }
        }
    }
    let (earn, mut c, f) = best;
    if earn.is_finite() {
        members.extend(&dp.fillers[..f]);
        let (cells, mut state) = (states * counts, full);
        for layer in (0..dp.layers.len()).rev() {
            let from = dp.from[layer * cells + state * counts + c];
            if from != u16::MAX {
                members.push(dp.layers[layer]);
                state = usize::from(from);
                c -= 1;
            }
        }
    }
    earn
}

/// The least weight of the programme's layers (the first `optional` taken) that meets
/// each state of `needs` with each count of members (`dp.cost`, state-major), and
/// where each layer's robot was taken from (`dp.from`).
fn fill(
    inst: &Instance,
    needs: &[(usize, usize)],
    states: usize,
    counts: usize,
    optional: usize,
    w: &[f64],
    dp: &mut Programme,
) {
    let cells = states * counts;
    dp.cost.clear();
    dp.cost.resize(cells, f64::INFINITY);
    dp.cost[0] = 0.0;
    dp.from.clear();
    dp.from.resize(cells * dp.layers.len(), u16::MAX);
    for (layer, &i) in dp.layers.iter().enumerate() {
        let q = inst.skills(RobotId(i as u32));
        dp.next.clear();
        if layer < optional {
            dp.next.resize(cells, f64::INFINITY);
        } else {
            dp.next.extend_from_slice(&dp.cost);
        }
        let from = &mut dp.from[layer * cells..][..cells];
        for state in 0..states {
            let (mut rest, mut to, mut radix) = (state, 0, 1);
            for &(s, r) in needs {
                let met = rest % (r + 1);
                rest /= r + 1;
                to += (met + q[s] as usize).min(r) * radix;
                radix *= r + 1;
            }
            for c in 0..counts - 1 {
                let v = dp.cost[state * counts + c] + w[i];
                let cell = to * counts + c + 1;
                if v < dp.next[cell] {
                    dp.next[cell] = v;
                    from[cell] = state as u16;
                }
            }
        }
        std::mem::swap(&mut dp.cost, &mut dp.next);
    }
}

#[cfg(test)]
mod tests {
    use afg_game::{Instance, RobotId, TaskId};
    use proptest::prelude::*;

    use super::super::super::lagrange::tests::skill_knobs;
    use super::{Programme, Role, TaskAt, best_team, skill_needs};

    /// What team `members` is worth to task `at` at weights `w`, by the rules
    /// [`best_team`] maximises (minus infinity where the task may not hold it).
    fn worth(inst: &Instance, at: &TaskAt, w: &[f64], members: &[usize]) -> f64 {
        let mut held = vec![0u64; inst.num_skills()];
        for &i in members {
            for (h, &q) in held.iter_mut().zip(inst.skills(RobotId(i as u32))) {
                *h += u64::from(q);
            }
        }
        let n = members.len();
        let earns = n >= at.threshold.max(1)
            && n <= at.capacity
            && (inst.requires(at.j).iter().zip(&held)).all(|(&r, &h)| h >= u64::from(r));
        let paid: f64 = members.iter().map(|&i| w[i]).sum();
        let value = match at.role {
            Role::Earn if earns => inst.value_function(at.j).value(n),
            Role::Either { capacity } if earns || n <= capacity => {
                if earns {
                    inst.value_function(at.j).value(n)
                } else {
                    0.0
                }
            }
            Role::Idle { room } if n <= room => 0.0,
            _ => return f64::NEG_INFINITY,
        };
        value - paid
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(300))]

        /// A task's best team is the best of every team it may hold (every subset of
        /// its candidates with its fixed robots), and the members it names are worth
        /// what it says.
        #[test]
        fn the_best_team_is_the_best_of_every_team(
            seed in 0u64..10_000,
            threshold in 1usize..=4,
            capacity in 1usize..=8,
            role in 0usize..3,
            chosen in proptest::collection::vec(0usize..4, 8),
            w in proptest::collection::vec(-1.0f64..2.0, 8),
        ) {
            let inst = skill_knobs(0.4, (0, 2)).config(8, 1, seed).unwrap().generate().unwrap();
            // Per robot: 0 not a candidate, 1 fixed there, else a candidate.
            let candidates: Vec<usize> = (0..8).filter(|&i| chosen[i] >= 2).collect();
            let fixed: Vec<usize> = (0..8).filter(|&i| chosen[i] == 1).collect();
            let role = [Role::Earn, Role::Either { capacity }, Role::Idle { room: capacity / 2 }][role];
            let needs = skill_needs(&inst, TaskId(0));
            let at = TaskAt { j: TaskId(0), needs, threshold, capacity, role, candidates: &candidates, fixed: &fixed };
            let mut best = f64::NEG_INFINITY;
            for subset in 0u32..1 << candidates.len() {
                let mut members = fixed.clone();
                members.extend((0..candidates.len()).filter(|&b| subset >> b & 1 == 1).map(|b| candidates[b]));
                best = best.max(worth(&inst, &at, &w, &members));
            }
            let mut members = Vec::new();
            let found = best_team(&inst, &at, &w, &mut Programme::default(), &mut members);
            prop_assert!((found - best).abs() < 1e-9 || found == best, "{found} vs {best}");
            if found.is_finite() {
                prop_assert!((worth(&inst, &at, &w, &members) - found).abs() < 1e-9);
                prop_assert!(fixed.iter().all(|i| members.contains(i)));
            }
        }
    }
}

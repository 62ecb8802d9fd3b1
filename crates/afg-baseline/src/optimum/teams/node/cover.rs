//! The cheapest team a task needs: the least summed reduced cost of robots that
//! together hold its threshold of members and every skill it requires (a covering
//! knapsack), asked by the reduced-cost fixing of tasks ([`super::fixing`]).

use afg_game::{Instance, TaskId};

/// The most states, and states times robots, in which [`joint_cover`] covers all of a
/// task's needs at once.
const JOINT_STATES: usize = 1 << 12;
const JOINT_WORK: usize = 1 << 20;

/// Whether `closes` holds at the least summed reduced cost (`reduced[i]`: robot i's at
/// task j) of any team that lets task j earn: the cheapest robots that together hold
/// its `threshold` of members and every skill it requires, or where that takes more
/// than [`JOINT_STATES`] states or [`JOINT_WORK`] steps, at a lower bound on it
/// ([`apart`]). `closes` must hold at every cost above one where it holds: the lower
/// bound settles it where it holds there, a greedy team where it does not hold there.
pub(super) fn cheapest_team_closes(
    instance: &Instance,
    j: TaskId,
    threshold: usize,
    reduced: &[f64],
    closes: impl Fn(f64) -> bool,
) -> bool {
    let needs = needs(instance, j, threshold);
    if closes(apart(&needs, reduced)) {
        return true;
    }
    if !closes(greedy_team(&needs, reduced)) {
        return false;
    }
    joint_cover(&needs, reduced).is_some_and(closes)
}

/// The least summed reduced cost of robots that together meet every one of `needs` (a
/// covering knapsack, exact by dynamic programming), where it takes at most
/// [`JOINT_STATES`] states and [`JOINT_WORK`] steps.
fn joint_cover(needs: &[(usize, Vec<usize>)], reduced: &[f64]) -> Option<f64> {
    let states = needs
        .iter()
        .try_fold(1usize, |n, (need, _)| n.checked_mul(need + 1))
        .filter(|&states| states <= JOINT_STATES && states * reduced.len() <= JOINT_WORK)?;
    Some(cover(needs, states, reduced))
}

/// A lower bound on [`joint_cover`]: the largest of each need's own cheapest cover
/// (the members': the `threshold` lowest reduced costs).
fn apart(needs: &[(usize, Vec<usize>)], reduced: &[f64]) -> f64 {
    let k = needs[0].0.min(reduced.len());
    let mut lowest = reduced.to_vec();
    if k > 0 {
        lowest.select_nth_unstable_by(k - 1, f64::total_cmp);
    }
    let members: f64 = lowest[..k].iter().sum();
    (needs[1..].iter())
        .map(|need| cover(std::slice::from_ref(need), need.0 + 1, reduced))
        .fold(members, f64::max)
}

/// The summed reduced cost of a team that meets every one of `needs` (infinite where
/// none does), at least [`joint_cover`]: for each skill, then the members, the cheapest
/// robots not yet taken that add to it until it is met.
fn greedy_team(needs: &[(usize, Vec<usize>)], reduced: &[f64]) -> f64 {
    let mut order: Vec<usize> = (0..reduced.len()).collect();
    order.sort_by(|&a, &b| reduced[a].total_cmp(&reduced[b]));
    let (mut taken, mut met, mut cost) = (vec![false; reduced.len()], vec![0; needs.len()], 0.0);
    for k in (1..needs.len()).chain([0]) {
        for &i in &order {
            if met[k] >= needs[k].0 {
                break;
            }
            if taken[i] || needs[k].1[i] == 0 {
                continue;
            }
            taken[i] = true;
            cost += reduced[i];
            for (units, (_, held)) in met.iter_mut().zip(needs) {
                *units += held[i];
            }
        }
    }
    let all_met = met
        .iter()
        .zip(needs)
        .all(|(&units, (need, _))| units >= *need);
    if all_met { cost } else { f64::INFINITY }
}

/// Task j's needs: how much of each (its `threshold` of members, then every skill it
/// requires), and how much of it each robot holds.
fn needs(instance: &Instance, j: TaskId, threshold: usize) -> Vec<(usize, Vec<usize>)> {
    let mut needs = vec![(threshold, vec![1; instance.num_robots()])];
    for (s, &need) in instance.requires(j).iter().enumerate() {
        if need > 0 {
            let held = instance.robot_ids().map(|i| instance.skills(i)[s] as usize);
            needs.push((need as usize, held.collect()));
        }
    }
    needs
}

/// The least summed reduced cost of robots that together meet every need (a state: the
/// units met of each need, capped at the need, in mixed radix), over `states` states.
fn cover(needs: &[(usize, Vec<usize>)], states: usize, reduced: &[f64]) -> f64 {
    let mut cost = vec![f64::INFINITY; states];
    cost[0] = 0.0;
    let mut next = cost.clone();
    for (i, &r) in reduced.iter().enumerate() {
        if needs.iter().all(|(_, held)| held[i] == 0) {
            continue;
        }
        for (state, &c) in cost.iter().enumerate().filter(|(_, c)| c.is_finite()) {
            let (mut rest, mut to, mut radix) = (state, 0, 1);
            for (need, held) in needs {
                let met = rest % (need + 1);
                rest /= need + 1;
                to += (met + held[i]).min(*need) * radix;
                radix *= need + 1;
            }
            next[to] = next[to].min(c + r);
        }
        cost.copy_from_slice(&next);
    }
    cost[states - 1]
}

#[cfg(test)]
mod tests {
    use super::super::lagrange::tests::skill_knobs;
    use super::{apart, cheapest_team_closes, cover, greedy_team, joint_cover, needs};

    /// The cheapest team is the least reduced cost over every team that holds the
    /// threshold and the skills (brute force over the subsets of 7 robots), the lower
    /// bound for many needs is below it and the greedy team above it, and whether a
    /// limit closes at the cheapest team is decided as at the brute force's, for limits
    /// at, between and beyond those bounds.
    #[test]
    fn the_cheapest_team_is_the_cheapest_covering_subset() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let mut joint_asked = 0;
        for seed in 0..40 {
            let inst = skill_knobs(0.5, (0, 3))
                .config(7, 2, seed)
                .unwrap()
                .generate()
                .unwrap();
            let reduced: Vec<f64> = (0..7).map(|_| rng.random_range(0.0..1.0)).collect();
            for j in inst.task_ids() {
                let k = inst.min_team(j);
                let brute = (0u32..1 << 7)
                    .filter(|set| set.count_ones() as usize >= k)
                    .filter(|set| {
                        let mut held = vec![0u64; inst.num_skills()];
                        for i in inst.robot_ids().filter(|i| set >> i.index() & 1 == 1) {
                            for (h, &q) in held.iter_mut().zip(inst.skills(i)) {
                                *h += u64::from(q);
                            }
                        }
                        inst.skills_met(j, &held)
                    })
                    .map(|set| {
                        (0..7)
                            .filter(|i| set >> i & 1 == 1)
                            .map(|i| reduced[i])
                            .sum()
                    })
                    .fold(f64::INFINITY, f64::min);
                let needs = needs(&inst, j, k);
                let cheapest = joint_cover(&needs, &reduced).unwrap();
                assert!(
                    (cheapest - brute).abs() < 1e-12 || cheapest == brute,
                    "{cheapest} {brute}"
                );
                let (low, high) = (apart(&needs, &reduced), greedy_team(&needs, &reduced));
                assert!(low <= cheapest + 1e-12 && cheapest <= high + 1e-12);
                assert_eq!(high.is_finite(), brute.is_finite());
                let between = |a: f64, b: f64| {
                    if a.is_finite() && b.is_finite() {
                        0.5 * (a + b)
                    } else {
                        a
                    }
                };
                for limit in [
                    low - 0.1,
                    between(low, brute),
                    brute,
                    between(brute, high),
                    high + 0.1,
                ] {
                    let closes = |cost: f64| cost >= limit - 1e-9;
                    assert_eq!(
                        cheapest_team_closes(&inst, j, k, &reduced, closes),
                        closes(brute),
                        "seed {seed} task {}: limit {limit}, cheapest {brute}",
                        j.index()
                    );
                    joint_asked += usize::from(!closes(low) && closes(high));
                }
                // the members alone: the k lowest reduced costs
                let mut sorted = reduced.clone();
                sorted.sort_by(f64::total_cmp);
                let members: f64 = sorted[..k].iter().sum();
                let alone = cover(&needs[..1], k + 1, &reduced);
                assert!((alone - members).abs() < 1e-12, "{alone} {members}");
                if inst.requires(j).iter().all(|&r| r == 0) {
                    assert!((cheapest - members).abs() < 1e-12);
                }
            }
        }
        assert!(
            joint_asked >= 10,
            "the exact cover asked {joint_asked} times"
        );
    }
}

//! From an order of the tasks to a schedule: each task in turn gets the team that can
//! start it soonest without anyone waiting longer than `max_wait`.
//!
//! Every route then follows one global order, so no two robots can wait for each other
//! in a cycle, and each task is staffed by exactly its team (no extras): the timing below
//! is the evaluator's, task by task.

use crate::ScheduleInstance;
use crate::instance::straight;

/// How much more a minute of driving weighs than a minute of arrival time when a task
/// without skills picks its team (0: the earliest arrivals, whoever they are).
const TRAVEL_WEIGHT: f64 = 0.3;

/// Teams up to this size are picked by insertion (see [`smallest`]).
const SMALL_TEAM: usize = 16;

/// The most travel times kept in a table (128 MiB); larger instances compute them.
const TABLE_LIMIT: usize = 1 << 24;

/// The instance, precomputed for decoding: travel times, durations, team needs.
pub(crate) struct Decoder {
    num_robots: usize,
    num_tasks: usize,
    /// Places: tasks `0..M`, robot starts `M..M+N`, depots `M+N..`.
    points: Vec<[f64; 2]>,
    speed: f64,
    /// All travel times, place by place, where they fit in [`TABLE_LIMIT`] entries.
    table: Option<Vec<f64>>,
    home: Vec<usize>,
    duration: Vec<f64>,
    team_floor: Vec<usize>,
    /// `robot_skills[i * S + s]`, `requires[j * S + s]`.
    robot_skills: Vec<u32>,
    requires: Vec<u32>,
    num_skills: usize,
    max_wait: f64,
    return_to_depot: bool,
}

/// Where the robots are between two tasks of the order.
#[derive(Clone, PartialEq, Debug)]
pub(crate) struct Fleet {
    /// When each robot is free to leave.
    pub(crate) free: Vec<f64>,
    /// The place it leaves from.
    pub(crate) at: Vec<usize>,
}

impl Decoder {
    pub(crate) fn new(inst: &ScheduleInstance, max_wait: f64) -> Self {
        let (n, m, s) = (inst.num_robots(), inst.num_tasks(), inst.num_skills());
        let mut points: Vec<[f64; 2]> = inst.tasks.iter().map(|t| [t.x, t.y]).collect();
        points.extend(inst.robots.iter().map(|r| [r.x, r.y]));
        points.extend(inst.depots.iter().copied());
        let p = points.len();
        let table = (p * p <= TABLE_LIMIT).then(|| {
            let mut table = Vec::with_capacity(p * p);
            for a in 0..p {
                table.extend((0..p).map(|b| straight(points[a], points[b]) / inst.speed));
            }
            table
        });
        Decoder {
            table,
            num_robots: n,
            num_tasks: m,
            points,
            speed: inst.speed,
            home: inst.robots.iter().map(|r| m + n + r.depot).collect(),
            duration: inst.tasks.iter().map(|t| t.duration).collect(),
            team_floor: inst.tasks.iter().map(|t| t.team_floor()).collect(),
            robot_skills: (0..n)
                .flat_map(|i| (0..s).map(move |k| (i, k)))
                .map(|(i, k)| inst.robot_skill(i, k))
                .collect(),
            requires: (0..m)
                .flat_map(|j| (0..s).map(move |k| (j, k)))
                .map(|(j, k)| inst.task_requires(j, k))
                .collect(),
            num_skills: s,
            max_wait,
            return_to_depot: inst.return_to_depot,
        }
    }

    /// The travel time between two places.
    pub(crate) fn time(&self, from: usize, to: usize) -> f64 {
        match &self.table {
            Some(table) => table[from * self.points.len() + to],
            None => straight(self.points[from], self.points[to]) / self.speed,
        }
    }

    /// The `count` tasks nearest each task, nearest first.
    pub(crate) fn neighbours(&self, count: usize) -> Vec<Vec<usize>> {
        (0..self.num_tasks)
            .map(|j| {
                let mut others: Vec<usize> = (0..self.num_tasks).filter(|&o| o != j).collect();
                let far = |o: &usize| self.time(j, *o);
                let count = count.min(others.len());
                if count > 0 && count < others.len() {
                    others.select_nth_unstable_by(count - 1, |a, b| far(a).total_cmp(&far(b)));
                }
                others.truncate(count);
                others.sort_by(|a, b| far(a).total_cmp(&far(b)));
                others
            })
            .collect()
    }

    /// The fleet at time 0.
    pub(crate) fn start(&self) -> Fleet {
        Fleet {
            free: vec![0.0; self.num_robots],
            at: (0..self.num_robots).map(|i| self.num_tasks + i).collect(),
        }
    }

    /// When each robot would arrive at task j.
    fn ready(&self, fleet: &Fleet, j: usize, ready: &mut Vec<(f64, usize)>) {
        ready.clear();
        ready.extend((0..self.num_robots).map(|i| (fleet.free[i] + self.time(fleet.at[i], j), i)));
        ready.sort_unstable_by(by_key);
    }

    /// The k robots that arrive first when driving counts [`TRAVEL_WEIGHT`] times more:
    /// a team drawn from robots nearby rather than from anyone who could arrive a little
    /// earlier from far away. None when that team would wait longer than `max_wait`.
    fn staff_near(
        &self,
        fleet: &Fleet,
        j: usize,
        ready: &mut Vec<(f64, usize)>,
        team: &mut Vec<usize>,
    ) -> Option<f64> {
        let k = self.team_floor[j];
        let arrive = |i: usize| fleet.free[i] + self.time(fleet.at[i], j);
        let keyed = (0..self.num_robots).map(|i| {
            let drive = self.time(fleet.at[i], j);
            (fleet.free[i] + drive + TRAVEL_WEIGHT * drive, i)
        });
        smallest(keyed, k, ready);
        team.clear();
        team.extend(ready.iter().map(|r| r.1));
        let start = team.iter().map(|&i| arrive(i)).fold(f64::MIN, f64::max);
        let first = team.iter().map(|&i| arrive(i)).fold(f64::MAX, f64::min);
        (start - first <= self.max_wait).then_some(start)
    }

    /// Staffs task j: its team into `team`; returns when it starts and how far its first
    /// member waits beyond `max_wait` (0 unless no team can gather in time, when the team
    /// that starts soonest is taken and the search pays for the excess).
    pub(crate) fn staff(
        &self,
        fleet: &Fleet,
        j: usize,
        ready: &mut Vec<(f64, usize)>,
        team: &mut Vec<usize>,
    ) -> (f64, f64) {
        if self.num_skills == 0
            && let Some(start) = self.staff_near(fleet, j, ready, team)
        {
            return (start, 0.0);
        }
        self.ready(fleet, j, ready);
        let in_time = if self.num_skills == 0 {
            self.staff_by_count(j, ready, team)
        } else {
            self.staff_by_skills(j, ready, team, self.max_wait)
        };
        if let Some(start) = in_time {
            return (start, 0.0);
        }
        let start = if self.num_skills == 0 {
            let k = self.team_floor[j];
            team.clear();
            team.extend(ready[..k].iter().map(|r| r.1));
            ready[k - 1].0
        } else {
            self.staff_by_skills(j, ready, team, f64::INFINITY)
                .expect("a validated instance can staff every task")
        };
        let first = team
            .iter()
            .map(|&i| ready.iter().find(|r| r.1 == i).expect("ready").0)
            .fold(f64::INFINITY, f64::min);
        (start, start - first - self.max_wait)
    }

    fn staff_by_count(
        &self,
        j: usize,
        ready: &[(f64, usize)],
        team: &mut Vec<usize>,
    ) -> Option<f64> {
        let k = self.team_floor[j];
        let mut lo = 0;
        for e in k - 1..ready.len() {
            let latest = ready[e].0;
            while ready[lo].0 < latest - self.max_wait {
                lo += 1;
            }
            if e + 1 - lo >= k {
                team.clear();
                team.extend(ready[e + 1 - k..=e].iter().map(|r| r.1));
                return Some(latest);
            }
        }
        None
    }

    /// The soonest team that covers task j's skills and count with no member waiting
    /// longer than `max_wait`.
    fn staff_by_skills(
        &self,
        j: usize,
        ready: &[(f64, usize)],
        team: &mut Vec<usize>,
        max_wait: f64,
    ) -> Option<f64> {
        let s = self.num_skills;
        let need = &self.requires[j * s..(j + 1) * s];
        let mut lacking = vec![0u32; s];
        for e in 0..ready.len() {
            let latest = ready[e].0;
            lacking.copy_from_slice(need);
            let mut count_left = self.team_floor[j];
            team.clear();
            for &(r, i) in ready[..=e].iter().rev() {
                if r < latest - max_wait {
                    break;
                }
                let skills = &self.robot_skills[i * s..(i + 1) * s];
                let covered = lacking.iter().all(|&l| l == 0);
                let helps = lacking.iter().zip(skills).any(|(&l, &h)| l > 0 && h > 0)
                    || (covered && count_left > 0);
                if !helps {
                    if i == ready[e].1 {
                        break; // the latest must be needed, or an earlier team starts sooner
                    }
                    continue;
                }
                team.push(i);
                count_left = count_left.saturating_sub(1);
                for (l, &h) in lacking.iter_mut().zip(skills) {
                    *l = l.saturating_sub(h);
                }
                if count_left == 0 && lacking.iter().all(|&l| l == 0) {
                    self.prune(j, team);
                    return Some(latest);
                }
            }
        }
        None
    }

    /// Whether `team` holds task j's count and every skill it requires.
    fn covers(&self, j: usize, team: &[usize]) -> bool {
        let s = self.num_skills;
        team.len() >= self.team_floor[j]
            && (0..s).all(|k| {
                team.iter()
                    .map(|&i| self.robot_skills[i * s + k])
                    .sum::<u32>()
                    >= self.requires[j * s + k]
            })
    }

    /// Drops members the team can do without, earliest arrivals first (they would wait
    /// longest): a team with a member to spare would complete before that member commits,
    /// and the simulator would treat it as an extra.
    fn prune(&self, j: usize, team: &mut Vec<usize>) {
        let mut k = team.len();
        while k > 1 {
            k -= 1;
            let without: Vec<usize> = team
                .iter()
                .enumerate()
                .filter(|&(x, _)| x != k)
                .map(|(_, &i)| i)
                .collect();
            if self.covers(j, &without) {
                team.remove(k);
            }
        }
    }

    /// Sends `team` to task j starting at `start`.
    pub(crate) fn assign(&self, fleet: &mut Fleet, j: usize, start: f64, team: &[usize]) {
        for &i in team {
            fleet.free[i] = start + self.duration[j];
            fleet.at[i] = j;
        }
    }

    /// When each robot is back, given the fleet after its last task.
    pub(crate) fn back(&self, fleet: &Fleet, i: usize) -> f64 {
        let ret = if self.return_to_depot {
            self.time(fleet.at[i], self.home[i])
        } else {
            0.0
        };
        fleet.free[i] + ret
    }

    /// The makespan of a finished fleet and the mean of the robots' return times.
    pub(crate) fn score(&self, fleet: &Fleet) -> (f64, f64) {
        let (mut makespan, mut sum) = (0.0f64, 0.0);
        for i in 0..self.num_robots {
            let b = self.back(fleet, i);
            makespan = makespan.max(b);
            sum += b;
        }
        (makespan, sum / self.num_robots as f64)
    }

    /// Decodes a whole order into routes.
    pub(crate) fn routes(&self, order: &[usize]) -> Vec<Vec<usize>> {
        let mut fleet = self.start();
        let (mut ready, mut team) = (Vec::new(), Vec::new());
        let mut routes = vec![Vec::new(); self.num_robots];
        for &j in order {
            let (start, _) = self.staff(&fleet, j, &mut ready, &mut team);
            self.assign(&mut fleet, j, start, &team);
            for &i in &team {
                routes[i].push(j);
            }
        }
        routes
    }
}

/// Robots keyed by a time, the soonest first, ties by the lower index.
fn by_key(a: &(f64, usize), b: &(f64, usize)) -> std::cmp::Ordering {
    a.0.total_cmp(&b.0).then(a.1.cmp(&b.1))
}

/// The `k` smallest of `items` by (key, index) into `out`, in no particular order:
/// kept sorted by insertion while k is small (a team's size; O(N k) and no
/// partitioning), selected in place beyond.
fn smallest(items: impl Iterator<Item = (f64, usize)>, k: usize, out: &mut Vec<(f64, usize)>) {
    let less = |a: &(f64, usize), b: &(f64, usize)| by_key(a, b).is_lt();
    out.clear();
    if k > SMALL_TEAM {
        out.extend(items);
        out.select_nth_unstable_by(k - 1, by_key);
        out.truncate(k);
        return;
    }
    let mut best = [(f64::INFINITY, usize::MAX); SMALL_TEAM];
    let mut len = 0;
    for item in items {
        if len == k {
            if !less(&item, &best[k - 1]) {
                continue;
            }
        } else {
            len += 1;
        }
        // Shift the larger ones up one place and drop the item in.
        let mut at = len - 1;
        while at > 0 && less(&item, &best[at - 1]) {
            best[at] = best[at - 1];
            at -= 1;
        }
        best[at] = item;
    }
    out.extend_from_slice(&best[..len]);
}

#[cfg(test)]
mod tests {
    use proptest::prelude::*;
    use rand::SeedableRng;
    use rand::seq::SliceRandom;
    use rand_chacha::ChaCha8Rng;

    use super::*;

    proptest! {
        /// The k smallest by (key, index) are the first k of the sorted list, for teams
        /// picked by insertion and by selection alike, ties in the keys included, in
        /// whatever order the items come.
        #[test]
        fn smallest_are_the_first_of_the_sorted(
            keys in proptest::collection::vec(0u8..6, 1..40),
            k in 1usize..40,
            seed in any::<u64>(),
        ) {
            let k = k.min(keys.len());
            let mut items: Vec<(f64, usize)> =
                keys.iter().enumerate().map(|(i, &key)| (f64::from(key) / 4.0, i)).collect();
            items.shuffle(&mut ChaCha8Rng::seed_from_u64(seed));
            let mut sorted = items.clone();
            sorted.sort_by(by_key);
            let mut out = vec![(9.0, 99)]; // cleared first
            smallest(items.iter().copied(), k, &mut out);
            out.sort_by(by_key);
            prop_assert_eq!(out, sorted[..k].to_vec());
        }
    }
}

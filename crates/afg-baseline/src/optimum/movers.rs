//! The residual edges between task nodes: for every ordered pair (j, k), the robots of
//! task j keyed by the cost of moving them to k, cheapest first.

use dary_heap::QuaternaryHeap as Heap;
use std::cmp::Ordering;

/// Tasks that at most this many robots ever entered refresh a pair by a scan of them,
/// not a heap.
const SCAN: usize = 32;

/// Marks a robot that is in no heap's task (unassigned, or fixed where it is).
pub(super) const NOWHERE: u32 = u32::MAX;

/// A robot in task j, keyed by the cost of moving it to task k: `c_rk − c_rj`.
#[derive(Clone, Copy)]
pub(super) struct Entry {
    pub key: f64,
    pub robot: u32,
}

impl PartialEq for Entry {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other) == Ordering::Equal
    }
}
impl Eq for Entry {}
impl PartialOrd for Entry {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for Entry {
    /// Reversed, so that the (max-)heap pops the cheapest; ties by lower robot index.
    fn cmp(&self, other: &Self) -> Ordering {
        other
            .key
            .total_cmp(&self.key)
            .then(other.robot.cmp(&self.robot))
    }
}

/// The cheapest live robot of every ordered task pair, read in O(1), over one
/// lazy-deletion heap per pair built the first time that pair's cheapest robot leaves.
///
/// An entry of heap (j, k) is live while its robot's task (in the caller's `task_of`)
/// is j: a robot that leaves j leaves stale entries behind, dropped when they reach the
/// top. A robot entering j updates the cheapest entry of every pair (j, k) at once but
/// joins the heaps only when one is next needed (when its pair's cheapest robot
/// leaves): most pairs never lose their cheapest robot, so most heaps are never built
/// or refilled. A robot that comes back to j enters with the same keys again, which is
/// harmless.
#[derive(Clone)]
pub(super) struct Movers {
    m: usize,
    /// `key[j * m + k]`, `robot[j * m + k]`: the cheapest live entry of pair (j, k),
    /// apart so that a row of keys is one slice; [`Entry::NONE`]'s if j has no movable
    /// robot.
    key: Vec<f64>,
    robot: Vec<u32>,
    heaps: Vec<Option<Heap<Entry>>>,
    /// Every robot that ever entered each task (some have left again).
    members: Vec<Vec<u32>>,
    /// `absorbed[j * m + k]`: how many of `members[j]` heap (j, k) has taken.
    absorbed: Vec<usize>,
    /// Columns no robot may move to (removed tasks).
    closed: Vec<bool>,
}

impl Entry {
    /// No robot: an edge that does not exist.
    const NONE: Entry = Entry {
        key: f64::INFINITY,
        robot: NOWHERE,
    };
}

impl Movers {
    /// The movers of `task_of` (`NOWHERE` for a robot that may not move), with
    /// `costs` the row-major N × M cost matrix, and no robot moving to a column where
    /// `closed`: one pass over it.
    pub fn new(task_of: &[u32], costs: &[f64], closed: Vec<bool>) -> Self {
        let m = closed.len();
        let mut movers = Movers {
            m,
            key: vec![f64::INFINITY; m * m],
            robot: vec![NOWHERE; m * m],
            heaps: (0..m * m).map(|_| None).collect(),
            members: vec![Vec::new(); m],
            absorbed: vec![0; m * m],
            closed,
        };
        // What `enter` does for every robot, in one tight pass: robots come in index
        // order, so a later one with the same key never displaces an earlier one.
        for (robot, &task) in task_of.iter().enumerate() {
            if task == NOWHERE {
                continue;
            }
            let (j, row) = (task as usize, &costs[robot * m..][..m]);
            movers.members[j].push(robot as u32);
            let keys = &mut movers.key[j * m..][..m];
            let robots = &mut movers.robot[j * m..][..m];
            for (k, &cost) in row.iter().enumerate() {
                let key = cost - row[j];
                if key < keys[k] {
                    keys[k] = key;
                    robots[k] = robot as u32;
                }
            }
        }
        // No robot moves to its own column or to a closed one.
        for j in 0..m {
            for k in 0..m {
                if k == j || movers.closed[k] {
                    movers.set_top(j * m + k, Entry::NONE);
                }
            }
        }
        movers
    }

    /// The cost of moving the cheapest robot of task `j` to each task k (`keys(j)[k]`;
    /// infinite where there is none).
    pub fn keys(&self, j: usize) -> &[f64] {
        &self.key[j * self.m..][..self.m]
    }

    /// The cheapest robot of task `j` to move to task `k` (`NOWHERE` if none).
    pub fn robot(&self, j: usize, k: usize) -> u32 {
        self.robot[j * self.m + k]
    }

    /// The cheapest live entry of `pair`.
    fn top(&self, pair: usize) -> Entry {
        Entry {
            key: self.key[pair],
            robot: self.robot[pair],
        }
    }

    fn set_top(&mut self, pair: usize, entry: Entry) {
        self.key[pair] = entry.key;
        self.robot[pair] = entry.robot;
    }

    /// Records that `robot` (with cost row `costs`) has entered `task`.
    pub fn enter(&mut self, robot: u32, task: usize, costs: &[f64]) {
        self.members[task].push(robot);
        for k in 0..self.m {
            if k == task || self.closed[k] {
                continue;
            }
            let pair = task * self.m + k;
            let entry = Entry {
                key: costs[k] - costs[task],
                robot,
            };
            if entry > self.top(pair) {
                self.set_top(pair, entry);
            }
        }
    }

    /// Records that `robot` has left task `j` (`task_of` already says where it went),
    /// refreshing the pairs whose cheapest robot it was.
    pub fn leave(&mut self, robot: u32, j: usize, task_of: &[u32], costs: &[f64]) {
        for k in (0..self.m).filter(|&k| k != j) {
            let pair = j * self.m + k;
            if self.robot[pair] != robot {
                continue;
            }
            let (m, members) = (self.m, &self.members[j]);
            if members.len() <= SCAN && self.heaps[pair].is_none() {
                // Few robots ever entered j: a scan finds the cheapest live one sooner
                // than a heap is built.
                let mut top = Entry::NONE;
                for &r in members
                    .iter()
                    .filter(|&&r| task_of[r as usize] as usize == j)
                {
                    let row = &costs[r as usize * m..][..m];
                    let entry = Entry {
                        key: row[k] - row[j],
                        robot: r,
                    };
                    if entry > top {
                        top = entry;
                    }
                }
                self.set_top(pair, top);
                continue;
            }
            // Those that entered since the heap last took robots (all, for a new heap).
            let fresh = members[self.absorbed[pair]..]
                .iter()
                .filter(|&&r| task_of[r as usize] as usize == j)
                .map(|&robot| {
                    let row = &costs[robot as usize * m..][..m];
                    Entry {
                        key: row[k] - row[j],
                        robot,
                    }
                });
            let heap = self.heaps[pair].get_or_insert_with(Heap::new);
            if heap.is_empty() {
                *heap = Heap::from(fresh.collect::<Vec<_>>());
            } else {
                heap.extend(fresh);
            }
            self.absorbed[pair] = members.len();
            let mut top = Entry::NONE;
            while let Some(&head) = heap.peek() {
                if task_of[head.robot as usize] as usize == j {
                    top = head;
                    break;
                }
                heap.pop();
            }
            self.set_top(pair, top);
        }
    }

    /// Builds the heap of every pair of open columns now, from `task_of` and the
    /// row-major `costs` (one pass over them), so that no move has to build one later.
    pub fn build_all(&mut self, task_of: &[u32], costs: &[f64]) {
        let m = self.m;
        let mut entries: Vec<Vec<Entry>> = vec![Vec::new(); m * m];
        for (robot, &j) in task_of.iter().enumerate() {
            if j == NOWHERE {
                continue;
            }
            let (j, row) = (j as usize, &costs[robot * m..][..m]);
            for k in (0..m).filter(|&k| k != j && !self.closed[k]) {
                entries[j * m + k].push(Entry {
                    key: row[k] - row[j],
                    robot: robot as u32,
                });
            }
        }
        for (pair, list) in entries.into_iter().enumerate() {
            let (j, k) = (pair / m, pair % m);
            if j == k || self.closed[j] || self.closed[k] {
                continue;
            }
            self.install(j, k, list);
        }
    }

    /// Makes `entries` (every live robot of task `j`, keyed for a move to `k`) the
    /// heap of pair (j, k), with its cheapest entry on top.
    fn install(&mut self, j: usize, k: usize, entries: Vec<Entry>) {
        let pair = j * self.m + k;
        let heap = Heap::from(entries);
        self.set_top(pair, heap.peek().copied().unwrap_or(Entry::NONE));
        self.heaps[pair] = Some(heap);
        self.absorbed[pair] = self.members[j].len();
    }

    /// Closes column `k`: no robot may move to it or from it (its robots have left or
    /// are about to, without refreshing its pairs).
    pub fn close(&mut self, k: usize) {
        self.closed[k] = true;
        self.members[k].clear();
        for j in 0..self.m {
            for pair in [k * self.m + j, j * self.m + k] {
                self.set_top(pair, Entry::NONE);
                self.heaps[pair] = None;
                self.absorbed[pair] = 0;
            }
        }
    }

    /// Opens closed column `k` (no robot in it yet) with travel costs `column` (one per
    /// robot), written into `costs` (row-major, M per robot): every robot of `task_of`
    /// may move to it. One pass over the robots, which builds the heaps of the pairs
    /// into `k`.
    pub fn open(&mut self, k: usize, task_of: &[u32], costs: &mut [f64], column: &[f64]) {
        let m = self.m;
        self.closed[k] = false;
        let mut counts = vec![0; m];
        for &j in task_of.iter().filter(|&&j| j != NOWHERE) {
            counts[j as usize] += 1;
        }
        let mut entries: Vec<Vec<Entry>> = counts.into_iter().map(Vec::with_capacity).collect();
        for (robot, (row, &c)) in costs.chunks_mut(m).zip(column).enumerate() {
            row[k] = c;
            let j = task_of[robot];
            if j != NOWHERE {
                entries[j as usize].push(Entry {
                    key: c - row[j as usize],
                    robot: robot as u32,
                });
            }
        }
        for (j, list) in entries.into_iter().enumerate() {
            if j == k || self.closed[j] {
                continue;
            }
            self.install(j, k, list);
        }
    }

    /// Makes room for `wider` columns, the new ones closed.
    pub fn widen(&mut self, wider: usize) {
        let m = self.m;
        let mut key = vec![f64::INFINITY; wider * wider];
        let mut robot = vec![NOWHERE; wider * wider];
        let mut absorbed = vec![0; wider * wider];
        let mut heaps: Vec<Option<Heap<Entry>>> = (0..wider * wider).map(|_| None).collect();
        for j in 0..m {
            key[j * wider..][..m].copy_from_slice(&self.key[j * m..][..m]);
            robot[j * wider..][..m].copy_from_slice(&self.robot[j * m..][..m]);
            absorbed[j * wider..][..m].copy_from_slice(&self.absorbed[j * m..][..m]);
            for k in 0..m {
                heaps[j * wider + k] = self.heaps[j * m + k].take();
            }
        }
        self.key = key;
        self.robot = robot;
        self.absorbed = absorbed;
        self.heaps = heaps;
        self.members.resize(wider, Vec::new());
        self.closed.resize(wider, true);
        self.m = wider;
    }
}

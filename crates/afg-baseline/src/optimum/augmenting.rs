//! Robot by robot: each free robot enters along a shortest augmenting path (the
//! Hungarian / successive-shortest-path scheme). The solver behind
//! [`Optimum::complete`](super::Optimum::complete) and
//! [`Optimum::action_values`](super::Optimum::action_values), and the reference the
//! faster [`transport`](super::transport) solver is tested against.
//!
//! The new robot joins some task j0, a chain of robots shifts j0 → j1 → … → jt, and
//! task jt takes one more member. Johnson potentials keep the reduced costs of the
//! edges between task nodes ([`Movers`]) non-negative, so Dijkstra over the M task
//! nodes applies.
//!
//! # Complexity
//! Per robot O(M² + L M log N) for a path of L shifts; O(N M² log N) in all and
//! O(N M) memory.

use afg_game::{Assignment, Instance, RobotId, TaskId};

use super::movers::{Movers, NOWHERE};

pub(super) struct Solver<'a> {
    inst: &'a Instance,
    /// Nodes: the M tasks, then the void where the instance allows it.
    m: usize,
    /// `costs[i * m + j] = beta d(i, j)`; 0 at the void.
    costs: Vec<f64>,
    pub assignment: Assignment,
    /// The task of every robot the solver placed; `NOWHERE` for fixed and free robots.
    placed: Vec<u32>,
    movers: Movers,
    /// Johnson potentials of the task nodes: every residual edge's reduced cost
    /// `c + potential[from] − potential[to]` is non-negative.
    pub potential: Vec<f64>,
    /// Reduced distances of the last [`Solver::shortest_paths`].
    pub dist: Vec<f64>,
    pred: Vec<Pred>,
    done: Vec<bool>,
    /// Robot shifts made by the augmentations so far.
    pub shifts: u64,
}

impl<'a> Solver<'a> {
    /// A solver holding `partial` (robots assigned there are fixed: never in a heap).
    fn new(inst: &'a Instance, partial: Assignment) -> Self {
        let n = inst.num_robots();
        let m = inst.num_tasks() + usize::from(inst.allows_void());
        let void = inst.allows_void().then_some(0.0);
        let costs: Vec<f64> = inst
            .robot_ids()
            .flat_map(|i| inst.task_ids().map(move |j| inst.cost(i, j)).chain(void))
            .collect();
        let placed = vec![NOWHERE; n];
        Solver {
            inst,
            m,
            movers: Movers::new(&placed, &costs, vec![false; m]),
            costs,
            assignment: partial,
            placed,
            potential: vec![0.0; m],
            dist: vec![0.0; m],
            pred: vec![Pred::Source; m],
            done: vec![false; m],
            shifts: 0,
        }
    }

    pub fn cost(&self, robot: usize, task: usize) -> f64 {
        self.costs[robot * self.m + task]
    }

    /// The task of node `j`; `None` for the void.
    fn task(&self, j: usize) -> Option<TaskId> {
        (j < self.inst.num_tasks()).then_some(TaskId(j as u32))
    }

    /// Puts `robot` in `task` (moving it if the solver placed it before).
    fn place(&mut self, robot: usize, task: usize) {
        self.assignment.set(RobotId(robot as u32), self.task(task));
        let from = std::mem::replace(&mut self.placed[robot], task as u32);
        if from != NOWHERE {
            let (placed, costs) = (&self.placed, &self.costs);
            self.movers
                .leave(robot as u32, from as usize, placed, costs);
        }
        let row = &self.costs[robot * self.m..][..self.m];
        self.movers.enter(robot as u32, task, row);
    }

    /// Dijkstra over the task nodes with reduced costs, from a new unit that enters
    /// task j at the real cost the caller wrote into `dist[j]` (infinite: not there);
    /// only these first edges may be negative. Fills `dist` and `pred`.
    pub fn shortest_paths(&mut self) {
        let m = self.m;
        for j in 0..m {
            self.dist[j] -= self.potential[j];
            self.pred[j] = Pred::Source;
            self.done[j] = false;
        }
        for _ in 0..m {
            let dist = &self.dist;
            let j = (0..m)
                .filter(|&j| !self.done[j])
                .min_by(|&a, &b| dist[a].total_cmp(&dist[b]))
                .expect("an unsettled task remains");
            self.done[j] = true;
            if self.dist[j] == f64::INFINITY {
                break;
            }
            for k in 0..m {
                if self.done[k] {
                    continue;
                }
                // A missing edge has an infinite key and never improves a distance.
                let key = self.movers.keys(j)[k];
                let d = self.dist[j] + key + self.potential[j] - self.potential[k];
                if d < self.dist[k] {
                    self.dist[k] = d;
                    self.pred[k] = Pred::Shift {
                        from: j,
                        robot: self.movers.robot(j, k),
                    };
                }
            }
        }
    }

    /// Where the paths of the last [`Solver::shortest_paths`] should end: the task with
    /// room where taking one more member is cheapest, and that real cost (the path's
    /// cost minus the member's marginal value), the change in `−welfare` of the
    /// augmentation.
    pub fn best_end(&self) -> (usize, f64) {
        // The void's next member is worth 0.
        let next = |j: usize| {
            self.task(j).map_or(0.0, |task| {
                self.inst
                    .marginal_value(task, self.assignment.size(task) + 1)
            })
        };
        let total = |j: usize| self.dist[j] + self.potential[j] - next(j);
        (0..self.m)
            .filter(|&j| {
                self.task(j)
                    .is_none_or(|task| self.assignment.size(task) < self.inst.capacity(task))
            })
            .map(|j| (j, total(j)))
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .expect("capacities or the void hold every robot (checked by Instance::new)")
    }

    /// Adds `robot` along a shortest augmenting path and updates the potentials.
    fn augment(&mut self, robot: usize) {
        for j in 0..self.m {
            self.dist[j] = self.cost(robot, j);
        }
        self.shortest_paths();
        let (end, _) = self.best_end();
        // Shift robots back along the path, then place the new robot.
        let mut at = end;
        while let Pred::Shift { from, robot: r } = self.pred[at] {
            self.place(r as usize, at);
            self.shifts += 1;
            at = from;
        }
        self.place(robot, at);
        for j in 0..self.m {
            self.potential[j] += self.dist[j];
        }
    }
}

/// Where a task node was reached from on the current shortest-path tree.
#[derive(Clone, Copy)]
enum Pred {
    /// Directly from the new robot.
    Source,
    /// From task `from`, by moving `robot` out of it.
    Shift { from: usize, robot: u32 },
}

/// A solver that has completed `partial` optimally, leaving `skip` (if any) out.
pub(super) fn solved(inst: &Instance, partial: Assignment, skip: Option<usize>) -> Solver<'_> {
    let mut s = Solver::new(inst, partial);
    let free: Vec<usize> = (0..inst.num_robots())
        .filter(|&i| s.assignment.task_of(RobotId(i as u32)).is_none() && Some(i) != skip)
        .collect();
    for robot in free {
        s.augment(robot);
    }
    s
}

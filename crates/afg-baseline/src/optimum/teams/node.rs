//! The branch and bound's nodes: what a node decides, its relaxation (a concave game
//! for the transport solver), and how it branches. A skill game's node has two more
//! bounds, the lowest kept: the skills priced (module `lagrange`) and, in long
//! searches, the robots priced (module `robot_prices`).

use std::cmp::Ordering;

use afg_game::{Assignment, Instance, Point, RobotId, TaskId};

use super::super::transport::{
    self, Column, Interrupted, NEVER, Slots, Solution, Stop, assignment_of,
};

mod branching;
mod count;
mod cover;
mod fixing;
mod lagrange;
mod robot_prices;
mod rounding;
mod staffing;
pub(super) use branching::Branch;
pub(super) use lagrange::MAX_PAIRS;
pub(super) use staffing::AFTER_NODES;

/// What a node decides of one task.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Decision {
    /// Not decided: its value replaced by its envelope.
    Open,
    /// Staffed: it earns (at least k members, and the skills it requires).
    Staffed,
    /// Unstaffed: it earns nothing (in a game without skills, at most k − 1 members).
    Unstaffed,
}

/// The most decisions a child may change from its parent and still start from the
/// parent's prices.
const WARM_CHANGES: usize = 8;

/// A robot fixed at a task (`true`) or kept out of it (`false`).
type Pair = (RobotId, TaskId, bool);

/// A node: its decisions, its relaxation's bound, and what the branching reads of its
/// relaxed optimum: the coalition sizes and, in a game with skills, where every robot
/// is (an open node of a large game holds M numbers, not N).
#[derive(Clone)]
pub(super) struct Node {
    decisions: Vec<Decision>,
    pairs: Vec<Pair>,
    pub(super) bound: f64,
    prices: Vec<f64>,
    skill_prices: Vec<f64>,
    /// How much of each task's team the Lagrangian relaxation at those prices holds
    /// (empty: none solved), which the branching reads first.
    skill_earns: Vec<f64>,
    /// Its robot-priced bound's prices, where its children's start (`None`: none).
    robot_prices: Option<robot_prices::RobotPrices>,
    pub(super) sizes: Vec<usize>,
    assignment: Option<Assignment>,
}

impl PartialEq for Node {
    fn eq(&self, other: &Self) -> bool {
        self.bound.total_cmp(&other.bound) == Ordering::Equal
    }
}
impl Eq for Node {}
impl PartialOrd for Node {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for Node {
    fn cmp(&self, other: &Self) -> Ordering {
        self.bound.total_cmp(&other.bound)
    }
}

impl Node {
    /// What a rounding reads of the node: its relaxed coalitions, prices (the `m`
    /// tasks') and bound.
    pub(super) fn relaxation(&self, m: usize) -> super::TeamRelaxation {
        super::TeamRelaxation {
            sizes: self.sizes.clone(),
            prices: self.prices[..m].to_vec(),
            bound: self.bound,
        }
    }
}

/// The search's data: the instance, each task's threshold as the search reads it, the
/// bonus that forces a staffed task's first members (and, four times over, a fixed
/// robot's place), the skill prices of the Lagrangian bound (empty: none), and the best
/// found so far.
pub(super) struct Search<'a> {
    instance: &'a Instance,
    thresholds: Vec<usize>,
    /// The pairs that no assignment better than the best found uses: a row-major N × M
    /// lookup (empty: none yet).
    forbidden: Vec<bool>,
    /// Every robot's travel cost at every column, those pairs' raised by
    /// [`Search::keep_out_cost`]: computed once for every relaxation ([`transport::Costs::travel`];
    /// empty, computed by each, beyond [`MAX_PAIRS`]).
    travel: Vec<f64>,
    /// The tasks that earn in no assignment better than the best found (empty: none
    /// known yet), decided unstaffed in every node.
    cannot_earn: Vec<bool>,
    root_dual: Option<fixing::RootDual>,
    bonus: f64,
    skill_prices: Vec<f64>,
    skill_step: f64,
    /// Subgradient steps at every node but the root (module `lagrange`).
    node_rounds: usize,
    /// Which nodes get the robot-priced bound (module `robot_prices`).
    robot_gate: robot_prices::Gate,
    /// The price of a task's earning in the relaxations (module `count`; 0: none).
    count_price: f64,
    /// The most tasks that can earn at once ([`count::count_cap`]).
    count_cap: usize,
    best: Assignment,
    best_welfare: f64,
    nodes: u64,
}

impl<'a> Search<'a> {
    /// The search of the exact solve: every threshold read as the task's smallest
    /// earning team ([`Instance::smallest_teams`]; more than N: it never earns).
    pub(super) fn exact(instance: &'a Instance) -> Self {
        let thresholds = (instance.smallest_teams().into_iter())
            .map(|k| k.unwrap_or(instance.num_robots() + 1))
            .collect();
        Search::with_thresholds(instance, thresholds)
    }

    /// The search of a rounding or a staffing (the dives): the thresholds as they are.
    pub(super) fn new(instance: &'a Instance) -> Self {
        let thresholds = instance.task_ids().map(|j| instance.min_team(j)).collect();
        Search::with_thresholds(instance, thresholds)
    }

    /// The search that reads `thresholds` as the tasks' thresholds.
    fn with_thresholds(instance: &'a Instance, thresholds: Vec<usize>) -> Self {
        // Every robot lies in the box of their positions: no distance to a task
        // exceeds the one to the box's farthest corner (O(N + M), not N M).
        let mut lo = Point::new(f64::INFINITY, f64::INFINITY);
        let mut hi = Point::new(-lo.x, -lo.y);
        for p in instance.robots() {
            (lo.x, lo.y, hi.x, hi.y) = (lo.x.min(p.x), lo.y.min(p.y), hi.x.max(p.x), hi.y.max(p.y));
        }
        let max_cost = (instance.tasks().iter())
            .filter(|_| lo.x <= hi.x) // a game with robots
            .map(|t| {
                let dx = (t.position.x - lo.x).abs().max((hi.x - t.position.x).abs());
                let dy = (t.position.y - lo.y).abs().max((hi.y - t.position.y).abs());
                instance.beta() * dx.hypot(dy)
            })
            .fold(0.0, f64::max);
        let max_reward = instance
            .tasks()
            .iter()
            .map(|t| t.reward)
            .fold(0.0, f64::max);
        Search {
            instance,
            count_cap: count::count_cap(&thresholds, instance.num_robots()),
            thresholds,
            forbidden: Vec::new(),
            travel: if instance.num_robots() * instance.num_tasks() <= MAX_PAIRS {
                transport::travel_costs(instance)
            } else {
                Vec::new()
            },
            cannot_earn: Vec::new(),
            root_dual: None,
            // More than any other member or move is worth: a staffed task's first k
            // members come before anything else.
            bonus: 2.0 * (max_cost + max_reward) + 1.0,
            skill_prices: Vec::new(),
            skill_step: 0.0,
            node_rounds: 0,
            robot_gate: robot_prices::Gate::default(),
            count_price: 0.0,
            best: Assignment::unassigned(instance.num_robots(), instance.num_tasks()),
            best_welfare: f64::NEG_INFINITY,
            nodes: 0,
        }
    }

    /// The best assignment, its welfare, and the nodes solved.
    pub(super) fn into_best(self) -> (Assignment, f64, u64) {
        (self.best, self.best_welfare, self.nodes)
    }

    /// The best welfare found so far.
    pub(super) fn best_welfare(&self) -> f64 {
        self.best_welfare
    }

    /// Nodes whose relaxation was solved so far.
    pub(super) fn nodes(&self) -> u64 {
        self.nodes
    }

    /// The root's decisions: the tasks no team can staff are unstaffed.
    pub(super) fn root_decisions(&self) -> Vec<Decision> {
        let inst = self.instance;
        let mut decisions = vec![Decision::Open; inst.num_tasks()];
        for j in inst.unstaffable_tasks() {
            decisions[j.index()] = Decision::Unstaffed;
        }
        for j in inst.task_ids() {
            if self.threshold(j) > inst.num_robots().min(inst.capacity(j)) {
                decisions[j.index()] = Decision::Unstaffed;
            }
        }
        decisions
    }

    /// Task j's threshold as every relaxation and branching here reads it (see
    /// [`Search::exact`]).
    fn threshold(&self, j: TaskId) -> usize {
        self.thresholds[j.index()]
    }

    /// Whether a node of this bound cannot beat the best found (beyond rounding).
    pub(super) fn closes(&self, bound: f64) -> bool {
        bound <= self.best_welfare + 1e-9 * self.best_welfare.abs().max(1.0)
    }

    /// The largest coalition an unstaffed task may hold: below its threshold where
    /// only the threshold can keep it from earning, its capacity where skills can.
    fn unstaffed_room(&self, j: TaskId) -> usize {
        let inst = self.instance;
        if inst.requires(j).iter().any(|&r| r > 0) {
            inst.capacity(j)
        } else {
            inst.capacity(j).min(self.threshold(j) - 1)
        }
    }

    /// The columns of a node's relaxation; `None` where no assignment meets its
    /// decisions (staffed thresholds above N, a staffed task that can no longer get its
    /// skills, or too little room in all). An open task that can no longer get its
    /// skills, or earns in no assignment better than the best found, is decided
    /// unstaffed.
    fn columns(&self, decisions: &mut [Decision], pairs: &[Pair]) -> Option<Vec<Column>> {
        let inst = self.instance;
        let barred = (inst.num_skills() > 0).then(|| self.barred(pairs));
        for j in inst.task_ids() {
            if decisions[j.index()] == Decision::Unstaffed {
                continue;
            }
            let hopeless = self.cannot_earn.get(j.index()).copied().unwrap_or(false)
                || barred
                    .as_ref()
                    .is_some_and(|b| !self.skills_reachable(j, b));
            if hopeless {
                if decisions[j.index()] == Decision::Staffed {
                    return None;
                }
                decisions[j.index()] = Decision::Unstaffed;
            }
        }
        let staffed: usize = inst
            .task_ids()
            .filter(|j| decisions[j.index()] == Decision::Staffed)
            .map(|j| self.threshold(j))
            .sum();
        if staffed > inst.num_robots() {
            return None;
        }
        let mut room = 0usize;
        let mut columns: Vec<Column> = inst
            .task_ids()
            .map(|j| {
                let (column, _) = self.task_column(j, decisions[j.index()], self.count_price);
                if let Column::Task { capacity, .. } = column {
                    room = room.saturating_add(capacity);
                }
                column
            })
            .collect();
        if inst.allows_void() {
            columns.push(Column::Void);
        } else if room < inst.num_robots() {
            return None;
        }
        Some(columns)
    }

    /// Task j's column under `decision`, its value less `penalty` once it earns (the
    /// Lagrangian price of its skills; 0 for the envelope), and the size over which an
    /// open task's envelope spreads its value (0 where it may not earn).
    fn task_column(&self, j: TaskId, decision: Decision, penalty: f64) -> (Column, usize) {
        let inst = self.instance;
        let (value, k) = (inst.value_function(j), self.threshold(j));
        let capacity = inst.capacity(j);
        let (value, capacity, flat) = match decision {
            Decision::Open => {
                let (slots, flat) =
                    Slots::penalised(value, k, penalty, capacity.min(inst.num_robots()));
                (slots, capacity, flat)
            }
            Decision::Staffed => (
                Slots::envelope(value, k, self.bonus).less(penalty),
                capacity,
                k,
            ),
            Decision::Unstaffed => (Slots::worthless(value), self.unstaffed_room(j), 0),
        };
        (Column::Task { value, capacity }, flat)
    }

    /// The root (every task open but those no team can staff), solved; or, where
    /// `stop` ends its solve first, a proven bound from the prices it had reached, with
    /// an assignment built from where the robots stood offered to the best found.
    pub(super) fn root(&mut self, stop: Stop) -> Result<Node, f64> {
        let mut decisions = self.root_decisions();
        let columns = (self.columns(&mut decisions, &[]))
            .expect("the root is feasible: the instance holds every robot");
        match transport::solve_columns(
            self.instance,
            &columns,
            None,
            transport::Costs::default(),
            stop,
        ) {
            Ok(solution) => Ok(self
                .node_of(decisions, Vec::new(), Vec::new(), &columns, solution)
                .expect("the root fixes no robot")),
            Err(Interrupted { task_of, bound }) => {
                self.offer(&self.completed(&task_of));
                Err(bound)
            }
        }
    }

    /// Solves a node's relaxations (warm from its parent's prices): the Lagrangian one
    /// where the root priced the skills (the pairs its dual rules out then kept out of
    /// the node), then the envelope's; offers their assignments to the best found, and
    /// returns the node with the lower bound, at most its parent's; `None` if
    /// infeasible or closed by the Lagrangian bound.
    pub(super) fn node(
        &mut self,
        mut decisions: Vec<Decision>,
        pairs: Vec<Pair>,
        parent: Option<&Node>,
    ) -> Option<Node> {
        let inst = self.instance;
        let columns = self.columns(&mut decisions, &pairs)?;
        // A parent's prices help where a few tasks changed; after many (a dive's
        // rounding), the subsample levels start closer.
        let changed = |p: &Node| {
            decisions
                .iter()
                .zip(&p.decisions)
                .filter(|(a, b)| a != b)
                .count()
        };
        let warm = parent.filter(|p| changed(p) <= WARM_CHANGES).map(|p| {
            let mut prices = p.prices.clone();
            for (j, (&now, &before)) in decisions.iter().zip(&p.decisions).enumerate() {
                match (now, before) {
                    (Decision::Staffed, Decision::Open) => prices[j] += self.bonus,
                    (Decision::Unstaffed, Decision::Open) => prices[j] = 0.0,
                    _ => {}
                }
            }
            prices
        });
        // The Lagrangian bound first: where it closes the node, the envelope's
        // relaxation (the one branched on) need not be solved.
        let dual = match parent {
            Some(p) => self.skill_bound(&decisions, &pairs, p)?,
            None => None,
        };
        let skill_bound = dual.as_ref().map_or(f64::INFINITY, |d| d.relaxed.bound);
        if self.closes(skill_bound) {
            return None;
        }
        let mut pairs = pairs;
        if let Some(dual) = &dual {
            self.keep_out_below(&decisions, &mut pairs, &dual.relaxed);
        }
        let robot_prices = match &dual {
            Some(dual) => self.price_robots(&decisions, &pairs, &dual.relaxed, parent)?,
            None => None,
        };
        let robot_bound = robot_prices.as_ref().map_or(f64::INFINITY, |r| r.bound);
        let (skill_prices, skill_earns) =
            dual.map_or((Vec::new(), Vec::new()), |d| (d.lambda, d.relaxed.earns));
        let adjust = self.adjust(&pairs);
        let Ok(solution) = transport::solve_columns(
            inst,
            &columns,
            warm.as_deref(),
            self.costs(&adjust, &[]),
            NEVER,
        ) else {
            unreachable!("never stopped")
        };
        let node = self.node_of(decisions, pairs, skill_prices, &columns, solution)?;
        // A child's assignments are its parent's too: its bound is at most the parent's.
        let inherited = parent.map_or(f64::INFINITY, |p| p.bound);
        Some(Node {
            bound: node.bound.min(skill_bound).min(robot_bound).min(inherited),
            skill_earns,
            robot_prices,
            ..node
        })
    }

    /// The node of `decisions` and `pairs` whose relaxation (its `columns`) was solved
    /// to `solution`, the skill prices of its Lagrangian bound beside it (empty: none);
    /// its assignment is offered to the best found. `None` where that assignment does
    /// not keep every robot where `pairs` fixed it.
    fn node_of(
        &mut self,
        decisions: Vec<Decision>,
        pairs: Vec<Pair>,
        skill_prices: Vec<f64>,
        columns: &[Column],
        solution: Solution,
    ) -> Option<Node> {
        let inst = self.instance;
        let Solution {
            task_of, prices, ..
        } = solution;
        self.nodes += 1;
        let assignment = assignment_of(inst, &task_of);
        if !self.keeps(&assignment, &pairs) {
            return None; // no assignment keeps every robot where the node fixed it
        }
        let mut bound = self.count_price * self.count_cap as f64
            - inst
                .robot_ids()
                .map(|i| assignment.task_of(i).map_or(0.0, |j| inst.cost(i, j)))
                .sum::<f64>();
        for j in inst.task_ids() {
            let Column::Task { value, .. } = columns[j.index()] else {
                unreachable!("tasks come first")
            };
            bound += value.value(assignment.size(j));
            if decisions[j.index()] == Decision::Staffed {
                bound -= self.bonus * self.threshold(j) as f64;
            }
        }
        self.offer(&assignment);
        Some(Node {
            decisions,
            pairs,
            bound,
            skill_prices,
            skill_earns: Vec::new(),
            robot_prices: None,
            prices,
            sizes: assignment.sizes().to_vec(),
            assignment: inst.has_skill_rules().then_some(assignment),
        })
    }

    /// Whether robot i may join task j at all (the root's dual does not rule it out).
    fn allowed(&self, i: RobotId, j: TaskId) -> bool {
        let m = self.instance.num_tasks();
        !self
            .forbidden
            .get(i.index() * m + j.index())
            .copied()
            .unwrap_or(false)
    }

    /// Whether `assignment` keeps every robot where `pairs` fixed it, and out of the
    /// pairs the root's dual rules out.
    fn keeps(&self, assignment: &Assignment, pairs: &[Pair]) -> bool {
        pairs
            .iter()
            .all(|&(i, j, fixed)| (assignment.task_of(i) == Some(j)) == fixed)
            && (self.instance.robot_ids())
                .all(|i| assignment.task_of(i).is_none_or(|j| self.allowed(i, j)))
    }

    /// Offers `assignment` to the best found (a better one rules out more pairs).
    pub(super) fn offer(&mut self, assignment: &Assignment) {
        let welfare = self.instance.welfare(assignment);
        if welfare > self.best_welfare {
            self.best_welfare = welfare;
            self.best = assignment.clone();
            self.forbid();
        }
    }
}

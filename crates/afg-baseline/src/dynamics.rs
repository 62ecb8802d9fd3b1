//! Best-response dynamics: GRAPE's decentralised algorithm (Jang et al. 2018) and its
//! centralised twin, under either preference (selfish = GRAPE DA, balanced = Def. 2).
//!
//! Both start with every robot unassigned. A *change* is one robot switching to its
//! most preferred task (strictly better than where it is, [`Instance::best_response`]).
//!
//! **Decentralised.** Each robot keeps a local view of the partition with an
//! evolution number (how many changes it has seen) and a random time stamp. In a
//! synchronous round every unsatisfied robot best-responds on its view (a change
//! bumps the evolution number and draws a new stamp), then every robot sends its view
//! to its neighbours on the communication graph and keeps the one with the highest
//! (evolution, stamp): GRAPE's distributed mutex. A robot that adopts another view
//! becomes unsatisfied and reconsiders. It ends when a round has no change and no
//! adoption: all views agree and nobody wants to move.
//!
//! Every surviving view descends from the empty partition through a chain of changes,
//! each a best response to the view before it. Replaying that chain's robot order
//! through the centralised twin reproduces the same partition (tested).
//!
//! **Memory and time.** A view is persistent ([`imbl::Vector`]): a change copies one
//! path of a shallow tree, not the partition, and a message shares the sender's view,
//! so the N views take O(N + changes · log N) memory instead of O(N²). Only what
//! changed is looked at: the unsatisfied robots act, and only robots whose view changed
//! since they last sent it can raise a neighbour's (views only ever rise in
//! (evolution, stamp)), so a round costs O(unsatisfied + their messages) rather than
//! O(N · degree). Every robot still sends every round in GRAPE, and `messages` counts
//! those; the partitions, rounds and messages equal the plain simulation's (tested
//! against it).

use std::rc::Rc;

use imbl::Vector;

use afg_game::{Assignment, Instance, Preference, RobotId, TaskId};
use afg_graph::{GraphKind, RobotGraph};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::{AllocError, AllocStats, Allocation, Allocator, timed};

/// Best-response dynamics run centrally: robots take turns, first in the order of
/// `schedule` (one turn per entry, so a robot may appear several times), then in
/// sweeps over robots 0..N until a sweep makes no change.
///
/// # Complexity
/// O(M) per turn; sizes are kept incrementally.
///
/// # Examples
/// ```
/// use afg_baseline::{Allocator, CentralisedDa};
/// use afg_game::{GeneratorConfig, Preference};
/// let inst = GeneratorConfig::paper(60, 5, 3).generate()?;
/// let da = CentralisedDa::new(Preference::Selfish).allocate(&inst)?;
/// assert!(inst.is_stable(&da.assignment, Preference::Selfish));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Debug)]
pub struct CentralisedDa {
    /// Which preference robots follow.
    pub preference: Preference,
    /// Turns taken before the index-order sweeps.
    pub schedule: Vec<RobotId>,
}

impl CentralisedDa {
    /// Index-order sweeps under `preference`.
    pub fn new(preference: Preference) -> Self {
        CentralisedDa {
            preference,
            schedule: Vec::new(),
        }
    }

    /// One turn: `robot` moves to its best response if that is strictly better.
    fn turn(&self, instance: &Instance, a: &mut Assignment, robot: RobotId) -> bool {
        match instance.best_response(a, robot, self.preference) {
            Some(j) => {
                a.set(robot, Some(j));
                true
            }
            None => false,
        }
    }

    /// Index-order sweeps from `assignment` (complete or partial) until a sweep makes
    /// no change: afterwards every robot is satisfied under the preference (Def. 3 for
    /// [`Preference::Balanced`]). Returns (changes, sweeps). This is the repair step
    /// that makes any allocation stable; the schedule is not used.
    ///
    /// # Examples
    /// ```
    /// use afg_baseline::{Allocator, CentralisedDa, Nearest};
    /// use afg_game::{GeneratorConfig, Preference};
    /// let inst = GeneratorConfig::paper(40, 5, 2).generate()?;
    /// let mut a = Nearest.allocate(&inst)?.assignment;
    /// let before = inst.welfare(&a);
    /// let (changes, _sweeps) = CentralisedDa::new(Preference::Balanced).improve(&inst, &mut a);
    /// assert!(inst.is_stable(&a, Preference::Balanced));
    /// assert!(changes == 0 || inst.welfare(&a) > before);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn improve(&self, instance: &Instance, assignment: &mut Assignment) -> (u64, u64) {
        let (mut changes, mut sweeps) = (0u64, 0u64);
        loop {
            sweeps += 1;
            let mut changed = false;
            for i in instance.robot_ids() {
                if self.turn(instance, assignment, i) {
                    changes += 1;
                    changed = true;
                }
            }
            if !changed {
                return (changes, sweeps);
            }
        }
    }
}

impl Allocator for CentralisedDa {
    fn name(&self) -> String {
        match self.preference {
            Preference::Selfish => "da".into(),
            Preference::Balanced => "da-balanced".into(),
        }
    }

    fn allocate(&self, instance: &Instance) -> Result<Allocation, AllocError> {
        let (result, wall_time) = timed(|| {
            let n = instance.num_robots();
            if let Some(i) = self.schedule.iter().find(|i| i.index() >= n) {
                return Err(AllocError::InvalidParameter(format!(
                    "schedule names robot {i}, N = {n}"
                )));
            }
            let mut a = Assignment::unassigned(n, instance.num_tasks());
            let mut changes = 0u64;
            for &i in &self.schedule {
                changes += u64::from(self.turn(instance, &mut a, i));
            }
            let (more, sweeps) = self.improve(instance, &mut a);
            Ok((a, changes + more, sweeps))
        });
        let (assignment, iterations, rounds) = result?;
        Ok(Allocation {
            assignment,
            stats: AllocStats {
                iterations,
                rounds,
                wall_time,
                ..AllocStats::default()
            },
        })
    }
}

/// GRAPE's decentralised algorithm, simulated round by round over the robot
/// communication graph (see the module docs). The graph defaults to kNN, k = 10;
/// if it is disconnected, each stray component is linked to its nearest robot
/// outside it (reported in [`DecentralisedRun::added_edges`]).
///
/// # Examples
/// ```
/// use afg_baseline::{Allocator, DecentralisedDa};
/// use afg_game::{GeneratorConfig, Preference};
/// let inst = GeneratorConfig::paper(20, 5, 3).generate()?;
/// let da = DecentralisedDa::new(Preference::Selfish, 7).allocate(&inst)?;
/// assert!(inst.is_stable(&da.assignment, Preference::Selfish));
/// assert!(da.stats.messages > 0);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Debug)]
pub struct DecentralisedDa {
    /// Which preference robots follow.
    pub preference: Preference,
    /// Communication graph.
    pub graph: GraphKind,
    /// Seed of the time stamps.
    pub seed: u64,
}

impl DecentralisedDa {
    /// The default kNN (k = 10) communication graph.
    pub fn new(preference: Preference, seed: u64) -> Self {
        DecentralisedDa {
            preference,
            graph: GraphKind::default(),
            seed,
        }
    }
}

/// A decentralised run: the allocation, the robots of the winning chain of changes
/// in order, and the edges added to connect the graph.
#[derive(Clone, Debug)]
pub struct DecentralisedRun {
    /// Final partition and statistics (`iterations` is the final evolution number).
    pub allocation: Allocation,
    /// Robot of each change on the surviving chain, oldest first.
    pub chain: Vec<RobotId>,
    /// Edges added by the connectivity fallback.
    pub added_edges: usize,
}

/// One change on a chain of views.
struct Change {
    robot: RobotId,
    prev: Option<Rc<Change>>,
}

impl Drop for Change {
    /// Unlinks the chain iteratively: a long chain dropped recursively would overflow the stack.
    fn drop(&mut self) {
        let mut prev = self.prev.take();
        while let Some(rc) = prev {
            match Rc::try_unwrap(rc) {
                Ok(mut c) => prev = c.prev.take(),
                Err(_) => break,
            }
        }
    }
}

/// A robot's local view of the partition.
struct View {
    tasks: Vector<Option<TaskId>>,
    sizes: Vec<usize>,
    evolution: u64,
    stamp: u64,
    last: Option<Rc<Change>>,
}

impl View {
    /// The view of `n` robots, none assigned, over `m` tasks.
    fn empty(n: usize, m: usize) -> View {
        View {
            tasks: std::iter::repeat_n(None, n).collect(),
            sizes: vec![0; m],
            evolution: 0,
            stamp: 0,
            last: None,
        }
    }

    /// The partition this view holds.
    fn assignment(&self) -> Assignment {
        let mut assignment = Assignment::unassigned(self.tasks.len(), self.sizes.len());
        for (i, &task) in self.tasks.iter().enumerate() {
            assignment.set(RobotId(i as u32), task);
        }
        assignment
    }

    /// The robots whose changes made this view, oldest first.
    fn chain(&self) -> Vec<RobotId> {
        let mut chain = Vec::with_capacity(self.evolution as usize);
        let mut link = self.last.as_deref();
        while let Some(c) = link {
            chain.push(c.robot);
            link = c.prev.as_deref();
        }
        chain.reverse();
        chain
    }

    fn key(&self) -> (u64, u64) {
        (self.evolution, self.stamp)
    }

    /// The view after `robot` moves to `task`, with a new stamp.
    fn changed(&self, robot: RobotId, task: TaskId, stamp: u64) -> View {
        let (mut tasks, mut sizes) = (self.tasks.clone(), self.sizes.clone());
        if let Some(old) = tasks.set(robot.index(), Some(task)) {
            sizes[old.index()] -= 1;
        }
        sizes[task.index()] += 1;
        View {
            tasks,
            sizes,
            evolution: self.evolution + 1,
            stamp,
            last: Some(Rc::new(Change {
                robot,
                prev: self.last.clone(),
            })),
        }
    }

    fn best_response(
        &self,
        instance: &Instance,
        robot: RobotId,
        pref: Preference,
    ) -> Option<TaskId> {
        let current = self.tasks[robot.index()];
        instance.best_response_given(robot, current, &self.sizes, pref)
    }
}

impl DecentralisedDa {
    /// Runs the algorithm and returns the chain of changes as well.
    ///
    /// # Errors
    /// [`AllocError::Graph`] if the communication graph cannot be built, and
    /// [`AllocError::NotConverged`] if the rounds exceed a safety bound (never seen).
    pub fn run(&self, instance: &Instance) -> Result<DecentralisedRun, AllocError> {
        let n = instance.num_robots();
        let limit = 1000 + 4 * (n as u64) * (n as u64 + 1);
        let (result, wall_time) = timed(|| {
            let mut graph = RobotGraph::build(instance.robots(), self.graph)?;
            let added_edges = graph.connect_components(instance.robots());
            let per_round = 2 * graph.num_edges() as u64;
            let mut rng = ChaCha8Rng::seed_from_u64(self.seed);
            let empty = Rc::new(View::empty(n, instance.num_tasks()));
            let mut views: Vec<Rc<View>> = vec![empty; n];
            // Robots to act in the next round, in index order (the stamps are drawn in it).
            let mut unsatisfied: Vec<u32> = (0..n as u32).collect();
            // Robots whose view changed since they last sent it.
            let mut senders: Vec<u32> = Vec::new();
            let mut is_sender = vec![false; n];
            // The best view offered to each robot this round, by its sender.
            let mut offer: Vec<Option<u32>> = vec![None; n];
            let mut offered: Vec<u32> = Vec::new();
            let (mut rounds, mut messages) = (0u64, 0u64);
            loop {
                rounds += 1;
                if rounds > limit {
                    return Err(AllocError::NotConverged { rounds: limit });
                }
                let mut active = false;
                for &a in &unsatisfied {
                    let (i, view) = (RobotId(a), &views[a as usize]);
                    if let Some(j) = view.best_response(instance, i, self.preference) {
                        views[a as usize] = Rc::new(view.changed(i, j, rng.random()));
                        active = true;
                        if !std::mem::replace(&mut is_sender[a as usize], true) {
                            senders.push(a);
                        }
                    }
                }
                unsatisfied.clear();
                // Everyone broadcasts its view; each keeps the highest (evolution, stamp).
                // A view that did not change since it was last sent cannot beat the
                // receiver's, so only the changed ones are compared.
                messages += per_round;
                let outbox = Outbox {
                    senders: &mut senders,
                    is_sender: &mut is_sender,
                };
                best_offers(&graph, &views, outbox, &mut offer, &mut offered);
                let adopted: Vec<(u32, Rc<View>)> = offered
                    .drain(..)
                    .map(|a| {
                        let b = offer[a as usize]
                            .take()
                            .expect("an offered robot has an offer");
                        (a, Rc::clone(&views[b as usize]))
                    })
                    .collect();
                for (a, view) in adopted {
                    views[a as usize] = view;
                    unsatisfied.push(a);
                    is_sender[a as usize] = true;
                    senders.push(a);
                    active = true;
                }
                unsatisfied.sort_unstable();
                if !active {
                    break;
                }
            }
            Ok((Rc::clone(&views[0]), rounds, messages, added_edges))
        });
        let (view, rounds, messages, added_edges) = result?;
        let (assignment, chain) = (view.assignment(), view.chain());
        let stats = AllocStats {
            iterations: view.evolution,
            rounds,
            messages,
            wall_time,
            seed: Some(self.seed),
        };
        Ok(DecentralisedRun {
            allocation: Allocation { assignment, stats },
            chain,
            added_edges,
        })
    }
}

/// The robots whose view changed since they last sent it, and the flag of each robot.
struct Outbox<'a> {
    senders: &'a mut Vec<u32>,
    is_sender: &'a mut [bool],
}

/// Sends every changed view to the sender's neighbours (emptying `outbox`): each
/// neighbour's best offer (highest evolution, then stamp, above its own view) goes
/// into `offer`, and the robots with an offer into `offered`.
fn best_offers(
    graph: &RobotGraph,
    views: &[Rc<View>],
    outbox: Outbox<'_>,
    offer: &mut [Option<u32>],
    offered: &mut Vec<u32>,
) {
    for &b in outbox.senders.iter() {
        outbox.is_sender[b as usize] = false;
        let key = views[b as usize].key();
        for &a in graph.neighbours(RobotId(b)) {
            let best =
                offer[a as usize].map_or(views[a as usize].key(), |c| views[c as usize].key());
            if key > best {
                if offer[a as usize].is_none() {
                    offered.push(a);
                }
                offer[a as usize] = Some(b);
            }
        }
    }
    outbox.senders.clear();
}

impl Allocator for DecentralisedDa {
    fn name(&self) -> String {
        match self.preference {
            Preference::Selfish => "da-decentralised".into(),
            Preference::Balanced => "da-balanced-decentralised".into(),
        }
    }

    fn allocate(&self, instance: &Instance) -> Result<Allocation, AllocError> {
        self.run(instance).map(|r| r.allocation)
    }
}

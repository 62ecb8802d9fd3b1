//! Best-response dynamics: GRAPE's decentralised algorithm (Jang et al. 2018) and its
//! centralised twin, under either preference (selfish = GRAPE DA, balanced = Def. 2).
//!
//! Both start with every robot unassigned. A *change* is one robot switching to its
//! most preferred task (strictly better than where it is, [`Instance::best_response`]).
//! Where the instance allows the void task (GRAPE's game), an unassigned robot is in
//! the void, worth 0: it joins a task only for a positive score, and leaves for the
//! void when its place scores below 0 ([`Instance::best_move`]). Selfish, that is
//! GRAPE's clipping of utilities at 0; balanced, it leaves when its marginal welfare is
//! negative.
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

use afg_game::realloc::PreviousAssignment;
use afg_game::{Assignment, Instance, Preference, RobotId};
use afg_graph::GraphKind;

use crate::swarm::{Grape, Network, drive};
use crate::{AllocError, AllocStats, Allocation, Allocator, Plays, check_game, timed};

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

    /// One turn: `robot` makes its best move if that is strictly better
    /// ([`Instance::best_move`]: to a task, or to the void where the instance allows it).
    fn turn(&self, instance: &Instance, a: &mut Assignment, robot: RobotId) -> bool {
        match instance.best_move(a, robot, self.preference) {
            Some(place) => {
                a.set(robot, place);
                true
            }
            None => false,
        }
    }

    /// A warm start after robots or tasks changed: `previous` carried over to
    /// `instance` (survivors keep their task), then [`CentralisedDa::improve`] places
    /// the others by best response and sweeps to a stable assignment. Returns the
    /// carried-over start and the result.
    ///
    /// # Errors
    /// [`AllocError::Game`] if `previous` does not fit `instance`
    /// ([`PreviousAssignment::carry_over`]), [`AllocError::TeamsNotSupported`] for a
    /// game with skills.
    ///
    /// # Examples
    /// ```
    /// use afg_baseline::CentralisedDa;
    /// use afg_game::realloc::PreviousAssignment;
    /// use afg_game::{GeneratorConfig, Preference};
    /// // Three robots on tasks 1, 0, 1; robot 1 left and two robots joined.
    /// let old = r#"{"format":"afg-assignment","version":1,"tasks":[1,0,1],"left_robots":[1]}"#;
    /// let now = GeneratorConfig::paper(4, 2, 7).generate()?;
    /// let previous = PreviousAssignment::from_json(old)?;
    /// let (start, result) = CentralisedDa::new(Preference::Balanced).warm_start(&now, &previous)?;
    /// assert_eq!(start.tasks()[2..], [None, None]);
    /// assert!(now.is_stable(&result, Preference::Balanced));
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn warm_start(
        &self,
        instance: &Instance,
        previous: &PreviousAssignment,
    ) -> Result<(Assignment, Assignment), AllocError> {
        check_game(instance, self, Plays::Counts)?;
        let start = previous.carry_over(instance)?;
        let mut assignment = start.clone();
        self.improve(instance, &mut assignment);
        Ok((start, assignment))
    }

    /// Index-order sweeps from `assignment` (complete or partial) until a sweep makes
    /// no change: afterwards every robot is satisfied under the preference (Def. 3 for
    /// [`Preference::Balanced`]). In a team game, where a stable partition may not
    /// exist, it gives up after 1000 + 4 N (N + 1) changes. Returns (changes, sweeps). This is the repair step
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
        let limit = change_limit(instance.num_robots());
        while changes <= limit {
            sweeps += 1;
            let mut changed = false;
            for i in instance.robot_ids() {
                if self.turn(instance, assignment, i) {
                    changes += 1;
                    changed = true;
                }
            }
            if !changed {
                break;
            }
        }
        (changes, sweeps)
    }
}

/// The changes after which the dynamics give up: far above the N(N + 1)/2 that GRAPE
/// needs in the concave game, reached only in a team game without a stable partition.
fn change_limit(n: usize) -> u64 {
    let n = n as u64;
    1000 + 4 * n * (n + 1)
}

impl Allocator for CentralisedDa {
    fn name(&self) -> String {
        match self.preference {
            Preference::Selfish => "da".into(),
            Preference::Balanced => "da-balanced".into(),
        }
    }

    fn allocate(&self, instance: &Instance) -> Result<Allocation, AllocError> {
        check_game(instance, self, Plays::Counts)?;
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
            if more > change_limit(n) {
                // A team game in which the dynamics cycle: no stable partition reached.
                return Err(AllocError::NotConverged { rounds: sweeps });
            }
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
/// communication graph on a perfect network (see the module docs; lossy, late and
/// failing networks are [`Swarm`](crate::Swarm)'s). The graph defaults to kNN,
/// k = 10; if it is disconnected, each stray component is linked to its nearest robot
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

impl DecentralisedDa {
    /// Runs the algorithm and returns the chain of changes as well.
    ///
    /// # Errors
    /// [`AllocError::Graph`] if the communication graph cannot be built, and
    /// [`AllocError::NotConverged`] if the rounds exceed a safety bound (never seen).
    pub fn run(&self, instance: &Instance) -> Result<DecentralisedRun, AllocError> {
        check_game(instance, self, Plays::Counts)?;
        let limit = change_limit(instance.num_robots());
        let network = Network {
            graph: self.graph,
            ..Network::default()
        };
        let (result, wall_time) = timed(|| {
            let mut sim = Grape::new(instance, self.preference, &network, self.seed)?;
            let (converged, trace) = drive(&mut sim, limit, false, |_| {})?;
            Ok::<_, AllocError>(sim.finish(converged, trace))
        });
        let (outcome, view) = result?;
        if !outcome.converged {
            return Err(AllocError::NotConverged { rounds: limit });
        }
        let stats = AllocStats {
            iterations: view.evolution(),
            rounds: outcome.rounds,
            messages: outcome.traffic.messages,
            wall_time,
            seed: Some(self.seed),
            bound: None,
        };
        Ok(DecentralisedRun {
            allocation: Allocation {
                assignment: view.assignment(),
                stats,
            },
            chain: view.chain(),
            added_edges: outcome.added_edges,
        })
    }
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

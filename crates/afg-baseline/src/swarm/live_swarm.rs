//! A decentralised method inside a mission: robots that move, fail and come back,
//! tasks that appear and are done, all while the method runs round by round over the
//! radio.

use std::borrow::Cow;

use afg_game::{Instance, Point};

use super::auction::Auction;
use super::grape::Grape;
use super::network::Network;
use super::radio::Radio;
use super::task_news::TaskNews;
use super::{Simulation, SwarmMethod};
use crate::AllocError;

/// Rounds of silence before a neighbour removes a failed robot (as [`Failure::new`](super::Failure::new)).
pub const DETECT_AFTER: u64 = 3;

/// GRAPE or the auction run round by round inside a mission. The game holds every
/// robot at its current position and every task of the mission; a robot considers
/// only the tasks it knows have appeared and are not done, and heads for the task its
/// own view (GRAPE) or the place it believes it holds (the auction) gives it, settled
/// or not. The auction's prices only rise, so every piece of news (a task appearing,
/// done, or seen) restarts it among the robots that hear it, in a new epoch that
/// spreads with their bids; a robot that comes back bids in the current epoch. Links follow the robots ([`LiveSwarm::round`] relinks them by
/// the network's graph rule, with no edges added to connect the swarm). A robot that
/// fails is noticed by its neighbours [`DETECT_AFTER`] rounds later; one that comes
/// back keeps the view it had.
///
/// TaskNews of tasks: with no sensing radius every robot hears of a task the moment it
/// appears or is done (a base station announces it); with one, a robot sees the tasks
/// within that radius, and tells its neighbours what they lack in each round's
/// broadcast (lost as any message; 5 bytes a task).
///
/// # Examples
/// ```
/// use afg_baseline::{LiveSwarm, Network, SwarmMethod};
/// use afg_game::{Instance, Point, Preference, Task};
/// let task = |x| Task { position: Point::new(x, 0.0), reward: 5.0, eps: 2.0, capacity: None };
/// let robots = vec![Point::new(0.0, 0.0), Point::new(1.0, 0.0), Point::new(9.0, 0.0)];
/// let game = Instance::with_void(robots.clone(), vec![task(0.0), task(9.0)], 0.1)?;
/// let grape = SwarmMethod::Grape { preference: Preference::Selfish };
/// let mut swarm = LiveSwarm::new(game, grape, &Network::default(), None, 1)?;
/// swarm.task_appears(0);
/// while !swarm.settled() {
///     swarm.round(&robots)?;
/// }
/// assert!((0..3).all(|i| swarm.task_of(i) == Some(0)));
/// swarm.task_appears(1);
/// while !swarm.settled() {
///     swarm.round(&robots)?;
/// }
/// assert_eq!(swarm.task_of(2), Some(1));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub struct LiveSwarm {
    engine: Engine,
    /// Whether a round since the last change did nothing.
    quiet: bool,
}

/// The method running.
enum Engine {
    Grape(Grape<'static>),
    Auction(Auction<'static>),
}

/// Calls the same method on whichever engine runs.
macro_rules! on_engine {
    ($engine:expr, $sim:ident => $call:expr) => {
        match $engine {
            Engine::Grape($sim) => $call,
            Engine::Auction($sim) => $call,
        }
    };
}

impl LiveSwarm {
    /// A swarm on `game` (every robot at its start, every task of the mission, none
    /// yet known) running `method` over `network`; robots see tasks within `sensing`
    /// (`None`: all hear of every task at once).
    ///
    /// # Errors
    /// [`AllocError::TeamsNotSupported`] for a team game;
    /// [`AllocError::InvalidParameter`] for a network with its own failures (a mission
    /// has its own), a sensing radius that is not positive, an auction increment that
    /// is not, or a network knob out of range; [`AllocError::Graph`] if the graph
    /// cannot be built.
    pub fn new(
        game: Instance,
        method: SwarmMethod,
        network: &Network,
        sensing: Option<f64>,
        seed: u64,
    ) -> Result<Self, AllocError> {
        super::refuse_teams(method, &game)?;
        let bad = |what: &str| Err(AllocError::InvalidParameter(what.into()));
        if network.failure.is_some() {
            return bad(
                "in a mission robots fail at the mission's failure times, not the network's",
            );
        }
        if sensing.is_some_and(|r| !(r.is_finite() && r > 0.0)) {
            return bad("the sensing radius must be finite and positive");
        }
        let places = game.tasks().iter().map(|t| t.position).collect();
        let news = Some(TaskNews::new(game.num_robots(), places, sensing));
        let engine = match method {
            SwarmMethod::Grape { preference } => {
                let radio = Radio::moving(game.robots(), network, seed)?;
                Engine::Grape(Grape::with_radio(
                    Cow::Owned(game),
                    preference,
                    radio,
                    seed,
                    news,
                ))
            }
            SwarmMethod::Auction { epsilon } => {
                let radio = Radio::moving(game.robots(), network, seed)?;
                let auction = Auction::with_radio(Cow::Owned(game), epsilon, radio, seed, news)?;
                Engine::Auction(auction)
            }
        };
        Ok(LiveSwarm {
            engine,
            quiet: false,
        })
    }

    /// `task` appears: the robots that see it (all, without a sensing radius) know it.
    pub fn task_appears(&mut self, task: usize) {
        on_engine!(&mut self.engine, sim => sim.task_event(task, false));
        self.quiet = false;
    }

    /// `task` is done: the robots that see it know it, and drop it from their views.
    pub fn task_done(&mut self, task: usize) {
        on_engine!(&mut self.engine, sim => sim.task_event(task, true));
        self.quiet = false;
    }

    /// `robot` fails now (it is noticed [`DETECT_AFTER`] rounds later).
    ///
    /// # Errors
    /// [`AllocError::Graph`] if the survivors' graph cannot be built.
    pub fn fail(&mut self, robot: usize) -> Result<(), AllocError> {
        self.quiet = false;
        on_engine!(&mut self.engine, sim => sim.fail(&[robot as u32], DETECT_AFTER))
    }

    /// `robot` is back.
    ///
    /// # Errors
    /// [`AllocError::Graph`] if the graph cannot be built.
    pub fn revive(&mut self, robot: usize) -> Result<(), AllocError> {
        self.quiet = false;
        on_engine!(&mut self.engine, sim => sim.revive(robot as u32))
    }

    /// One round with the robots at `positions`: relink, sense, then the method's round.
    ///
    /// # Errors
    /// [`AllocError::Game`] for a position out of range, [`AllocError::Graph`] if
    /// the graph cannot be built.
    pub fn round(&mut self, positions: &[Point]) -> Result<(), AllocError> {
        let quiet = on_engine!(&mut self.engine, sim => {
            sim.move_to(positions.to_vec())?;
            let active = sim.round()?;
            !active && sim.quiet()
        });
        self.quiet = quiet;
        Ok(())
    }

    /// The task `robot`'s own view gives it.
    pub fn task_of(&self, robot: usize) -> Option<usize> {
        on_engine!(&self.engine, sim => sim.own_task(robot as u32)).map(|t| t.index())
    }

    /// Whether every living robot holds the same partition (GRAPE: the same view; the
    /// auction: tables giving the same partition).
    pub fn agreed(&self) -> bool {
        on_engine!(&self.engine, sim => sim.agreed())
    }

    /// Whether the last round changed nothing, nothing is in flight and all agree:
    /// the swarm has settled until the next event.
    pub fn settled(&self) -> bool {
        self.quiet && self.agreed()
    }

    /// Rounds run.
    pub fn rounds(&self) -> u64 {
        on_engine!(&self.engine, sim => sim.rounds())
    }

    /// Messages sent (every awake robot to each neighbour every round).
    pub fn messages(&self) -> u64 {
        on_engine!(&self.engine, sim => sim.traffic()).messages
    }

    /// Bytes on the air: whole partitions (GRAPE) or tables (the auction), as the
    /// methods send them, and the news of tasks.
    pub fn bytes(&self) -> u64 {
        on_engine!(&self.engine, sim => sim.traffic()).bytes
    }
}

//! The network model: who can hear whom, which messages are lost or late, when robots
//! wake, and which robots stop.

use afg_game::Point;
use afg_graph::GraphKind;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use super::links::{Channel, Links, gilbert_elliott};
use crate::AllocError;

/// The network a decentralised method talks over. [`Network::default`] is the
/// perfect one of GRAPE's analysis: kNN links (k = 10), every message delivered in
/// the round it is sent, every robot awake every round, none failing.
///
/// # Examples
/// ```
/// use afg_baseline::{Failure, Network};
/// use afg_graph::GraphKind;
/// let lossy = Network {
///     graph: GraphKind::Radius { radius: 1.5 },
///     loss: 0.3,
///     burst: Some(4.0),
///     failure: Some(Failure::new(0.1, 20)),
///     ..Network::default()
/// };
/// assert!(lossy.check().is_ok());
/// assert!(Network { loss: 1.0, ..Network::default() }.check().is_err());
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Network {
    /// Who can hear whom (a disk radius, or the k nearest). If the graph is
    /// disconnected, each stray component is linked to its nearest robot outside it.
    pub graph: GraphKind,
    /// The long-run share of messages lost, in [0, 1).
    pub loss: f64,
    /// Mean length in rounds of a run of losses on one link (Gilbert–Elliott: a link
    /// is good or bad, bad links lose every message); `None` for independent losses.
    pub burst: Option<f64>,
    /// A delivered message arrives a uniform 0..=`max_delay` rounds after it is sent.
    pub max_delay: u32,
    /// The chance that a robot wakes in a round (1 = synchronous rounds). An asleep
    /// robot neither moves nor sends; it still receives.
    pub activation: f64,
    /// Robots that stop mid-run.
    pub failure: Option<Failure>,
    /// Links that cross the vertical line through the robots' median x are down until
    /// this round: the swarm works in two halves, then they merge.
    pub partition_until: Option<u64>,
}

/// Robots that crash: `fraction` of the robots alive stop at the start of round
/// `at_round` (chosen at random) and never send again. Their neighbours notice after
/// `detect_after` silent rounds (a robot with no living neighbour is noticed by its
/// nearest living robot) and remove it from the partition; the survivors relink to
/// their own nearest (the same graph rule over the survivors).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Failure {
    /// Share of the robots that crash, in [0, 1).
    pub fraction: f64,
    /// The round they crash at (from 1).
    pub at_round: u64,
    /// Silent rounds before a neighbour removes a crashed robot (at least 1).
    pub detect_after: u64,
}

impl Failure {
    /// `fraction` of the robots crash at `at_round`, noticed after 3 silent rounds.
    pub fn new(fraction: f64, at_round: u64) -> Self {
        Failure {
            fraction,
            at_round,
            detect_after: 3,
        }
    }
}

impl Default for Network {
    fn default() -> Self {
        Network {
            graph: GraphKind::default(),
            loss: 0.0,
            burst: None,
            max_delay: 0,
            activation: 1.0,
            failure: None,
            partition_until: None,
        }
    }
}

impl Network {
    /// Checks every knob's range, and that a burst length can give the loss.
    ///
    /// # Errors
    /// [`AllocError::InvalidParameter`] saying which value is out of range.
    pub fn check(&self) -> Result<(), AllocError> {
        let bad = |what: String| Err(AllocError::InvalidParameter(what));
        if !(0.0..1.0).contains(&self.loss) {
            return bad(format!("loss {} must be in [0, 1)", self.loss));
        }
        if !(self.activation > 0.0 && self.activation <= 1.0) {
            return bad(format!("activation {} must be in (0, 1]", self.activation));
        }
        if let Some(burst) = self.burst {
            if !(burst.is_finite() && burst >= 1.0) {
                return bad(format!("burst length {burst} must be at least 1 round"));
            }
            if gilbert_elliott(self.loss, burst).0 > 1.0 {
                return bad(format!(
                    "bursts of mean length {burst} cannot lose {} of the messages: at most {:.3}",
                    self.loss,
                    burst / (burst + 1.0)
                ));
            }
        }
        if let Some(f) = self.failure {
            if !(0.0..1.0).contains(&f.fraction) {
                return bad(format!("failing share {} must be in [0, 1)", f.fraction));
            }
            if f.at_round == 0 || f.detect_after == 0 {
                return bad("failures start at round 1 or later and take a round to notice".into());
            }
        }
        Ok(())
    }

    /// Whether this is GRAPE's perfect network (any graph).
    pub fn is_perfect(&self) -> bool {
        self.loss == 0.0
            && self.max_delay == 0
            && self.activation == 1.0
            && self.failure.is_none()
            && self.partition_until.is_none()
    }
}

/// The radio layer both decentralised methods run on: who is alive and awake this
/// round, the links in force, messages in flight, crashes and who notices them.
pub(super) struct Radio<M> {
    network: Network,
    links: Links,
    channel: Channel,
    /// The network's draws (GRAPE's stamps are another generator).
    rng: ChaCha8Rng,
    split_x: Option<f64>,
    alive: Vec<bool>,
    awake: Vec<bool>,
    /// Whether stray components are linked to the rest (a swarm standing still is
    /// made connected; a moving one hears only who is in range).
    connect: bool,
    /// Messages by arrival round modulo the longest delay + 1: (receiver, message).
    in_flight: Vec<Vec<(u32, M)>>,
    in_flight_count: usize,
    /// (round, noticer, crashed): who notices whom, and when.
    to_notice: Vec<(u64, u32, u32)>,
    /// The current round (from 1).
    pub round: u64,
    /// Edges added to connect the graph (at the start and after the crash).
    pub added_edges: usize,
}

/// What happens at the start of a round.
pub(super) struct RoundStart {
    /// Messages the awake robots' broadcasts make this round.
    pub broadcasts: u64,
    /// Robots crashed this round (the survivors have relinked).
    pub crashed: Vec<u32>,
    /// (noticer, crashed) pairs: who noticed whom this round.
    pub noticed: Vec<(u32, u32)>,
}

impl<M> Radio<M> {
    /// Every robot alive, linked by the network's graph made connected; draws from
    /// stream 1 of `seed`.
    pub fn new(points: &[Point], network: &Network, seed: u64) -> Result<Self, AllocError> {
        Self::build(points, network, seed, true)
    }

    /// [`Radio::new`] for robots that move: the links are the graph's alone (a robot
    /// out of everyone's range hears nobody), rebuilt by [`Radio::relink`].
    pub fn moving(points: &[Point], network: &Network, seed: u64) -> Result<Self, AllocError> {
        Self::build(points, network, seed, false)
    }

    fn build(
        points: &[Point],
        network: &Network,
        seed: u64,
        connect: bool,
    ) -> Result<Self, AllocError> {
        network.check()?;
        let n = points.len();
        let split_x = network.partition_until.map(|_| median_x(points));
        let everyone: Vec<u32> = (0..n as u32).collect();
        let (links, added_edges) =
            Links::build(points, &everyone, network.graph, split_x, connect)?;
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        rng.set_stream(1);
        Ok(Radio {
            network: network.clone(),
            links,
            channel: Channel::new(network),
            rng,
            split_x,
            alive: vec![true; n],
            awake: vec![true; n],
            connect,
            in_flight: (0..=network.max_delay).map(|_| Vec::new()).collect(),
            in_flight_count: 0,
            to_notice: Vec::new(),
            round: 0,
            added_edges,
        })
    }

    /// Starts the next round: the crash and the noticing due now, then who wakes.
    ///
    /// # Errors
    /// [`AllocError::Graph`] if the survivors' graph cannot be built.
    pub fn next_round(&mut self, points: &[Point]) -> Result<RoundStart, AllocError> {
        self.round += 1;
        let mut crashed = Vec::new();
        if let Some(failure) = self.network.failure
            && failure.at_round == self.round
        {
            crashed = self.crash(points, failure.fraction, failure.detect_after)?;
        }
        let round = self.round;
        let (due, later): (Vec<_>, Vec<_>) = std::mem::take(&mut self.to_notice)
            .into_iter()
            .partition(|&(at, _, _)| at <= round);
        self.to_notice = later;
        let noticed = due.into_iter().map(|(_, a, c)| (a, c)).collect();
        Ok(RoundStart {
            broadcasts: self.wake(),
            crashed,
            noticed,
        })
    }

    /// Draws who is awake; returns the messages their broadcasts make.
    fn wake(&mut self) -> u64 {
        if self.network.activation == 1.0 {
            return self.links.broadcast;
        }
        let mut messages = 0;
        for i in 0..self.alive.len() {
            let up = self.alive[i] && self.rng.random::<f64>() < self.network.activation;
            self.awake[i] = up;
            if up {
                messages += self.links.degree(i as u32);
            }
        }
        messages
    }

    /// `fraction` of the living robots stop (see [`Radio::fail`]). Returns them.
    fn crash(
        &mut self,
        points: &[Point],
        fraction: f64,
        detect_after: u64,
    ) -> Result<Vec<u32>, AllocError> {
        let living: Vec<u32> = self.living().collect();
        let count = ((fraction * living.len() as f64).round() as usize).min(living.len() - 1);
        let mut crashed: Vec<u32> = rand::seq::index::sample(&mut self.rng, living.len(), count)
            .into_iter()
            .map(|k| living[k])
            .collect();
        crashed.sort_unstable();
        self.fail(&crashed, points, detect_after)?;
        Ok(crashed)
    }

    /// The living robots of `crashed` stop now: each is to be noticed `detect_after`
    /// rounds from now by its living neighbours (or its nearest living robot), and the
    /// survivors relink (returned as [`Radio::relink`]).
    ///
    /// # Errors
    /// [`AllocError::Graph`] if the survivors' graph cannot be built.
    pub fn fail(
        &mut self,
        crashed: &[u32],
        points: &[Point],
        detect_after: u64,
    ) -> Result<Vec<u32>, AllocError> {
        let crashed: Vec<u32> = crashed.iter().copied().filter(|&c| self.alive(c)).collect();
        for &c in &crashed {
            self.alive[c as usize] = false;
        }
        let survivors: Vec<u32> = self.living().collect();
        let at = self.round + detect_after;
        for &c in &crashed {
            let mut noticers: Vec<u32> = self
                .links
                .out(c)
                .map(|(_, a)| a)
                .filter(|&a| self.alive[a as usize])
                .collect();
            if noticers.is_empty() {
                let d = |x: u32| points[c as usize].distance(points[x as usize]);
                let nearest = survivors
                    .iter()
                    .copied()
                    .min_by(|&a, &b| d(a).total_cmp(&d(b)));
                noticers.extend(nearest);
            }
            self.to_notice
                .extend(noticers.into_iter().map(|a| (at, a, c)));
        }
        self.relink(points)
    }

    /// `robot` is back: alive, awake, and no longer to be noticed; it is linked at the
    /// next [`Radio::relink`].
    pub fn revive(&mut self, robot: u32) {
        self.alive[robot as usize] = true;
        self.awake[robot as usize] = true;
        self.to_notice.retain(|&(_, _, c)| c != robot);
    }

    /// Links the living robots anew by the graph rule at `points`; in a moving swarm
    /// (robots that moved), links that stay keep their loss state. Returns the robots
    /// whose neighbours changed (in a moving swarm; every survivor otherwise).
    ///
    /// # Errors
    /// [`AllocError::Graph`] if the graph cannot be built.
    pub fn relink(&mut self, points: &[Point]) -> Result<Vec<u32>, AllocError> {
        let living: Vec<u32> = self.living().collect();
        if living.is_empty() {
            return Ok(living);
        }
        let (mut links, added) = Links::build(
            points,
            &living,
            self.network.graph,
            self.split_x,
            self.connect,
        )?;
        let changed = if self.connect {
            living
        } else {
            links.carry_from(&self.links)
        };
        self.links = links;
        self.added_edges += added;
        Ok(changed)
    }

    /// Whether `robot` is alive.
    pub fn alive(&self, robot: u32) -> bool {
        self.alive[robot as usize]
    }

    /// Whether each robot is alive.
    pub fn alive_flags(&self) -> Vec<bool> {
        self.alive.clone()
    }

    /// Whether `robot` is alive and awake this round.
    pub fn up(&self, robot: u32) -> bool {
        self.alive[robot as usize] && self.awake[robot as usize]
    }

    /// The living robots.
    pub fn living(&self) -> impl Iterator<Item = u32> + '_ {
        (0..self.alive.len() as u32).filter(|&i| self.alive[i as usize])
    }

    /// The links out of `robot`: (link, neighbour).
    pub fn out(&self, robot: u32) -> impl Iterator<Item = (usize, u32)> + '_ {
        self.links.out(robot)
    }

    /// Number of robots `robot` is linked to.
    pub fn degree(&self, robot: u32) -> u64 {
        self.links.degree(robot)
    }

    /// Whether a message sent over `link` this round gets through (drawn as any
    /// message's loss).
    pub fn delivered(&mut self, link: usize) -> bool {
        !self
            .channel
            .lost(&mut self.links, link, self.round, &mut self.rng)
    }

    /// Sends `message` over `link` to `to`: lost, or in flight until its arrival round.
    pub fn transmit(&mut self, link: usize, to: u32, message: M) {
        if !self.delivered(link) {
            return;
        }
        let delay = self.channel.delay(&mut self.rng) as usize;
        let slot = (self.round as usize + delay) % self.in_flight.len();
        self.in_flight[slot].push((to, message));
        self.in_flight_count += 1;
    }

    /// This round's arrivals at living robots, in the order they were sent.
    pub fn arrivals(&mut self) -> Vec<(u32, M)> {
        let slot = self.round as usize % self.in_flight.len();
        let arrived = std::mem::take(&mut self.in_flight[slot]);
        self.in_flight_count -= arrived.len();
        let alive = &self.alive;
        arrived
            .into_iter()
            .filter(|(to, _)| alive[*to as usize])
            .collect()
    }

    /// Nothing in flight and nothing scheduled.
    pub fn idle(&self) -> bool {
        let crash_ahead = self
            .network
            .failure
            .is_some_and(|f| f.at_round > self.round);
        self.in_flight_count == 0 && !crash_ahead && self.to_notice.is_empty()
    }
}

/// Robots with something to do when next awake, each listed once.
pub(super) struct Roster {
    robots: Vec<u32>,
    listed: Vec<bool>,
}

impl Roster {
    /// None of `n` robots listed.
    pub fn empty(n: usize) -> Roster {
        Roster {
            robots: Vec::new(),
            listed: vec![false; n],
        }
    }

    /// All `n` robots listed, in index order.
    pub fn everyone(n: usize) -> Roster {
        Roster {
            robots: (0..n as u32).collect(),
            listed: vec![true; n],
        }
    }

    /// Lists `robot` (once).
    pub fn add(&mut self, robot: u32) {
        if !std::mem::replace(&mut self.listed[robot as usize], true) {
            self.robots.push(robot);
        }
    }

    pub fn is_empty(&self) -> bool {
        self.robots.is_empty()
    }

    /// Puts the list in index order.
    pub fn sort(&mut self) {
        self.robots.sort_unstable();
    }

    /// The listed robots up this round, in list order, taken off the list; asleep
    /// ones stay listed, crashed ones leave it.
    pub fn take_up<M>(&mut self, radio: &Radio<M>) -> Vec<u32> {
        let (up, asleep): (Vec<u32>, Vec<u32>) = std::mem::take(&mut self.robots)
            .into_iter()
            .filter(|&a| {
                let alive = radio.alive(a);
                self.listed[a as usize] = alive && !radio.up(a);
                alive
            })
            .partition(|&a| radio.up(a));
        self.robots = asleep;
        up
    }
}

/// The median of the points' x coordinates: the partition line.
fn median_x(points: &[Point]) -> f64 {
    let mut xs: Vec<f64> = points.iter().map(|p| p.x).collect();
    let mid = xs.len() / 2;
    *xs.select_nth_unstable_by(mid, f64::total_cmp).1
}

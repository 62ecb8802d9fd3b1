//! The radio at work: who hears whom this round, what is lost or delayed, who is
//! awake, and the roster of living robots.

use afg_game::Point;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::links::{Channel, Links};
use super::network::Network;
use crate::AllocError;

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

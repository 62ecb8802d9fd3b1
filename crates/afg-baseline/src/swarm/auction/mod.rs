//! The decentralised auction: CBAA (the consensus-based auction of Choi, Brunet and
//! How) on the slot-expanded problem, with Bertsekas' ε-bids.
//!
//! Task j has places k = 1, 2, … (up to its capacity), the k-th worth
//! `v_jk = F_j(k) − F_j(k−1)`, decreasing in k; robot i values it at `v_jk − β d(i, j)`.
//! Welfare is then the value of a matching of robots to places, so the optimum is an
//! assignment problem with N persons and Σ_j cap_j objects. Every robot keeps its own
//! table of each place's (price, winner). An awake robot that holds no place bids for
//! the one worth most to it at current prices, raising that price by the gap to its
//! second choice plus ε (Bertsekas' forward auction). Tables merge by max-consensus
//! between neighbours — higher price wins, then the lower robot id — and a robot that
//! learns it was outbid bids again.
//!
//! One departure (ours): a robot picks at random among the places within ε of its
//! best, not always the best. Many robots with nearly the same tables otherwise bid
//! for the same place in the same round and all but one bid again; spreading them
//! over near-equal places halved the rounds at N = 1000. A place that is not the best
//! is raised by ε alone, so each robot ends within 2ε of its best choice (2ε-CS).
//!
//! Prices only rise and every robot ends holding a place in every survivor's table,
//! at 2ε-complementary slackness: by LP duality the matching is within 2N·ε of the
//! best one, and the partition it gives (each robot at its place's task, places filled
//! from k = 1 up, worth at least the matching) as well.
//!
//! Where the instance allows the void task, it is one more place for everyone: worth
//! 0, at price 0, never filled and never raised, so it needs no record. A robot for
//! which it is (within ε of) the best choice holds it and bids no more: prices only
//! rise, so no other place can become worth more to it (until a restart).
//!
//! A crashed robot leaves a place whose price was set with it in the market: keeping
//! it, or freeing it at any price, breaks that argument (a late crash left 0.05 % of
//! the optimum on the table in our tests). So those who notice a crash restart the
//! auction among the survivors: a new epoch, every table open again at price 0. The
//! first record of the new epoch a robot hears makes it restart too; older epochs'
//! records lose to any of the new one.
//!
//! On a game whose tasks need teams (thresholds), the robots staff the tasks a
//! shared rule picks and each such task's first k places are worth the same large
//! bonus ([`teams`], ours); the epoch's first record carries the number of robots
//! living when it opened, which the rule counts. There a task done does not restart
//! the auction: the robots that held its places, and those holding places beyond a
//! team (who may be wanted by a team the freed robots let the rule staff), bid again,
//! the latter releasing their place by a record without a winner at ε above its
//! price; the teams at work keep their places.
//!
//! # Complexity
//! Every robot keeps a table of the places bid on so far, at most P = Σ_j cap_j (P = N
//! when uncapped, since a task never needs more places than robots): O(N·P) memory at
//! worst. A round costs O(P) per awake bidder (its best and second-best place) and
//! O(P) per table merged from a neighbour, so O(N·k·P) for a round in which every robot
//! hears its k neighbours. The rounds grow with the graph's diameter and with the
//! number of ε-increments the prices climb.
//!
//! Like GRAPE's simulation, only messages that can change their receiver are
//! simulated: a robot keeps sending a place's record while some neighbour holds a
//! lower one; every broadcast is counted.

use std::borrow::Cow;

use afg_game::{Instance, RobotId, TaskId};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::network::Network;
use super::radio::{Radio, Roster};
use super::task_news::TaskNews;
use super::{Outcome, Simulation, TracePoint, Traffic, partition_of};
use crate::AllocError;

mod events;
mod table;
mod teams;
use table::{HEADER_BYTES, Place, RECORD_BYTES, Record, Table, VOID};
use teams::Staffing;

/// The auction's state between rounds.
pub(crate) struct Auction<'a> {
    instance: Cow<'a, Instance>,
    /// In a mission: the tasks each robot knows of (`None`: every task known).
    news: Option<TaskNews>,
    epsilon: f64,
    radio: Radio<(Place, Record)>,
    /// Each task's place values `v_jk`, k from 0, as many as it has places.
    values: Vec<Vec<f64>>,
    /// On a game of teams: the tasks staffed and their team places.
    staffing: Option<Staffing>,
    /// The robots living when each epoch opened (what its records tell the rule).
    living_at: Vec<usize>,
    tables: Vec<Table>,
    /// The place each robot believes it holds.
    holding: Vec<Option<Place>>,
    /// The task of the last place each robot held (`None`: none, or the void): where a
    /// robot in a mission keeps heading while it bids again.
    last_task: Vec<Option<TaskId>>,
    /// Robots to bid when next awake.
    bidders: Roster,
    /// Places whose record some neighbour may lack, per robot, and the robots with any.
    pending: Vec<Vec<Place>>,
    senders: Roster,
    /// The epoch noticers restart to: one more per crash noticed.
    epochs: u32,
    /// Ties between places within ε of the best, drawn in bidding order.
    draws: ChaCha8Rng,
    bids: u64,
    adoptions: u64,
    traffic: Traffic,
}

impl<'a> Auction<'a> {
    /// An auction where nobody has bid yet.
    ///
    /// # Errors
    /// [`AllocError::InvalidParameter`] for ε not finite and positive or a network knob
    /// out of range, [`AllocError::Graph`] if the graph cannot be built.
    pub fn new(
        instance: &'a Instance,
        epsilon: f64,
        network: &Network,
        seed: u64,
    ) -> Result<Self, AllocError> {
        let radio = Radio::new(instance.robots(), network, seed)?;
        Self::with_radio(Cow::Borrowed(instance), epsilon, radio, seed, None)
    }

    /// An auction on `radio` where nobody has bid yet; `news` for a mission's robots,
    /// who know only some tasks.
    ///
    /// # Errors
    /// [`AllocError::InvalidParameter`] for ε not finite and positive.
    pub(super) fn with_radio(
        instance: Cow<'a, Instance>,
        epsilon: f64,
        radio: Radio<(Place, Record)>,
        seed: u64,
        news: Option<TaskNews>,
    ) -> Result<Self, AllocError> {
        if !(epsilon.is_finite() && epsilon > 0.0) {
            return Err(AllocError::InvalidParameter(format!(
                "auction increment ε = {epsilon} must be finite and positive"
            )));
        }
        let (n, m) = (instance.num_robots(), instance.num_tasks());
        let places = |j: TaskId| instance.capacity(j).min(n);
        let staffing = Staffing::of(&instance, epsilon);
        let values = match &staffing {
            Some(staffing) => staffing.values(&instance, places),
            None => (instance.task_ids())
                .map(|j| {
                    (1..=places(j))
                        .map(|k| instance.marginal_value(j, k))
                        .collect()
                })
                .collect(),
        };
        let living_at = vec![radio.living().count()];
        Ok(Auction {
            instance,
            news,
            epsilon,
            radio,
            values,
            staffing,
            living_at,
            tables: vec![Table::open(0, m); n],
            holding: vec![None; n],
            last_task: vec![None; n],
            bidders: Roster::everyone(n),
            pending: vec![Vec::new(); n],
            senders: Roster::empty(n),
            epochs: 0,
            draws: ChaCha8Rng::seed_from_u64(seed),
            bids: 0,
            adoptions: 0,
            traffic: Traffic::default(),
        })
    }

    /// What the run left: each survivor at the task of the place it holds.
    pub fn finish(self, converged: bool, trace: Vec<TracePoint>) -> Outcome {
        let tasks = self.held();
        let alive = self.radio.alive_flags();
        Outcome {
            agreeing: self.agreeing(&tasks),
            tasks,
            alive,
            converged,
            rounds: self.radio.round,
            changes: self.bids,
            proposals: self.bids,
            adoptions: self.adoptions,
            traffic: self.traffic,
            added_edges: self.radio.added_edges,
            trace,
        }
    }

    /// The partition the robots act on: each living robot at its place's task.
    fn held(&self) -> Vec<Option<TaskId>> {
        (0..self.tables.len())
            .map(|i| {
                let place = self.holding[i].filter(|_| self.radio.alive(i as u32));
                place.filter(|&p| p != VOID).map(|(j, _)| TaskId(j))
            })
            .collect()
    }

    /// Share of the living robots whose table gives `tasks` for every living robot.
    fn agreeing(&self, tasks: &[Option<TaskId>]) -> f64 {
        let n = self.tables.len();
        let (mut living, mut agreeing) = (0usize, 0usize);
        for a in self.radio.living() {
            living += 1;
            let theirs = self.tables[a as usize].partition(n);
            let same = self
                .radio
                .living()
                .all(|i| theirs[i as usize] == tasks[i as usize]);
            agreeing += usize::from(same);
        }
        agreeing as f64 / living as f64
    }

    /// `robot` writes `record` for `place` into its table and will spread it.
    fn write(&mut self, robot: u32, place: Place, record: Record) {
        self.tables[robot as usize].set(place, record);
        self.pending[robot as usize].push(place);
        self.senders.add(robot);
    }

    /// Every awake bidder bids if it holds no place. Returns whether anyone did.
    fn act(&mut self) -> bool {
        let mut acted = false;
        for a in self.bidders.take_up(&self.radio) {
            if self.holding[a as usize].is_none()
                && let Some((place, price)) = self.choose(a)
            {
                self.holding[a as usize] = Some(place);
                self.last_task[a as usize] = (place != VOID).then_some(TaskId(place.0));
                acted = true;
                if place == VOID {
                    continue; // nothing to tell anyone
                }
                let record = Record {
                    epoch: self.tables[a as usize].epoch,
                    price,
                    winner: a,
                };
                self.write(a, place, record);
                self.bids += 1;
            }
        }
        acted
    }

    /// A new epoch, counting the robots living now.
    fn open_epoch(&mut self) {
        self.epochs += 1;
        self.living_at.push(self.radio.living().count());
    }

    /// Robot `a` opens a new epoch: every place open, nothing held, a bid to make.
    fn restart(&mut self, a: u32, epoch: u32) {
        let m = self.instance.num_tasks();
        self.tables[a as usize] = Table::open(epoch, m);
        self.pending[a as usize].clear();
        self.holding[a as usize] = None;
        self.bidders.add(a);
    }

    /// Robot `a`'s bid by its table: a place within ε of the one worth most to it at
    /// current prices (drawn at random), and the price that leaves it ε below its
    /// second choice (the best place's) or, for another place, ε above the old price.
    /// [`VOID`] where the instance allows it and it is drawn; `None` only when every
    /// place is taken and there is no void.
    fn choose(&mut self, a: u32) -> Option<(Place, f64)> {
        let table = &self.tables[a as usize];
        let unbid = Record::open(table.epoch);
        let robot = RobotId(a);
        // (net value, place, price) of every place worth bidding for: the places bid
        // for so far, then each task's first open one.
        let mut options: Vec<(f64, Place, f64)> = Vec::new();
        let known = |j: usize| (self.news.as_ref()).is_none_or(|n| n.knows_open(a, j));
        let staffed = (self.staffing.as_ref())
            .map(|s| s.staffed(self.living_at[table.epoch as usize], known));
        let biddable =
            |j: TaskId| known(j.index()) && staffed.as_ref().is_none_or(|s| s[j.index()]);
        let eligible = |j: usize, k: usize| {
            (self.staffing.as_ref()).is_none_or(|s| s.eligible(a as usize, j, k))
        };
        for j in self.instance.task_ids().filter(|&j| biddable(j)) {
            let cost = self.instance.cost(robot, j);
            let values = &self.values[j.index()];
            let places = &table.tasks[j.index()];
            let open = (self.staffing.as_ref()).map_or(places.len(), |s| {
                s.first_eligible(a as usize, j.index(), places.len())
            });
            let first_open = (open < values.len()).then_some((open, unbid));
            let known =
                (places.iter().copied().enumerate()).filter(|&(k, _)| eligible(j.index(), k));
            for (k, r) in known.chain(first_open) {
                options.push((values[k] - r.price - cost, (j.0, k as u32), r.price));
            }
        }
        if self.instance.allows_void() {
            options.push((0.0, VOID, 0.0));
        }
        let best = options
            .iter()
            .map(|o| o.0)
            .fold(f64::NEG_INFINITY, f64::max);
        let near: Vec<usize> = (0..options.len())
            .filter(|&o| options[o].0 >= best - self.epsilon)
            .collect();
        let pick = *near.get(self.draws.random_range(0..near.len().max(1)))?;
        let (net, place, price) = options[pick];
        let second = options
            .iter()
            .enumerate()
            .filter(|&(o, _)| o != pick)
            .map(|(_, o)| o.0)
            .fold(f64::NEG_INFINITY, f64::max);
        let gap = if second.is_finite() {
            (net - second).max(0.0)
        } else {
            0.0
        };
        Some((place, price + gap + self.epsilon))
    }

    /// Awake senders send each pending record to the neighbours whose record it beats.
    /// Returns the robots that sent.
    fn send(&mut self, broadcasts: u64) -> Vec<u32> {
        let mut useful = 0u64;
        let sent = self.senders.take_up(&self.radio);
        for &b in &sent {
            let places = &mut self.pending[b as usize];
            places.sort_unstable();
            places.dedup();
            let links: Vec<(usize, u32)> = self.radio.out(b).collect();
            for &place in &self.pending[b as usize] {
                let record = self.tables[b as usize].get(place);
                for &(link, a) in &links {
                    if record.beats(&self.tables[a as usize].get(place)) {
                        useful += 1;
                        self.radio.transmit(link, a, (place, record));
                    }
                }
            }
        }
        self.traffic.messages += broadcasts;
        self.traffic.bytes += self.full_bytes();
        self.traffic.delta_bytes += broadcasts * HEADER_BYTES + useful * RECORD_BYTES;
        sent
    }

    /// Bytes of this round's broadcasts carrying whole tables (CBAA's winning bids).
    fn full_bytes(&self) -> u64 {
        self.radio
            .living()
            .filter(|&b| self.radio.up(b))
            .map(|b| {
                let size = HEADER_BYTES + self.tables[b as usize].len * RECORD_BYTES;
                size * self.radio.degree(b)
            })
            .sum()
    }

    /// Arrivals merge into their receivers' tables; an outbid robot will bid again.
    /// Returns whether any record was taken.
    fn deliver(&mut self) -> bool {
        let mut taken = false;
        for (a, (place, record)) in self.radio.arrivals() {
            if record.epoch > self.tables[a as usize].epoch {
                self.restart(a, record.epoch);
            }
            let mine = self.tables[a as usize].get(place);
            if !record.beats(&mine) {
                continue;
            }
            taken = true;
            self.adoptions += 1;
            if self.holding[a as usize] == Some(place) {
                self.holding[a as usize] = None;
                self.bidders.add(a);
            }
            self.write(a, place, record);
        }
        taken
    }

    /// Robots that sent keep the records some neighbour still lacks.
    fn keep_sending(&mut self, sent: Vec<u32>) {
        for b in sent {
            let links: Vec<u32> = self.radio.out(b).map(|(_, a)| a).collect();
            let table = &self.tables[b as usize];
            let tables = &self.tables;
            let mut places = std::mem::take(&mut self.pending[b as usize]);
            places.retain(|&place| {
                let record = table.get(place);
                links
                    .iter()
                    .any(|&a| record.beats(&tables[a as usize].get(place)))
            });
            if !places.is_empty() {
                self.senders.add(b);
            }
            self.pending[b as usize].extend(places);
        }
    }
}

impl Simulation for Auction<'_> {
    fn round(&mut self) -> Result<bool, AllocError> {
        let start = self.radio.next_round(self.instance.robots())?;
        if !start.crashed.is_empty() {
            // The survivors relinked: new neighbours may hold older tables.
            let living: Vec<u32> = self.radio.living().collect();
            self.resend(living);
        }
        if !start.noticed.is_empty() {
            self.open_epoch();
            for (noticer, _) in start.noticed {
                if self.tables[noticer as usize].epoch < self.epochs {
                    self.restart(noticer, self.epochs);
                }
            }
        }
        self.bidders.sort();
        let acted = self.act();
        let sent = self.send(start.broadcasts);
        let taken = self.deliver();
        self.keep_sending(sent);
        Ok(acted || taken)
    }

    fn quiet(&self) -> bool {
        self.bidders.is_empty() && self.senders.is_empty() && self.radio.idle()
    }

    fn rounds(&self) -> u64 {
        self.radio.round
    }

    fn sample(&self) -> TracePoint {
        let tasks = self.held();
        let assignment = partition_of(&tasks, self.instance.num_tasks());
        TracePoint {
            round: self.radio.round,
            welfare: self.instance.welfare(&assignment),
            agreeing: self.agreeing(&tasks),
        }
    }
}

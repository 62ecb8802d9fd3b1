//! GRAPE round by round over a [`Network`]: views, the distributed mutex, lost and
//! late messages, sleeping and crashed robots.
//!
//! Each robot keeps a view of the partition with an evolution number (changes seen)
//! and a random stamp. In a round every awake, unsatisfied robot changes its view
//! once (removes the crashed robots it has noticed, or else best-responds), then
//! every awake robot broadcasts its view; a robot keeps the highest (evolution,
//! stamp) it receives — GRAPE's mutex — and reconsiders.
//!
//! Only messages that can change their receiver are simulated: views only rise in
//! (evolution, stamp), so a view no higher than the receiver's is a heartbeat, counted
//! in `messages` and `bytes` but not delivered. A robot keeps sending (every round, as
//! in GRAPE) while some neighbour holds a lower view, so a lost message is sent again.

use std::rc::Rc;

use afg_game::{Assignment, Instance, Preference, RobotId, TaskId};
use imbl::Vector;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::network::{Channel, Links, Network};
use crate::AllocError;

/// One change on a chain of views.
struct Change {
    /// The robot that moved, or that removed crashed robots.
    robot: RobotId,
    /// Robots whose task the change set.
    entries: u64,
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

/// A robot's local view of the partition. Persistent: a change copies one path of a
/// shallow tree, and a message shares the sender's view.
pub(crate) struct View {
    tasks: Vector<Option<TaskId>>,
    sizes: Vec<usize>,
    evolution: u64,
    stamp: u64,
    last: Option<Rc<Change>>,
}

impl View {
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
    pub fn assignment(&self) -> Assignment {
        let mut assignment = Assignment::unassigned(self.tasks.len(), self.sizes.len());
        for (i, &task) in self.tasks.iter().enumerate() {
            assignment.set(RobotId(i as u32), task);
        }
        assignment
    }

    /// The robots whose changes made this view, oldest first.
    pub fn chain(&self) -> Vec<RobotId> {
        let mut chain = Vec::with_capacity(self.evolution as usize);
        let mut link = self.last.as_deref();
        while let Some(c) = link {
            chain.push(c.robot);
            link = c.prev.as_deref();
        }
        chain.reverse();
        chain
    }

    /// Changes made since the empty partition.
    pub fn evolution(&self) -> u64 {
        self.evolution
    }

    fn key(&self) -> (u64, u64) {
        (self.evolution, self.stamp)
    }

    /// The view after `robot` sets `robots` to `task` (one change), with a new stamp.
    fn changed(&self, robot: RobotId, robots: &[u32], task: Option<TaskId>, stamp: u64) -> View {
        let (mut tasks, mut sizes) = (self.tasks.clone(), self.sizes.clone());
        for &i in robots {
            if let Some(old) = tasks.set(i as usize, task) {
                sizes[old.index()] -= 1;
            }
            if let Some(new) = task {
                sizes[new.index()] += 1;
            }
        }
        View {
            tasks,
            sizes,
            evolution: self.evolution + 1,
            stamp,
            last: Some(Rc::new(Change {
                robot,
                entries: robots.len() as u64,
                prev: self.last.clone(),
            })),
        }
    }
}

/// Longest divergence of two views' chains that [`MessageSizes::delta`] walks.
const DELTA_WALK: u64 = 64;

/// Bytes of one message on the air: a 20-byte header (sender, evolution, stamp) and
/// one task index per robot (a byte below 255 tasks); a change costs its robot id
/// and task.
struct MessageSizes {
    header: u64,
    full: u64,
    entry: u64,
}

impl MessageSizes {
    fn new(n: usize, m: usize) -> MessageSizes {
        let task = if m < 255 { 1 } else { 2 };
        MessageSizes {
            header: 20,
            full: 20 + n as u64 * task,
            entry: 4 + task,
        }
    }

    /// What `from` costs to send, as changes, to a robot holding the lower view `to`:
    /// the sender's changes since the last view both descend from (the receiver
    /// undoes its own since then from its chain), or the whole partition when that is
    /// smaller or the branches part more than [`DELTA_WALK`] changes back (the walk
    /// along the chains is the simulation's cost, not the robots').
    fn delta(&self, from: &View, to: &View) -> u64 {
        let most = ((self.full - self.header) / self.entry).min(DELTA_WALK);
        let (mut mine, mut theirs) = (from.last.as_deref(), to.last.as_deref());
        let (mut above, mut entries) = (from.evolution - to.evolution, 0u64);
        // Until both chains meet (at the latest at the empty partition).
        while let (Some(a), b) = (mine, theirs) {
            if b.is_some_and(|b| std::ptr::eq(a, b)) {
                break;
            }
            entries += a.entries;
            if entries > most {
                return self.full;
            }
            mine = a.prev.as_deref();
            if above > 0 {
                above -= 1;
            } else {
                theirs = b.and_then(|b| b.prev.as_deref());
            }
        }
        self.header + entries * self.entry
    }
}

/// A point of the run's trace.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct TracePoint {
    /// Round (from 1).
    pub round: u64,
    /// Welfare of the highest view among the living robots, crashed robots left out.
    pub welfare: f64,
    /// Share of the living robots that hold that view.
    pub agreeing: f64,
}

/// Most points a trace keeps: when it is full, every other point goes and the
/// sampling stride doubles.
const TRACE_POINTS: usize = 256;

/// What a run left: the highest view among the living, every robot's view, counters.
pub(crate) struct Outcome {
    pub leader: Rc<View>,
    pub views: Vec<Rc<View>>,
    pub alive: Vec<bool>,
    pub converged: bool,
    pub rounds: u64,
    pub messages: u64,
    pub bytes: u64,
    pub delta_bytes: u64,
    pub added_edges: usize,
    pub trace: Vec<TracePoint>,
}

/// The simulation's state between rounds.
pub(crate) struct Grape<'a> {
    instance: &'a Instance,
    preference: Preference,
    network: &'a Network,
    channel: Channel,
    links: Links,
    /// GRAPE's stamps (drawn in robot order, only at changes) and the network's draws.
    stamps: ChaCha8Rng,
    rng: ChaCha8Rng,
    views: Vec<Rc<View>>,
    alive: Vec<bool>,
    awake: Vec<bool>,
    /// Robots to act when next awake, in index order.
    unsatisfied: Vec<u32>,
    is_unsatisfied: Vec<bool>,
    /// Robots with a view some neighbour lacks.
    senders: Vec<u32>,
    is_sender: Vec<bool>,
    /// The best view offered to each robot this round.
    offer: Vec<Option<Rc<View>>>,
    offered: Vec<u32>,
    /// Messages by arrival round modulo the longest delay + 1: (receiver, view).
    in_flight: Vec<Vec<(u32, Rc<View>)>>,
    in_flight_count: usize,
    /// Crashed robots each robot has noticed, and the (noticer, crashed) pairs to come.
    noticed: Vec<Vec<u32>>,
    to_notice: Vec<(u32, u32)>,
    notice_round: Option<u64>,
    split_x: Option<f64>,
    sizes: MessageSizes,
    round: u64,
    messages: u64,
    bytes: u64,
    delta_bytes: u64,
    added_edges: usize,
    /// The sampled trace, when asked for (each point costs O(N)).
    trace: Option<Vec<TracePoint>>,
    stride: u64,
}

impl<'a> Grape<'a> {
    /// A swarm where nobody has moved yet.
    ///
    /// # Errors
    /// [`AllocError::InvalidParameter`] for a network knob out of range,
    /// [`AllocError::Graph`] if the graph cannot be built.
    pub fn new(
        instance: &'a Instance,
        preference: Preference,
        network: &'a Network,
        seed: u64,
    ) -> Result<Self, AllocError> {
        network.check()?;
        let (n, m) = (instance.num_robots(), instance.num_tasks());
        let split_x = network.partition_until.map(|_| median_x(instance));
        let everyone: Vec<u32> = (0..n as u32).collect();
        let (links, added_edges) =
            Links::build(instance.robots(), &everyone, network.graph, split_x)?;
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        rng.set_stream(1);
        let empty = Rc::new(View::empty(n, m));
        Ok(Grape {
            instance,
            preference,
            network,
            channel: Channel::new(network),
            links,
            stamps: ChaCha8Rng::seed_from_u64(seed),
            rng,
            views: vec![empty; n],
            alive: vec![true; n],
            awake: vec![true; n],
            unsatisfied: everyone,
            is_unsatisfied: vec![true; n],
            senders: Vec::new(),
            is_sender: vec![false; n],
            offer: vec![None; n],
            offered: Vec::new(),
            in_flight: vec![Vec::new(); network.max_delay as usize + 1],
            in_flight_count: 0,
            noticed: vec![Vec::new(); n],
            to_notice: Vec::new(),
            notice_round: None,
            split_x,
            sizes: MessageSizes::new(n, m),
            round: 0,
            messages: 0,
            bytes: 0,
            delta_bytes: 0,
            added_edges,
            trace: None,
            stride: 1,
        })
    }

    /// Samples the leader's welfare and agreement as the rounds go.
    pub fn traced(mut self) -> Self {
        self.trace = Some(Vec::new());
        self
    }

    /// Runs rounds until one changes nothing and nothing more can happen, or until
    /// `max_rounds`; `on_round` sees each round's number.
    ///
    /// # Errors
    /// [`AllocError::Graph`] if the survivors' graph cannot be built.
    pub fn run(
        mut self,
        max_rounds: u64,
        mut on_round: impl FnMut(u64),
    ) -> Result<Outcome, AllocError> {
        let converged = loop {
            let active = self.round()?;
            on_round(self.round);
            if self.trace.is_some() && self.round.is_multiple_of(self.stride) {
                self.sample();
            }
            if !active && self.quiet() {
                break true;
            }
            if self.round >= max_rounds {
                break false;
            }
        };
        if self
            .trace
            .as_ref()
            .is_some_and(|t| t.last().is_none_or(|p| p.round != self.round))
        {
            self.sample();
        }
        Ok(Outcome {
            leader: Rc::clone(self.leader()),
            views: self.views,
            alive: self.alive,
            converged,
            rounds: self.round,
            messages: self.messages,
            bytes: self.bytes,
            delta_bytes: self.delta_bytes,
            added_edges: self.added_edges,
            trace: self.trace.unwrap_or_default(),
        })
    }

    /// One round; whether any robot changed or adopted a view.
    fn round(&mut self) -> Result<bool, AllocError> {
        self.round += 1;
        if let Some(failure) = self.network.failure
            && failure.at_round == self.round
        {
            self.crash(failure.fraction)?;
            self.notice_round = Some(self.round + failure.detect_after);
        }
        if self.notice_round == Some(self.round) {
            for (noticer, crashed) in std::mem::take(&mut self.to_notice) {
                self.noticed[noticer as usize].push(crashed);
                self.mark_unsatisfied(noticer);
            }
            self.unsatisfied.sort_unstable();
        }
        let broadcasts = self.wake();
        let changed = self.act();
        let sent = self.send(broadcasts);
        self.deliver();
        let adopted = self.adopt();
        self.keep_sending(sent);
        Ok(changed || adopted)
    }

    /// Nothing is left to do and nothing is scheduled.
    fn quiet(&self) -> bool {
        let crash_ahead = self
            .network
            .failure
            .is_some_and(|f| f.at_round > self.round);
        let notice_ahead = self.notice_round.is_some_and(|r| r > self.round);
        self.unsatisfied.is_empty()
            && self.senders.is_empty()
            && self.in_flight_count == 0
            && !crash_ahead
            && !notice_ahead
    }

    fn mark_unsatisfied(&mut self, robot: u32) {
        if !std::mem::replace(&mut self.is_unsatisfied[robot as usize], true) {
            self.unsatisfied.push(robot);
        }
    }

    fn mark_sender(&mut self, robot: u32) {
        if !std::mem::replace(&mut self.is_sender[robot as usize], true) {
            self.senders.push(robot);
        }
    }

    /// Draws who is awake this round; returns the messages their broadcasts make.
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

    /// Every awake unsatisfied robot changes its view once, if it has a change to make.
    fn act(&mut self) -> bool {
        let mut changed = false;
        let mut asleep = Vec::new();
        for a in std::mem::take(&mut self.unsatisfied) {
            let i = a as usize;
            if !self.alive[i] || !self.awake[i] {
                if self.alive[i] {
                    asleep.push(a);
                } else {
                    self.is_unsatisfied[i] = false;
                }
                continue;
            }
            self.is_unsatisfied[i] = false;
            if let Some(view) = self.next_view(a) {
                self.views[i] = Rc::new(view);
                changed = true;
                self.mark_sender(a);
            }
        }
        self.unsatisfied = asleep;
        changed
    }

    /// The change robot `a` makes to its view: remove the crashed robots it noticed that
    /// its view still places, or else move to its best response.
    fn next_view(&mut self, a: u32) -> Option<View> {
        let (robot, view) = (RobotId(a), &self.views[a as usize]);
        let gone: Vec<u32> = self.noticed[a as usize]
            .iter()
            .copied()
            .filter(|&c| view.tasks[c as usize].is_some())
            .collect();
        if !gone.is_empty() {
            return Some(view.changed(robot, &gone, None, self.stamps.random()));
        }
        let current = view.tasks[a as usize];
        let task =
            self.instance
                .best_response_given(robot, current, &view.sizes, self.preference)?;
        Some(view.changed(robot, &[a], Some(task), self.stamps.random()))
    }

    /// Awake senders broadcast: the messages that can change a neighbour are put in
    /// flight unless lost; all are counted. Returns the robots that sent.
    fn send(&mut self, broadcasts: u64) -> Vec<u32> {
        let (mut useful, mut useful_bytes) = (0u64, 0u64);
        let mut sent = Vec::new();
        let mut asleep = Vec::new();
        for b in std::mem::take(&mut self.senders) {
            if !self.alive[b as usize] {
                self.is_sender[b as usize] = false;
                continue;
            }
            if !self.awake[b as usize] {
                asleep.push(b);
                continue;
            }
            self.is_sender[b as usize] = false;
            sent.push(b);
            let view = Rc::clone(&self.views[b as usize]);
            let links: Vec<(usize, u32)> = self.links.out(b).collect();
            for (link, a) in links {
                let theirs = &self.views[a as usize];
                if theirs.key() >= view.key() {
                    continue;
                }
                useful += 1;
                useful_bytes += self.sizes.delta(&view, theirs);
                if self
                    .channel
                    .lost(&mut self.links, link, self.round, &mut self.rng)
                {
                    continue;
                }
                let slot = (self.round as usize + self.channel.delay(&mut self.rng) as usize)
                    % self.in_flight.len();
                self.in_flight[slot].push((a, Rc::clone(&view)));
                self.in_flight_count += 1;
            }
        }
        self.senders = asleep;
        self.messages += broadcasts;
        self.bytes += broadcasts * self.sizes.full;
        self.delta_bytes += (broadcasts - useful) * self.sizes.header + useful_bytes;
        sent
    }

    /// This round's arrivals: each living receiver's best offer above its own view.
    fn deliver(&mut self) {
        let slot = self.round as usize % self.in_flight.len();
        for (a, view) in std::mem::take(&mut self.in_flight[slot]) {
            self.in_flight_count -= 1;
            let i = a as usize;
            if !self.alive[i] {
                continue;
            }
            let best = self.offer[i].as_ref().unwrap_or(&self.views[i]).key();
            if view.key() > best {
                if self.offer[i].is_none() {
                    self.offered.push(a);
                }
                self.offer[i] = Some(view);
            }
        }
    }

    /// Robots take their best offer and reconsider; whether any did.
    fn adopt(&mut self) -> bool {
        let offered = std::mem::take(&mut self.offered);
        for &a in &offered {
            let view = self.offer[a as usize]
                .take()
                .expect("an offered robot has an offer");
            self.views[a as usize] = view;
            self.mark_unsatisfied(a);
            self.mark_sender(a);
        }
        self.unsatisfied.sort_unstable();
        !offered.is_empty()
    }

    /// Robots that sent keep sending while a neighbour still holds a lower view.
    fn keep_sending(&mut self, sent: Vec<u32>) {
        for b in sent {
            let key = self.views[b as usize].key();
            let behind = self
                .links
                .out(b)
                .any(|(_, a)| self.views[a as usize].key() < key);
            if behind {
                self.mark_sender(b);
            }
        }
    }

    /// `fraction` of the living robots stop; their neighbours will notice, and the
    /// survivors relink.
    fn crash(&mut self, fraction: f64) -> Result<(), AllocError> {
        let living: Vec<u32> = (0..self.alive.len() as u32)
            .filter(|&i| self.alive[i as usize])
            .collect();
        let count = ((fraction * living.len() as f64).round() as usize).min(living.len() - 1);
        let mut crashed: Vec<u32> = rand::seq::index::sample(&mut self.rng, living.len(), count)
            .into_iter()
            .map(|k| living[k])
            .collect();
        crashed.sort_unstable();
        for &c in &crashed {
            self.alive[c as usize] = false;
        }
        let points = self.instance.robots();
        for &c in &crashed {
            let mut noticers: Vec<u32> = self
                .links
                .out(c)
                .map(|(_, a)| a)
                .filter(|&a| self.alive[a as usize])
                .collect();
            if noticers.is_empty() {
                let nearest = living
                    .iter()
                    .copied()
                    .filter(|&a| self.alive[a as usize])
                    .min_by(|&a, &b| {
                        let d = |x: u32| points[c as usize].distance(points[x as usize]);
                        d(a).total_cmp(&d(b))
                    })
                    .expect("a robot survives");
                noticers.push(nearest);
            }
            self.to_notice.extend(noticers.into_iter().map(|a| (a, c)));
        }
        let survivors: Vec<u32> = living
            .into_iter()
            .filter(|&a| self.alive[a as usize])
            .collect();
        let (links, added) = Links::build(points, &survivors, self.network.graph, self.split_x)?;
        self.links = links;
        self.added_edges += added;
        // New neighbours may hold older views.
        for a in survivors {
            self.mark_sender(a);
        }
        Ok(())
    }

    /// The highest view among the living robots.
    fn leader(&self) -> &Rc<View> {
        self.views
            .iter()
            .zip(&self.alive)
            .filter(|(_, alive)| **alive)
            .map(|(v, _)| v)
            .max_by_key(|v| v.key())
            .expect("a robot survives")
    }

    /// Records the leader's welfare and how many hold it; thins the trace when full.
    fn sample(&mut self) {
        let leader = Rc::clone(self.leader());
        let (mut living, mut agreeing) = (0usize, 0usize);
        for (view, &alive) in self.views.iter().zip(&self.alive) {
            living += usize::from(alive);
            agreeing += usize::from(alive && view.key() == leader.key());
        }
        let mut assignment = leader.assignment();
        for (i, &alive) in self.alive.iter().enumerate() {
            if !alive {
                assignment.set(RobotId(i as u32), None);
            }
        }
        let point = TracePoint {
            round: self.round,
            welfare: self.instance.welfare(&assignment),
            agreeing: agreeing as f64 / living as f64,
        };
        let Some(trace) = self.trace.as_mut() else {
            return;
        };
        trace.push(point);
        if trace.len() >= TRACE_POINTS {
            let mut keep = false;
            trace.retain(|_| {
                keep = !keep;
                keep
            });
            self.stride *= 2;
        }
    }
}

/// The median of the robots' x coordinates: the partition line.
fn median_x(instance: &Instance) -> f64 {
    let mut xs: Vec<f64> = instance.robots().iter().map(|p| p.x).collect();
    let mid = xs.len() / 2;
    *xs.select_nth_unstable_by(mid, f64::total_cmp).1
}

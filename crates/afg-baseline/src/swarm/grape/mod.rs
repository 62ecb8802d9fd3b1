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
//!
//! # Complexity
//! A round costs O(A·M + D·s) for A awake robots that best-respond (O(M) each), D
//! deliveries of a higher view and the s-step path copy each adoption makes (views are
//! persistent, s ≈ log N); heartbeats cost O(1). GRAPE's mutex keeps one chain of
//! changes, so the rounds grow about as N and the work as N² over a run (about 10⁹
//! robot-steps at N = 10 000, docs/swarm.md). Memory O(N·k) for the links and the
//! messages in flight, plus the views' shared trees.

use std::borrow::Cow;
use std::rc::Rc;

use afg_game::{Instance, Point, Preference, RobotId, TaskId};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::moving::{move_swarm, revive, tell};
use super::network::Network;
use super::radio::{Radio, Roster};
use super::task_news::TaskNews;
use super::{Outcome, Simulation, TracePoint, Traffic, partition_of};
use crate::AllocError;

mod view;
use view::{MessageSizes, View};

/// The simulation's state between rounds.
pub(crate) struct Grape<'a> {
    instance: Cow<'a, Instance>,
    preference: Preference,
    radio: Radio<Rc<View>>,
    /// GRAPE's stamps, drawn in robot order, only at changes.
    stamps: ChaCha8Rng,
    views: Vec<Rc<View>>,
    /// Robots to act when next awake, in index order.
    unsatisfied: Roster,
    /// Robots with a view some neighbour lacks.
    senders: Roster,
    /// The best view offered to each robot this round.
    offer: Vec<Option<Rc<View>>>,
    offered: Vec<u32>,
    /// Crashed robots each robot has noticed.
    noticed: Vec<Vec<u32>>,
    /// In a mission: the tasks each robot knows of, and how that news spreads
    /// (`None`: every task is known to every robot).
    news: Option<TaskNews>,
    sizes: MessageSizes,
    traffic: Traffic,
    proposals: u64,
    adoptions: u64,
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
        network: &Network,
        seed: u64,
    ) -> Result<Self, AllocError> {
        let radio = Radio::new(instance.robots(), network, seed)?;
        Ok(Self::with_radio(
            Cow::Borrowed(instance),
            preference,
            radio,
            seed,
            None,
        ))
    }

    /// A swarm on `radio` where nobody has moved yet; `news` for a mission's robots,
    /// who know only some tasks.
    pub(super) fn with_radio(
        instance: Cow<'a, Instance>,
        preference: Preference,
        radio: Radio<Rc<View>>,
        seed: u64,
        news: Option<TaskNews>,
    ) -> Self {
        let (n, m) = (instance.num_robots(), instance.num_tasks());
        let empty = Rc::new(View::empty(n, m));
        Grape {
            instance,
            preference,
            radio,
            stamps: ChaCha8Rng::seed_from_u64(seed),
            views: vec![empty; n],
            unsatisfied: Roster::everyone(n),
            senders: Roster::empty(n),
            offer: vec![None; n],
            offered: Vec::new(),
            noticed: vec![Vec::new(); n],
            news,
            sizes: MessageSizes::new(n, m),
            traffic: Traffic::default(),
            proposals: 0,
            adoptions: 0,
        }
    }

    /// What the run left, and the final partition's view.
    pub fn finish(self, converged: bool, trace: Vec<TracePoint>) -> (Outcome, Rc<View>) {
        let leader = Rc::clone(self.leader());
        let alive = self.radio.alive_flags();
        let outcome = Outcome {
            agreeing: self.agreeing_with(&leader),
            tasks: self.living_tasks(&leader),
            alive,
            converged,
            rounds: self.radio.round,
            changes: leader.evolution,
            proposals: self.proposals,
            adoptions: self.adoptions,
            traffic: self.traffic,
            added_edges: self.radio.added_edges,
            trace,
        };
        (outcome, leader)
    }

    /// The task of each robot in `view`, crashed robots unassigned.
    fn living_tasks(&self, view: &View) -> Vec<Option<TaskId>> {
        (view.tasks.iter().enumerate())
            .map(|(i, &task)| task.filter(|_| self.radio.alive(i as u32)))
            .collect()
    }

    /// Share of the living robots whose view holds the same partition as `leader`.
    fn agreeing_with(&self, leader: &Rc<View>) -> f64 {
        let (mut living, mut agreeing) = (0usize, 0usize);
        for i in self.radio.living() {
            let view = &self.views[i as usize];
            living += 1;
            agreeing += usize::from(view.key() == leader.key() || view.tasks == leader.tasks);
        }
        agreeing as f64 / living as f64
    }

    /// One round; whether any robot changed or adopted a view.
    fn round_impl(&mut self) -> Result<bool, AllocError> {
        let start = self.radio.next_round(self.instance.robots())?;
        if !start.crashed.is_empty() {
            // The survivors relinked: new neighbours may hold older views.
            let living: Vec<u32> = self.radio.living().collect();
            for a in living {
                self.senders.add(a);
            }
        }
        if !start.noticed.is_empty() {
            for (noticer, crashed) in start.noticed {
                self.noticed[noticer as usize].push(crashed);
                self.unsatisfied.add(noticer);
            }
            self.unsatisfied.sort();
        }
        let changed = self.act();
        let sent = self.send(start.broadcasts);
        self.deliver();
        let adopted = self.adopt();
        self.keep_sending(sent);
        let mut learnt = false;
        if let Some(news) = &mut self.news {
            let (told, bytes) = news.spread(&mut self.radio);
            self.traffic.bytes += bytes;
            self.traffic.delta_bytes += bytes;
            learnt = !told.is_empty();
            self.reconsider(told);
        }
        Ok(changed || adopted || learnt)
    }

    /// `robots` reconsider when next awake (they learnt of a task).
    fn reconsider(&mut self, robots: impl IntoIterator<Item = u32>) {
        for a in robots {
            self.unsatisfied.add(a);
        }
        self.unsatisfied.sort();
    }

    /// A mission's news: `task` appeared (or is done); the robots that hear of it
    /// reconsider.
    pub fn task_event(&mut self, task: usize, done: bool) {
        let told = tell(&mut self.news, &self.radio, &self.instance, task, done);
        self.reconsider(told);
    }

    /// The robots are at `points` now (see [`move_swarm`]): robots with new neighbours
    /// resend to those that lag, and robots that see a task reconsider.
    ///
    /// # Errors
    /// As [`move_swarm`].
    pub fn move_to(&mut self, points: Vec<Point>) -> Result<(), AllocError> {
        let (relinked, saw) =
            move_swarm(&mut self.instance, &mut self.radio, &mut self.news, points)?;
        for a in relinked {
            self.senders.add(a);
        }
        self.reconsider(saw);
        Ok(())
    }

    /// `robots` fail now; their neighbours notice after `detect_after` rounds.
    ///
    /// # Errors
    /// [`AllocError::Graph`] if the survivors' graph cannot be built.
    pub fn fail(&mut self, robots: &[u32], detect_after: u64) -> Result<(), AllocError> {
        let relinked = (self.radio).fail(robots, self.instance.robots(), detect_after)?;
        for a in relinked {
            self.senders.add(a);
        }
        Ok(())
    }

    /// `robot` is back, with the view it had, and linked; the others forget they saw
    /// it fail.
    ///
    /// # Errors
    /// [`AllocError::Graph`] if the graph cannot be built.
    pub fn revive(&mut self, robot: u32) -> Result<(), AllocError> {
        for noticed in &mut self.noticed {
            noticed.retain(|&c| c != robot);
        }
        for a in revive(&mut self.radio, &self.instance, robot)? {
            self.senders.add(a);
        }
        self.reconsider([robot]);
        Ok(())
    }

    /// The task `robot`'s own view gives it.
    pub fn own_task(&self, robot: u32) -> Option<TaskId> {
        self.views[robot as usize].tasks[robot as usize]
    }

    /// Whether every living robot holds the same view.
    pub fn agreed(&self) -> bool {
        let mut keys = self.radio.living().map(|i| self.views[i as usize].key());
        keys.next().is_none_or(|first| keys.all(|k| k == first))
    }

    /// Messages and bytes sent so far (as [`Traffic`]).
    pub fn traffic(&self) -> Traffic {
        self.traffic
    }

    /// Every awake unsatisfied robot changes its view once, if it has a change to make.
    /// A robot that removed robots from its view (crashed, or on a task done) stays
    /// unsatisfied: next round it looks at its own place in the view it made, whether or
    /// not a newer view reaches it.
    fn act(&mut self) -> bool {
        let mut changed = false;
        let mut again = false;
        for a in self.unsatisfied.take_up(&self.radio) {
            if let Some((view, removal)) = self.next_view(a) {
                if removal {
                    self.unsatisfied.add(a);
                    again = true;
                }
                self.views[a as usize] = Rc::new(view);
                self.proposals += 1;
                changed = true;
                self.senders.add(a);
            }
        }
        if again {
            self.unsatisfied.sort();
        }
        changed
    }

    /// The change robot `a` makes to its view: remove the crashed robots it noticed that
    /// its view still places (and the robots of the tasks it knows are done), or else
    /// make its best move (to a task, or to the void where the instance allows it); and
    /// whether it was a removal, after which `a` must look at its own place again.
    fn next_view(&mut self, a: u32) -> Option<(View, bool)> {
        let (robot, view) = (RobotId(a), &self.views[a as usize]);
        let mut gone: Vec<u32> = self.noticed[a as usize]
            .iter()
            .copied()
            .filter(|&c| view.tasks[c as usize].is_some())
            .collect();
        if let Some(news) = &self.news {
            for task in news.known_done(a).filter(|&j| view.sizes[j] > 0) {
                let at = |i: &usize| view.tasks[*i] == Some(TaskId(task as u32));
                gone.extend((0..view.tasks.len()).filter(at).map(|i| i as u32));
            }
        }
        if !gone.is_empty() {
            return Some((view.changed(robot, &gone, None, self.stamps.random()), true));
        }
        let current = view.tasks[a as usize];
        let place = match &self.news {
            None => (self.instance).best_move_given(robot, current, &view.sizes, self.preference),
            Some(news) => {
                self.instance
                    .best_move_among(robot, current, &view.sizes, self.preference, |t| {
                        news.knows_open(a, t.index())
                    })
            }
        }?;
        Some((
            view.changed(robot, &[a], place, self.stamps.random()),
            false,
        ))
    }

    /// Awake senders broadcast: the messages that can change a neighbour are put in
    /// flight unless lost; all are counted. Returns the robots that sent.
    fn send(&mut self, broadcasts: u64) -> Vec<u32> {
        let (mut useful, mut useful_bytes) = (0u64, 0u64);
        let sent = self.senders.take_up(&self.radio);
        for &b in &sent {
            let view = Rc::clone(&self.views[b as usize]);
            let links: Vec<(usize, u32)> = self.radio.out(b).collect();
            for (link, a) in links {
                let theirs = &self.views[a as usize];
                if theirs.key() >= view.key() {
                    continue;
                }
                useful += 1;
                useful_bytes += self.sizes.delta(&view, theirs);
                self.radio.transmit(link, a, Rc::clone(&view));
            }
        }
        self.traffic.messages += broadcasts;
        self.traffic.bytes += broadcasts * self.sizes.full;
        self.traffic.delta_bytes += (broadcasts - useful) * self.sizes.header + useful_bytes;
        sent
    }

    /// This round's arrivals: each living receiver's best offer above its own view.
    fn deliver(&mut self) {
        for (a, view) in self.radio.arrivals() {
            let i = a as usize;
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
            self.unsatisfied.add(a);
            self.senders.add(a);
        }
        self.unsatisfied.sort();
        self.adoptions += offered.len() as u64;
        !offered.is_empty()
    }

    /// Robots that sent keep sending while a neighbour still holds a lower view.
    fn keep_sending(&mut self, sent: Vec<u32>) {
        for b in sent {
            let key = self.views[b as usize].key();
            let behind = self
                .radio
                .out(b)
                .any(|(_, a)| self.views[a as usize].key() < key);
            if behind {
                self.senders.add(b);
            }
        }
    }

    /// The highest view among the living robots.
    fn leader(&self) -> &Rc<View> {
        self.radio
            .living()
            .map(|i| &self.views[i as usize])
            .max_by_key(|v| v.key())
            .expect("a robot survives")
    }
}

impl Simulation for Grape<'_> {
    fn round(&mut self) -> Result<bool, AllocError> {
        self.round_impl()
    }

    fn quiet(&self) -> bool {
        self.unsatisfied.is_empty() && self.senders.is_empty() && self.radio.idle()
    }

    fn rounds(&self) -> u64 {
        self.radio.round
    }

    /// The leader's welfare over the living robots, and how many hold it.
    fn sample(&self) -> TracePoint {
        let leader = self.leader();
        let assignment = partition_of(&self.living_tasks(leader), self.instance.num_tasks());
        TracePoint {
            round: self.radio.round,
            welfare: self.instance.welfare(&assignment),
            agreeing: self.agreeing_with(leader),
        }
    }
}

//! The auction in a moving swarm: tasks that appear or are done, robots that move,
//! fail and come back, and what the swarm reads out between rounds.

use afg_game::{Point, TaskId};

use super::Auction;
use super::table::{NOBODY, Record, VOID};
use crate::AllocError;
use crate::swarm::Traffic;
use crate::swarm::moving::{move_swarm, revive, tell};

impl Auction<'_> {
    /// `robots` will send every record of their tables again (they have new
    /// neighbours, who may hold older ones).
    pub(super) fn resend(&mut self, robots: Vec<u32>) {
        for a in robots {
            let table = &self.tables[a as usize];
            let places = table
                .tasks
                .iter()
                .enumerate()
                .flat_map(|(j, places)| (0..places.len() as u32).map(move |k| (j as u32, k)));
            self.pending[a as usize].extend(places);
            self.senders.add(a);
        }
    }

    /// `robots` heard news: they open a new epoch (one for all of them), which spreads
    /// with their bids. The auction's prices only rise, so a new task, a task done or
    /// a task seen is a restart among those who hear of it.
    pub(super) fn renew(&mut self, robots: Vec<u32>) {
        if robots.is_empty() {
            return;
        }
        self.open_epoch();
        for a in robots {
            if self.tables[a as usize].epoch < self.epochs {
                self.restart(a, self.epochs);
            }
        }
    }

    /// A mission's news: `task` appeared (or is done); the robots that hear of it
    /// restart the auction — but for a task done in a game of teams, where only the
    /// robots it frees and those beyond a team bid again ([`Auction::free`]).
    pub fn task_event(&mut self, task: usize, done: bool) {
        let told = tell(&mut self.news, &self.radio, &self.instance, task, done);
        if done && self.staffing.is_some() {
            self.free(told, task as u32);
        } else {
            self.renew(told);
        }
    }

    /// `robots` heard that `task` is done, in a game of teams: those that held its
    /// places or a place beyond a team (which they release: no winner, ε above its
    /// price) bid again; the others keep their teams.
    fn free(&mut self, robots: Vec<u32>, task: u32) {
        let Some(staffing) = &self.staffing else {
            return;
        };
        let mut released = Vec::new();
        for a in robots {
            let held = self.holding[a as usize];
            match held {
                Some(place) if place.0 == task => {}
                Some(place) if place != VOID && staffing.beyond_team(place) => {
                    released.push((a, place));
                }
                Some(VOID) | None => {}
                Some(_) => continue,
            }
            self.holding[a as usize] = None;
            self.bidders.add(a);
        }
        for (a, place) in released {
            let held = self.tables[a as usize].get(place);
            let record = Record {
                price: held.price + self.epsilon,
                winner: NOBODY,
                ..held
            };
            self.write(a, place, record);
        }
    }

    /// The robots are at `points` now (see [`move_swarm`]): robots with new neighbours
    /// resend their tables, and robots that see a task restart the auction.
    ///
    /// # Errors
    /// As [`move_swarm`].
    pub fn move_to(&mut self, points: Vec<Point>) -> Result<(), AllocError> {
        let (relinked, saw) =
            move_swarm(&mut self.instance, &mut self.radio, &mut self.news, points)?;
        self.resend(relinked);
        self.renew(saw);
        Ok(())
    }

    /// `robots` fail now; their neighbours notice after `detect_after` rounds and
    /// restart the auction among the survivors.
    ///
    /// # Errors
    /// [`AllocError::Graph`] if the survivors' graph cannot be built.
    pub fn fail(&mut self, robots: &[u32], detect_after: u64) -> Result<(), AllocError> {
        let relinked = (self.radio).fail(robots, self.instance.robots(), detect_after)?;
        self.resend(relinked);
        Ok(())
    }

    /// `robot` is back and linked, and bids in the auction's current epoch.
    ///
    /// # Errors
    /// [`AllocError::Graph`] if the graph cannot be built.
    pub fn revive(&mut self, robot: u32) -> Result<(), AllocError> {
        let relinked = revive(&mut self.radio, &self.instance, robot)?;
        self.restart(robot, self.epochs);
        self.resend(relinked);
        Ok(())
    }

    /// The task of the place `robot` believes it holds, or, while it bids again (it
    /// was outbid, or the auction restarted), of the last place it held if it does not
    /// know that task is done.
    pub fn own_task(&self, robot: u32) -> Option<TaskId> {
        let known =
            |j: &TaskId| (self.news.as_ref()).is_none_or(|n| n.knows_open(robot, j.index()));
        self.last_task[robot as usize].filter(known)
    }

    /// Whether every living robot's table gives the same partition (O(N · places)).
    pub fn agreed(&self) -> bool {
        let n = self.tables.len();
        let mut partitions = self
            .radio
            .living()
            .map(|a| self.tables[a as usize].partition(n));
        partitions
            .next()
            .is_none_or(|first| partitions.all(|p| p == first))
    }

    /// Messages and bytes sent so far.
    pub fn traffic(&self) -> Traffic {
        self.traffic
    }
}

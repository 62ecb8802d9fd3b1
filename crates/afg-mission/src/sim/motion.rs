//! Robots in motion: straight legs at their speed, where each is now, and the heap of
//! arrivals to come.

use std::cmp::Ordering;

use afg_game::Point;

use super::{REACHED, Robot, Sim, TraceEvent};

/// A robot's arrival at the end of its current leg, earliest first in a heap.
#[derive(Clone, Copy, Debug)]
pub(super) struct Arrival {
    pub(super) time: f64,
    pub(super) robot: u32,
    pub(super) leg: u64,
}

impl PartialEq for Arrival {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other) == Ordering::Equal
    }
}
impl Eq for Arrival {}
impl PartialOrd for Arrival {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for Arrival {
    /// Reversed, so that `BinaryHeap` pops the earliest; ties by robot index.
    fn cmp(&self, other: &Self) -> Ordering {
        other
            .time
            .total_cmp(&self.time)
            .then(other.robot.cmp(&self.robot))
            .then(other.leg.cmp(&self.leg))
    }
}

impl Sim<'_, '_> {
    /// Robots reaching their task now (from the queue of legs, the stale ones dropped).
    pub(super) fn arrivals(&mut self) {
        while let Some(&due) = self.due.peek() {
            if due.time > self.now {
                break;
            }
            self.due.pop();
            let i = due.robot as usize;
            let r = self.robots[i];
            if due.leg != self.legs[i] || !r.alive || r.there {
                continue;
            }
            if let Some(j) = r.task {
                let target = self.mission.tasks[j].position;
                self.distance += r.from.distance(target);
                self.robots[i].from = target;
                self.robots[i].since = self.now;
                self.robots[i].there = true;
                self.present(i, j, true);
                self.log(TraceEvent::Arrival {
                    time: self.now,
                    robot: i,
                    task: j,
                });
            }
        }
    }

    /// When robot `i`, on its leg to task `j`, gets there.
    pub(super) fn arrival_time(&self, i: usize, j: usize) -> f64 {
        let r = &self.robots[i];
        let d = r.from.distance(self.mission.tasks[j].position);
        let t = r.since + d / self.mission.robots[i].speed;
        // Within rounding of now counts as now.
        if t - self.now <= REACHED * t.abs().max(1.0) {
            self.now
        } else {
            t
        }
    }

    /// Where robot `i` is now.
    pub(super) fn position(&self, i: usize) -> Point {
        let r = &self.robots[i];
        match r.task.filter(|_| r.alive && !r.there) {
            None => r.from,
            Some(j) => {
                let to = self.mission.tasks[j].position;
                let d = r.from.distance(to);
                let covered = (self.now - r.since) * self.mission.robots[i].speed;
                if d <= 0.0 || covered >= d {
                    return to;
                }
                let f = covered / d;
                Point::new(
                    r.from.x + f * (to.x - r.from.x),
                    r.from.y + f * (to.y - r.from.y),
                )
            }
        }
    }

    /// Robot `i` stops where it is: it leaves its task (and its coalition, if there).
    pub(super) fn stop(&mut self, i: usize) {
        self.legs[i] += 1;
        let here = self.position(i);
        let r = self.robots[i];
        if let Some(j) = r.task {
            if r.there {
                self.present(i, j, false);
            } else if r.alive {
                self.distance += r.from.distance(here);
            }
        }
        self.robots[i] = Robot {
            from: here,
            since: self.now,
            task: None,
            there: false,
            ..r
        };
    }

    /// Robot `i` heads for task `j` from where it is.
    pub(super) fn send(&mut self, i: usize, j: usize) {
        if self.robots[i].task == Some(j) {
            return;
        }
        if self.robots[i].task.is_some() {
            self.reassignments += 1;
        }
        self.stop(i);
        self.robots[i].task = Some(j);
        let time = self.arrival_time(i, j);
        self.due.push(Arrival {
            time,
            robot: i as u32,
            leg: self.legs[i],
        });
    }
}

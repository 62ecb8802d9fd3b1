//! A robot's view of the partition under GRAPE: a chain of changes shared with the
//! views it came from, and the bytes a message of it takes.

use std::rc::Rc;

use afg_game::{Assignment, RobotId, TaskId};
use imbl::Vector;

use crate::swarm::partition_of;

/// One change on a chain of views.
pub(in crate::swarm) struct Change {
    /// The robot that moved, or that removed crashed robots.
    pub(in crate::swarm) robot: RobotId,
    /// Robots whose task the change set.
    pub(in crate::swarm) entries: u64,
    pub(in crate::swarm) prev: Option<Rc<Change>>,
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
    pub(in crate::swarm) tasks: Vector<Option<TaskId>>,
    pub(in crate::swarm) sizes: Vec<usize>,
    pub(in crate::swarm) evolution: u64,
    pub(in crate::swarm) stamp: u64,
    pub(in crate::swarm) last: Option<Rc<Change>>,
}

impl View {
    pub(in crate::swarm) fn empty(n: usize, m: usize) -> View {
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
        let tasks: Vec<Option<TaskId>> = self.tasks.iter().copied().collect();
        partition_of(&tasks, self.sizes.len())
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

    pub(in crate::swarm) fn key(&self) -> (u64, u64) {
        (self.evolution, self.stamp)
    }

    /// The view after `robot` sets `robots` to `task` (one change), with a new stamp.
    pub(in crate::swarm) fn changed(
        &self,
        robot: RobotId,
        robots: &[u32],
        task: Option<TaskId>,
        stamp: u64,
    ) -> View {
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
pub(in crate::swarm) const DELTA_WALK: u64 = 64;

/// Bytes of one message on the air: a 20-byte header (sender, evolution, stamp) and
/// one task index per robot (a byte below 255 tasks); a change costs its robot id
/// and task.
pub(in crate::swarm) struct MessageSizes {
    pub(in crate::swarm) header: u64,
    pub(in crate::swarm) full: u64,
    pub(in crate::swarm) entry: u64,
}

impl MessageSizes {
    pub(in crate::swarm) fn new(n: usize, m: usize) -> MessageSizes {
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
    pub(in crate::swarm) fn delta(&self, from: &View, to: &View) -> u64 {
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

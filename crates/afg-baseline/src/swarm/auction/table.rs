//! A robot's table of the auction: the latest record it knows of every place of every
//! task, and what a record weighs on the air.

use afg_game::TaskId;

/// No winner.
pub(in crate::swarm) const NOBODY: u32 = u32::MAX;

/// Bytes of a record on the air: place (task and index), price (f32) and winner.
pub(in crate::swarm) const RECORD_BYTES: u64 = 12;

/// A message header: sender and length.
pub(in crate::swarm) const HEADER_BYTES: u64 = 8;

/// One place's state in a robot's table.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(in crate::swarm) struct Record {
    /// The auction's epoch: raised each time it restarts after a crash.
    pub(in crate::swarm) epoch: u32,
    pub(in crate::swarm) price: f64,
    pub(in crate::swarm) winner: u32,
}

impl Record {
    /// A place nobody has bid for in `epoch`.
    pub(in crate::swarm) fn open(epoch: u32) -> Record {
        Record {
            epoch,
            price: 0.0,
            winner: NOBODY,
        }
    }

    /// Max-consensus order: later epoch, then higher price, then the lower robot id.
    pub(in crate::swarm) fn beats(&self, other: &Record) -> bool {
        self.epoch
            .cmp(&other.epoch)
            .then(self.price.total_cmp(&other.price))
            .then(other.winner.cmp(&self.winner))
            .is_gt()
    }
}

/// A place: (task, index from 0).
pub(in crate::swarm) type Place = (u32, u32);

/// The void task's one place, held by every robot that stays out ([`Auction::choose`]).
pub(in crate::swarm) const VOID: Place = (u32::MAX, 0);

/// A robot's table in its epoch: per task, the records of places 0..len (later ones
/// are open).
#[derive(Clone)]
pub(in crate::swarm) struct Table {
    pub(in crate::swarm) epoch: u32,
    pub(in crate::swarm) tasks: Vec<Vec<Record>>,
    /// Records held (the table's size on the air).
    pub(in crate::swarm) len: u64,
}

impl Table {
    /// Every place of `m` tasks open in `epoch`.
    pub(in crate::swarm) fn open(epoch: u32, m: usize) -> Table {
        Table {
            epoch,
            tasks: vec![Vec::new(); m],
            len: 0,
        }
    }

    pub(in crate::swarm) fn get(&self, (j, k): Place) -> Record {
        self.tasks[j as usize]
            .get(k as usize)
            .copied()
            .unwrap_or(Record::open(self.epoch))
    }

    pub(in crate::swarm) fn set(&mut self, (j, k): Place, record: Record) {
        let open = Record::open(self.epoch);
        let places = &mut self.tasks[j as usize];
        if places.len() <= k as usize {
            self.len += (k as usize + 1 - places.len()) as u64;
            places.resize(k as usize + 1, open);
        }
        places[k as usize] = record;
    }

    /// The task each robot holds a place of, by this table.
    pub(in crate::swarm) fn partition(&self, n: usize) -> Vec<Option<TaskId>> {
        let mut tasks = vec![None; n];
        for (j, places) in self.tasks.iter().enumerate() {
            for r in places.iter().filter(|r| r.winner != NOBODY) {
                tasks[r.winner as usize] = Some(TaskId(j as u32));
            }
        }
        tasks
    }
}

//! What each robot of a mission knows of the tasks: which have appeared and which are
//! done, learnt by sensing (within a radius) or from a neighbour.

use afg_game::Point;

use super::radio::Radio;

/// Bytes a fact (a task and its state) takes on the air.
const FACT_BYTES: u64 = 5;

/// Each robot's knowledge of the tasks, as two bit sets (appeared, done), and the
/// truth it senses.
pub(super) struct TaskNews {
    words: usize,
    appeared: Vec<u64>,
    done: Vec<u64>,
    /// Within this distance of a task a robot sees it (`None`: every robot hears of
    /// every task the moment it appears or is done).
    sensing: Option<f64>,
    /// Where each task is, and whether it has appeared or is done.
    places: Vec<Point>,
    truth_appeared: Vec<bool>,
    truth_done: Vec<bool>,
}

impl TaskNews {
    /// `n` robots knowing nothing of the tasks at `places`.
    pub fn new(n: usize, places: Vec<Point>, sensing: Option<f64>) -> TaskNews {
        let words = places.len().div_ceil(64).max(1);
        TaskNews {
            words,
            appeared: vec![0; n * words],
            done: vec![0; n * words],
            sensing,
            truth_appeared: vec![false; places.len()],
            truth_done: vec![false; places.len()],
            places,
        }
    }

    fn bit(&self, set: &[u64], robot: u32, task: usize) -> bool {
        set[robot as usize * self.words + task / 64] >> (task % 64) & 1 == 1
    }

    /// Whether `robot` knows `task` has appeared and does not know it is done.
    pub fn knows_open(&self, robot: u32, task: usize) -> bool {
        self.bit(&self.appeared, robot, task) && !self.bit(&self.done, robot, task)
    }

    /// The tasks `robot` knows are done.
    pub fn known_done(&self, robot: u32) -> impl Iterator<Item = usize> + '_ {
        let row = &self.done[robot as usize * self.words..][..self.words];
        row.iter().enumerate().flat_map(|(w, &bits)| {
            (0..64)
                .filter(move |b| bits >> b & 1 == 1)
                .map(move |b| w * 64 + b)
        })
    }

    /// `robot` learns that `task` appeared (and is done, if `done`); whether that was news.
    fn learn(&mut self, robot: u32, task: usize, done: bool) -> bool {
        let (k, mask) = (robot as usize * self.words + task / 64, 1u64 << (task % 64));
        let before = (self.appeared[k], self.done[k]);
        self.appeared[k] |= mask;
        if done {
            self.done[k] |= mask;
        }
        before != (self.appeared[k], self.done[k])
    }

    /// `task` appears (or is done): the robots at `points` that see it learn it.
    /// Returns those for whom it was news.
    pub fn event(&mut self, task: usize, done: bool, points: &[Point]) -> Vec<u32> {
        self.truth_appeared[task] = true;
        self.truth_done[task] |= done;
        let place = self.places[task];
        (0..points.len() as u32)
            .filter(|&i| {
                let sees = self
                    .sensing
                    .is_none_or(|r| points[i as usize].distance(place) <= r);
                sees && self.learn(i, task, done)
            })
            .collect()
    }

    /// The robots at `points` see the tasks within range (robots that moved); returns
    /// those who learnt something.
    pub fn sense(&mut self, points: &[Point]) -> Vec<u32> {
        let Some(range) = self.sensing else {
            return Vec::new();
        };
        let visible: Vec<usize> = (0..self.places.len())
            .filter(|&j| self.truth_appeared[j])
            .collect();
        let mut learnt = Vec::new();
        for (i, p) in points.iter().enumerate() {
            let mut news = false;
            for &j in &visible {
                if p.distance(self.places[j]) <= range {
                    news |= self.learn(i as u32, j, self.truth_done[j]);
                }
            }
            if news {
                learnt.push(i as u32);
            }
        }
        learnt
    }

    /// Every robot up this round tells its neighbours what they lack (over the radio:
    /// lost as any message); returns the robots that learnt something and the bytes.
    pub fn spread<M>(&mut self, radio: &mut Radio<M>) -> (Vec<u32>, u64) {
        if self.sensing.is_none() {
            return (Vec::new(), 0);
        }
        let w = self.words;
        let mut heard: Vec<(u32, u32)> = Vec::new();
        let mut bytes = 0;
        let living: Vec<u32> = radio.living().filter(|&b| radio.up(b)).collect();
        for b in living {
            let links: Vec<(usize, u32)> = radio.out(b).collect();
            for (link, a) in links {
                let (mine, theirs) = (b as usize * w, a as usize * w);
                let lacks: u32 = (0..w)
                    .map(|k| {
                        let new = (self.appeared[mine + k] & !self.appeared[theirs + k])
                            | (self.done[mine + k] & !self.done[theirs + k]);
                        new.count_ones()
                    })
                    .sum();
                if lacks > 0 {
                    bytes += u64::from(lacks) * FACT_BYTES;
                    if radio.delivered(link) {
                        heard.push((b, a));
                    }
                }
            }
        }
        // What each robot said is what it knew at the start of the round.
        let (said_appeared, said_done) = (self.appeared.clone(), self.done.clone());
        let mut learnt = Vec::new();
        for (b, a) in heard {
            let (mine, theirs) = (b as usize * w, a as usize * w);
            let mut news = false;
            for k in 0..w {
                let (ap, dn) = (said_appeared[mine + k], said_done[mine + k]);
                news |= ap & !self.appeared[theirs + k] != 0 || dn & !self.done[theirs + k] != 0;
                self.appeared[theirs + k] |= ap;
                self.done[theirs + k] |= dn;
            }
            if news {
                learnt.push(a);
            }
        }
        (learnt, bytes)
    }
}

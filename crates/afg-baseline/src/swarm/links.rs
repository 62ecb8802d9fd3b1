//! The link layer under the radio: the links in force, with each directed link's loss
//! state, and the channel that decides whether a message is lost and how late it is.

use afg_game::{Point, RobotId};
use afg_graph::{GraphKind, RobotGraph};
use rand::Rng;
use rand_chacha::ChaCha8Rng;

use super::network::{Network, gilbert_elliott};
use crate::AllocError;

/// The links in force: a neighbour list per robot (by original robot id; a crashed
/// robot has none), each directed link with its loss state and whether it crosses the
/// partition line.
pub(super) struct Links {
    offsets: Vec<usize>,
    neighbours: Vec<u32>,
    crossing: Vec<bool>,
    /// Gilbert–Elliott state of each directed link: bad, and the round it was last
    /// drawn at (0 = never).
    bad: Vec<bool>,
    drawn: Vec<u64>,
    /// Messages one round of broadcasts sends when every living robot is awake.
    pub broadcast: u64,
}

impl Links {
    /// The graph of `kind` over the robots in `members` (original ids), connected if
    /// `connect`; returns it with the number of edges added to connect it.
    pub fn build(
        points: &[Point],
        members: &[u32],
        kind: GraphKind,
        split_x: Option<f64>,
        connect: bool,
    ) -> Result<(Links, usize), AllocError> {
        let sub: Vec<Point> = members.iter().map(|&i| points[i as usize]).collect();
        let mut graph = RobotGraph::build(&sub, kind)?;
        let added = if connect {
            graph.connect_components(&sub)
        } else {
            0
        };
        let mut offsets = vec![0; points.len() + 1];
        for (k, &i) in members.iter().enumerate() {
            offsets[i as usize + 1] = graph.degree(RobotId(k as u32));
        }
        for i in 0..points.len() {
            offsets[i + 1] += offsets[i];
        }
        let mut neighbours = vec![0; offsets[points.len()]];
        for (k, &i) in members.iter().enumerate() {
            let start = offsets[i as usize];
            for (slot, &j) in graph.neighbours(RobotId(k as u32)).iter().enumerate() {
                neighbours[start + slot] = members[j as usize];
            }
        }
        let side = |i: u32| split_x.map(|x| points[i as usize].x < x);
        let crossing = (0..points.len() as u32)
            .flat_map(|i| {
                let range = offsets[i as usize]..offsets[i as usize + 1];
                neighbours[range].iter().map(move |&j| side(i) != side(j))
            })
            .collect();
        let len = neighbours.len();
        let links = Links {
            broadcast: len as u64,
            offsets,
            neighbours,
            crossing,
            bad: vec![false; len],
            drawn: vec![0; len],
        };
        Ok((links, added))
    }

    /// The directed links out of `robot`: (link index, neighbour).
    pub fn out(&self, robot: u32) -> impl Iterator<Item = (usize, u32)> + '_ {
        let start = self.offsets[robot as usize];
        let end = self.offsets[robot as usize + 1];
        (start..end).zip(self.neighbours[start..end].iter().copied())
    }

    /// Number of robots each robot hears.
    pub fn degree(&self, robot: u32) -> u64 {
        (self.offsets[robot as usize + 1] - self.offsets[robot as usize]) as u64
    }

    /// Takes over the loss state of every link that `old` also has (robots that move
    /// keep their bursts on the links that stay up); returns the robots whose
    /// neighbours changed. Both graphs' neighbour lists are sorted (no edges added).
    pub fn carry_from(&mut self, old: &Links) -> Vec<u32> {
        let mut changed = Vec::new();
        for robot in 0..self.offsets.len() - 1 {
            let (start, end) = (self.offsets[robot], self.offsets[robot + 1]);
            let (old_start, old_end) = (old.offsets[robot], old.offsets[robot + 1]);
            let new = &self.neighbours[start..end];
            let was = &old.neighbours[old_start..old_end];
            debug_assert!(new.is_sorted() && was.is_sorted());
            if new != was {
                changed.push(robot as u32);
            }
            let mut k = 0;
            for (slot, &to) in new.iter().enumerate() {
                while k < was.len() && was[k] < to {
                    k += 1;
                }
                if k < was.len() && was[k] == to {
                    self.bad[start + slot] = old.bad[old_start + k];
                    self.drawn[start + slot] = old.drawn[old_start + k];
                }
            }
        }
        changed
    }
}

/// Draws the fate of messages: lost or delivered, and when.
pub(super) struct Channel {
    loss: f64,
    /// Gilbert–Elliott (good → bad, bad → good), for bursty loss.
    transitions: Option<(f64, f64)>,
    max_delay: u32,
    partition_until: Option<u64>,
}

impl Channel {
    pub fn new(network: &Network) -> Channel {
        Channel {
            loss: network.loss,
            transitions: network.burst.map(|b| gilbert_elliott(network.loss, b)),
            max_delay: network.max_delay,
            partition_until: network.partition_until,
        }
    }

    /// Whether the message sent over `link` in `round` is lost. Draws nothing on a
    /// lossless channel.
    pub fn lost(&self, links: &mut Links, link: usize, round: u64, rng: &mut ChaCha8Rng) -> bool {
        if links.crossing[link] && self.partition_until.is_some_and(|r| round < r) {
            return true;
        }
        if self.loss == 0.0 {
            return false;
        }
        let Some((to_bad, to_good)) = self.transitions else {
            return rng.random::<f64>() < self.loss;
        };
        // The chance of the bad state `k` rounds after the last draw, in closed form.
        let p_bad = match links.drawn[link] {
            0 => self.loss,
            last => {
                let k = (round - last).min(i32::MAX as u64) as i32;
                let fade = (1.0 - to_bad - to_good).powi(k);
                if links.bad[link] {
                    self.loss + (1.0 - self.loss) * fade
                } else {
                    self.loss * (1.0 - fade)
                }
            }
        };
        let bad = rng.random::<f64>() < p_bad;
        links.bad[link] = bad;
        links.drawn[link] = round;
        bad
    }

    /// Extra rounds a delivered message takes. Draws nothing without delays.
    pub fn delay(&self, rng: &mut ChaCha8Rng) -> u32 {
        if self.max_delay == 0 {
            0
        } else {
            rng.random_range(0..=self.max_delay)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    /// Over many rounds on one link, the loss share and the mean run of losses are the
    /// ones asked for, whether the link is used every round or every third.
    #[test]
    fn gilbert_elliott_gives_the_loss_and_the_burst_length() {
        let points = [Point::new(0.0, 0.0), Point::new(1.0, 0.0)];
        for every in [1u64, 3] {
            let network = Network {
                loss: 0.3,
                burst: Some(5.0),
                ..Network::default()
            };
            let channel = Channel::new(&network);
            let (mut links, _) =
                Links::build(&points, &[0, 1], GraphKind::Complete, None, true).unwrap();
            let mut rng = ChaCha8Rng::seed_from_u64(every);
            let draws: Vec<bool> = (1..=600_000u64)
                .step_by(every as usize)
                .map(|round| channel.lost(&mut links, 0, round, &mut rng))
                .collect();
            let share = draws.iter().filter(|&&l| l).count() as f64 / draws.len() as f64;
            assert!((share - 0.3).abs() < 0.01, "every {every}: loss {share}");
            if every == 1 {
                let runs = draws.windows(2).filter(|w| w[0] && !w[1]).count();
                let mean_run = draws.iter().filter(|&&l| l).count() as f64 / runs as f64;
                assert!((mean_run - 5.0).abs() < 0.2, "mean burst {mean_run}");
            }
        }
        let independent = Channel::new(&Network {
            loss: 0.3,
            ..Network::default()
        });
        let (mut links, _) =
            Links::build(&points, &[0, 1], GraphKind::Complete, None, true).unwrap();
        let mut rng = ChaCha8Rng::seed_from_u64(9);
        let draws: Vec<bool> = (1..=200_000u64)
            .map(|round| independent.lost(&mut links, 0, round, &mut rng))
            .collect();
        let both = draws.windows(2).filter(|w| w[0] && w[1]).count() as f64;
        // Independent losses: a loss follows a loss 30 % of the time, not 80 %.
        let after_loss = both / draws.iter().filter(|&&l| l).count() as f64;
        assert!((after_loss - 0.3).abs() < 0.01, "{after_loss}");
    }

    #[test]
    fn links_keep_original_ids_and_mark_the_crossing() {
        let points = [
            Point::new(0.0, 0.0),
            Point::new(9.0, 9.0),
            Point::new(1.0, 0.0),
            Point::new(2.0, 0.0),
        ];
        // Robot 1 is gone: 0 - 2 - 3 on a line, split between x = 1 and x = 2.
        let (links, added) = Links::build(
            &points,
            &[0, 2, 3],
            GraphKind::Radius { radius: 1.1 },
            Some(1.5),
            true,
        )
        .unwrap();
        assert_eq!(added, 0);
        assert_eq!(links.out(1).count(), 0);
        let of = |i| links.out(i).map(|(_, j)| j).collect::<Vec<_>>();
        assert_eq!((of(0), of(2), of(3)), (vec![2], vec![0, 3], vec![2]));
        let crossing: Vec<bool> = (0..4)
            .flat_map(|i| links.out(i))
            .map(|(l, _)| links.crossing[l])
            .collect();
        assert_eq!(crossing, [false, false, true, true]);
        assert_eq!(links.broadcast, 4);
    }
}

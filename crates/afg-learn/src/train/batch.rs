//! The sampled batches a gradient step learns from: TD transitions with their DQN or
//! Double DQN targets, or states with the exact `Q*` of every task.

use afg_game::{Assignment, RobotId, TaskId};
use afg_graph::{AllocationState, GraphBatch};
use burn::module::AutodiffModule;
use rand::Rng;

use super::Trainer;
use super::replay::Episode;
use crate::env::n_step_reward;
use crate::regret::q_star;
use crate::targets::{double_dqn_target, dqn_target};
use crate::tensors::GraphTensors;
use crate::{InferBackend, LearnError};

impl Trainer {
    /// A sampled batch of states with the exact `Q*` of every task (the run's reward
    /// convention) and 1 where the task has room, 0 where it is full, row-major `[b, M]`.
    pub(super) fn q_star_batch(&mut self) -> Result<(GraphBatch, Vec<f32>, Vec<f32>), LearnError> {
        let (m, b) = (self.config.network.tasks(), self.config.batch);
        let units = self.config.network.units();
        let mut now = self.online.empty_batch(m);
        let mut labels = Vec::with_capacity(b * m);
        let mut allowed = Vec::with_capacity(b * m);
        for _ in 0..b {
            let (e, t) = self.sample_step();
            let ep = &self.replay[e];
            let a = ep.assignment_after(t);
            for value in self.q_star_labels(ep, &a, t)? {
                labels.push(value.unwrap_or(0.0));
                allowed.push(if value.is_some() { 1.0 } else { 0.0 });
            }
            now.push(
                &ep.graph,
                &AllocationState::from_assignment(&ep.instance, a, units),
                RobotId(t as u32),
            );
        }
        Ok((now, labels, allowed))
    }

    /// The exact `Q*(s_t, ·)` of episode `ep`'s step `t`, whose state is `a`, in the
    /// run's reward convention: minus the shaping potential Φ(s) of the run's
    /// [`Shaping`](crate::env::Shaping), divided by the
    /// welfare unit with `reward_scaling`; `None` where the task is full.
    fn q_star_labels(
        &self,
        ep: &Episode,
        a: &Assignment,
        t: usize,
    ) -> Result<Vec<Option<f32>>, LearnError> {
        let offset = -self.config.shaping.potential(&ep.instance, a);
        let unit = self.reward_unit(&ep.instance);
        Ok(q_star(&ep.instance, a, RobotId(t as u32))?
            .into_iter()
            .map(|q| q.map(|v| ((v + offset) / unit) as f32))
            .collect())
    }

    /// A quarter batch (at least one) of empty states of the replay's instances, each
    /// with a uniformly drawn acting robot, and their exact task prices in the
    /// network's welfare unit, centred over the tasks, row-major `[b / 4, M]`
    /// ([`TrainConfig::price_loss`](super::TrainConfig::price_loss)).
    pub(super) fn price_batch(&mut self) -> (GraphBatch, Vec<f32>) {
        let (n, m) = (self.config.robots, self.config.network.tasks());
        let units = self.config.network.units();
        let mut empty = self.online.empty_batch(m);
        let mut prices = Vec::with_capacity(self.config.batch / 4 * m);
        for _ in 0..(self.config.batch / 4).max(1) {
            let ep = &self.replay[self.rng.random_range(0..self.replay.len())];
            let actor = RobotId(self.rng.random_range(0..n) as u32);
            prices.extend_from_slice(ep.centred_prices(units));
            let state =
                AllocationState::from_assignment(&ep.instance, Assignment::unassigned(n, m), units);
            empty.push(&ep.graph, &state, actor);
        }
        (empty, prices)
    }

    /// A uniformly drawn stored step: (episode, robot index). One draw of the run's
    /// generator, whatever the algorithm.
    fn sample_step(&mut self) -> (usize, usize) {
        let n = self.config.robots;
        let k = self.rng.random_range(0..self.replay_len());
        (k / n, k % n)
    }

    /// A uniformly drawn demonstration step: (expert episode, robot index).
    fn sample_demonstration(&mut self) -> (usize, usize) {
        let k = self
            .rng
            .random_range(0..self.demos.len() * self.config.robots);
        (k / self.config.robots, k % self.config.robots)
    }

    /// The target network's Q values of the `next` states, and with `double` the online
    /// network's too (empty otherwise, and both empty for no states).
    fn next_q(&self, next: &GraphBatch, double: bool) -> (Vec<f32>, Vec<f32>) {
        if next.num_graphs() == 0 {
            return (Vec::new(), Vec::new());
        }
        let g = GraphTensors::<InferBackend>::new(next, &Default::default());
        let target: Vec<f32> = self.target.forward(&g).into_data().to_vec().expect("f32");
        let online: Vec<f32> = if double {
            let q = self.online.valid().forward(&g);
            q.into_data().to_vec().expect("f32")
        } else {
            Vec::new()
        };
        (target, online)
    }

    /// A sampled batch of transitions: the states, the actions taken and their DQN
    /// targets, or Double DQN targets with `double`, and how many of them (the last
    /// rows) are demonstrations.
    pub(super) fn td_batch(&mut self, double: bool) -> (GraphBatch, Vec<i64>, Vec<f32>, usize) {
        let (n, m, b) = (
            self.config.robots,
            self.config.network.tasks(),
            self.config.batch,
        );
        let units = self.config.network.units();
        let mut now = self.online.empty_batch(m);
        let mut next = self.online.empty_batch(m);
        let (mut actions, mut rewards, mut next_row) = (
            Vec::with_capacity(b),
            Vec::with_capacity(b),
            Vec::with_capacity(b),
        );
        let experts = match &self.config.demonstrations {
            Some(d) => d.per_batch(b),
            None => 0,
        };
        for row in 0..b {
            let ep = if row < b - experts {
                let (e, t) = self.sample_step();
                (&self.replay[e], t)
            } else {
                let (e, t) = self.sample_demonstration();
                (&self.demos[e], t)
            };
            let (ep, t) = ep;
            let (robot, task) = (RobotId(t as u32), TaskId(u32::from(ep.record.actions[t])));
            let mut a = ep.assignment_after(t);
            now.push(
                &ep.graph,
                &AllocationState::from_assignment(&ep.instance, a.clone(), units),
                robot,
            );
            actions.push(i64::from(task.0));
            // n-step return: the rewards of steps t..end, then bootstrap from s_end.
            let end = (t + self.config.n_step).min(n);
            let taken: Vec<TaskId> = ep.record.actions[t..end]
                .iter()
                .map(|&j| TaskId(u32::from(j)))
                .collect();
            let reward = n_step_reward(&ep.instance, &mut a, t, &taken, self.config.shaping);
            rewards.push((reward / self.reward_unit(&ep.instance)) as f32);
            next_row.push((end < n).then(|| {
                next.push(
                    &ep.graph,
                    &AllocationState::from_assignment(&ep.instance, a, units),
                    RobotId(end as u32),
                );
                next.num_graphs() - 1
            }));
        }
        let (next_target, next_online) = self.next_q(&next, double);
        let targets: Vec<f32> = (0..b)
            .map(|i| match next_row[i] {
                None => rewards[i],
                Some(row) => {
                    let range = row * m..(row + 1) * m;
                    let mask = &next.mask[range.clone()];
                    if double {
                        double_dqn_target(
                            rewards[i],
                            &next_online[range.clone()],
                            &next_target[range],
                            mask,
                            false,
                        )
                    } else {
                        dqn_target(rewards[i], &next_target[range], mask, false)
                    }
                }
            })
            .collect();
        (now, actions, targets, experts)
    }
}

#[cfg(test)]
mod tests {
    use afg_baseline::{Allocator, Optimum};

    use super::*;
    use crate::env::Shaping;
    use crate::qnetwork::NetworkConfig;
    use crate::train::{Algo, TrainConfig};

    /// Checks every step of every episode in the replay buffer of a small `QStar` run.
    fn replay_labels(shaping: Shaping, check: impl Fn(&Episode, usize, f32)) {
        let mut c = TrainConfig::new(7, Algo::QStar, NetworkConfig::afgnet(3, 0), 10, 1);
        (c.shaping, c.reward_scaling, c.validation_instances) = (shaping, false, 2);
        let mut t = Trainer::new(c).unwrap();
        while t.replay.len() < 20 {
            t.act(1.0).unwrap();
        }
        for ep in &t.replay {
            for step in 0..7 {
                let labels = t
                    .q_star_labels(ep, &ep.assignment_after(step), step)
                    .unwrap();
                assert!(
                    labels.iter().all(Option::is_some),
                    "no capacities: never full"
                );
                let best = labels
                    .iter()
                    .flatten()
                    .fold(f32::NEG_INFINITY, |a, &b| a.max(b));
                check(ep, step, best);
            }
        }
    }

    #[test]
    fn unshaped_q_star_labels_start_at_the_optimum() {
        replay_labels(Shaping::None, |ep, step, best| {
            if step == 0 {
                let opt = Optimum.allocate(&ep.instance).unwrap().assignment;
                let opt = ep.instance.welfare(&opt) as f32;
                assert!(
                    (best - opt).abs() < 1e-4 * opt.abs().max(1.0),
                    "{best} vs {opt}"
                );
            }
        });
    }

    #[test]
    fn shaped_q_star_labels_are_what_an_optimal_finish_adds_over_greedy() {
        // Greedy's own first choice completes greedily, so the best label is ≥ 0; the
        // last robot's greedy choice is optimal, so there it is 0.
        replay_labels(Shaping::Greedy, |_, step, best| {
            assert!(best > -1e-4, "step {step}: {best}");
            if step == 6 {
                assert!(best.abs() < 1e-4, "last step: {best}");
            }
        });
    }

    #[test]
    fn optimally_shaped_q_star_labels_are_advantages_with_best_zero() {
        // Φ = V*: the shaped Q* is Q*(s, a) − V*(s), whose maximum is 0 at every state.
        replay_labels(Shaping::Optimal, |_, step, best| {
            assert!(best.abs() < 1e-4, "step {step}: {best}");
        });
    }

    fn with_demonstrations(share: f64, weight: f64) -> TrainConfig {
        let mut c = TrainConfig::new(6, Algo::Ddqn, NetworkConfig::afgnet(3, 0), 60, 2);
        c.validation_instances = 2;
        c.demonstrations = Some(crate::train::Demonstrations {
            episodes: 8,
            share,
            margin: 0.1,
            weight,
        });
        c
    }

    #[test]
    fn demonstrations_follow_the_optimum_on_their_own_instances() {
        let t = Trainer::new(with_demonstrations(0.25, 1.0)).unwrap();
        assert_eq!(t.demos.len(), 8);
        for ep in &t.demos {
            let opt = Optimum.allocate(&ep.instance).unwrap().assignment;
            let shown = ep.assignment_after(6);
            assert!((ep.instance.welfare(&shown) - ep.instance.welfare(&opt)).abs() < 1e-9);
            assert!(ep.record.seed >= (1 << 62) + (1 << 61));
        }
    }

    #[test]
    fn large_margins_by_hand() {
        let mask = [true, false, true, true, true, true];
        assert_eq!(
            super::super::demos::large_margins(&mask, &[2, 0], 3, 0.5),
            vec![0.5, -1e9, 0.0, 0.0, 0.5, 0.5]
        );
    }

    #[test]
    fn the_large_margin_loss_teaches_the_expert_actions() {
        // Share of demonstration states whose greedy action is the expert's.
        let agreement = |t: &Trainer| {
            let net = t.online.valid();
            let device = Default::default();
            let (mut hits, mut total) = (0, 0);
            for ep in &t.demos {
                let mut batch = net.empty_batch(3);
                for step in 0..6 {
                    let state = AllocationState::from_assignment(
                        &ep.instance,
                        ep.assignment_after(step),
                        t.config.network.units(),
                    );
                    batch.push(&ep.graph, &state, RobotId(step as u32));
                }
                let q: Vec<f32> = net
                    .forward(&GraphTensors::new(&batch, &device))
                    .into_data()
                    .to_vec()
                    .unwrap();
                for step in 0..6 {
                    let range = step * 3..(step + 1) * 3;
                    let chosen =
                        crate::targets::masked_argmax(&q[range.clone()], &batch.mask[range]);
                    hits += usize::from(chosen == Some(usize::from(ep.record.actions[step])));
                    total += 1;
                }
            }
            hits as f64 / total as f64
        };
        let trained = |weight: f64| {
            let mut t = Trainer::new(with_demonstrations(0.9, weight)).unwrap();
            let before = agreement(&t);
            while !t.is_finished() {
                t.step().unwrap();
            }
            (before, agreement(&t))
        };
        // The same run (same draws) with and without the margin loss.
        let ((before, with_margin), (_, td_only)) = (trained(10.0), trained(0.0));
        assert!(
            with_margin > before + 0.2 && with_margin > td_only + 0.1,
            "{before} -> {with_margin} (TD only: {td_only})"
        );
    }

    #[test]
    fn bad_demonstrations_are_refused() {
        for (share, weight) in [(0.0, 1.0), (1.0, 1.0), (0.5, -1.0), (0.5, f64::NAN)] {
            assert!(Trainer::new(with_demonstrations(share, weight)).is_err());
        }
        let mut c = with_demonstrations(0.5, 1.0);
        c.algo = Algo::QStar;
        assert!(Trainer::new(c).is_err());
    }
}

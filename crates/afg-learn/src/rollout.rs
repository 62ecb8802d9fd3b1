//! Greedy rollouts of several instances in lockstep: one batched forward pass per step
//! for all unfinished episodes.

use afg_game::{Assignment, Instance, TaskId};
use afg_graph::{GraphKind, RobotGraph};
use burn::tensor::backend::Backend;

use crate::LearnError;
use crate::env::Env;
use crate::qnetwork::QNetwork;
use crate::targets::masked_argmax;
use crate::tensors::GraphTensors;

/// Greedy rollouts: each robot, in index order, takes the allowed task with the highest
/// Q value. Instances may differ in N but must all have the network's M.
///
/// # Errors
/// Graph construction errors, and [`LearnError::InvalidAction`] for an instance whose
/// task count differs from `tasks`.
pub fn greedy_rollouts<B: Backend>(
    network: &QNetwork<B>,
    tasks: usize,
    instances: &[Instance],
    graph: GraphKind,
    device: &B::Device,
) -> Result<Vec<Assignment>, LearnError> {
    if let Some(inst) = instances.iter().find(|i| i.num_tasks() != tasks) {
        return Err(LearnError::InvalidAction(format!(
            "the network was built for M = {tasks} tasks, an instance has {}",
            inst.num_tasks()
        )));
    }
    let graphs = instances
        .iter()
        .map(|i| RobotGraph::build(i.robots(), graph))
        .collect::<Result<Vec<_>, _>>()?;
    let units = network.units();
    let mut envs: Vec<Env<'_>> = instances.iter().map(|i| Env::reset(i, units)).collect();
    loop {
        let live: Vec<usize> = (0..envs.len())
            .filter(|&e| envs[e].actor().is_some())
            .collect();
        if live.is_empty() {
            break;
        }
        let mut batch = network.empty_batch(tasks);
        for &e in &live {
            batch.push(&graphs[e], envs[e].state(), envs[e].actor().expect("live"));
        }
        let q: Vec<f32> = network
            .forward(&GraphTensors::<B>::new(&batch, device))
            .into_data()
            .to_vec()
            .expect("f32 Q values");
        for (row, &e) in live.iter().enumerate() {
            let range = row * tasks..(row + 1) * tasks;
            let task = masked_argmax(&q[range.clone()], &batch.mask[range])
                .expect("capacities leave a task with room");
            envs[e].step(TaskId(task as u32))?;
        }
    }
    Ok(envs
        .into_iter()
        .map(|e| e.state().assignment().clone())
        .collect())
}

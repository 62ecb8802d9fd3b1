//! GRAPE's game (the void task) for the learned allocators: the price model plays it,
//! staying out when every task's `π_a − β d` is below the void's 0; Q networks, trained
//! without a void action, refuse it in one line.

use std::path::{Path, PathBuf};

use afg_baseline::{AllocError, Allocator};
use afg_game::{Assignment, GeneratorConfig, Instance, Point, Task, TaskId};
use afg_graph::{PriceState, TASK_FEATURES};
use afg_learn::price::{PriceMode, PriceModel, PricePolicy};
use afg_learn::run::{ModelOptions, load_model};

fn model(dir: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../models")
        .join(dir)
}

/// A paper instance in GRAPE's game, its robots spread `spread` times as far out, and
/// every task's capacity `capacity`.
fn void_instance(seed: u64, spread: f64, capacity: Option<usize>) -> Instance {
    let inst = GeneratorConfig::paper(60, 5, seed).generate().unwrap();
    let robots = inst
        .robots()
        .iter()
        .map(|p| Point::new(spread * p.x, spread * p.y))
        .collect();
    let tasks = inst
        .tasks()
        .iter()
        .map(|t| Task { capacity, ..*t })
        .collect();
    Instance::with_void(robots, tasks, inst.beta()).unwrap()
}

/// One-shot, replayed here from the model's prices of the empty state: robot by robot,
/// the best `π_a − β d` among tasks with room, or out when that is below 0.
#[test]
fn the_price_model_stays_out_where_no_task_is_worth_it() {
    let path = model("ours/price_n60").join(PriceModel::FILE_NAME);
    let mlp = PriceModel::load(&path).unwrap().mlp;
    let policy = PricePolicy::new(mlp.clone(), PriceMode::OneShot);
    let mut out = 0;
    for seed in 0..6 {
        // Capacities for half the robots, or none; robots far out.
        let capacity = (seed % 2 == 0).then_some(6);
        let inst = void_instance(seed, 4.0, capacity);
        let a = policy.allocate(&inst).unwrap().assignment;
        inst.check(&a).unwrap();
        out += inst.num_robots() - a.num_assigned();
        let state = PriceState::new(&inst);
        let mut features = vec![0.0; inst.num_tasks() * TASK_FEATURES];
        state.features(&mut features);
        let mut prices = vec![0.0; inst.num_tasks()];
        mlp.prices(&features, &mut prices);
        let mut partial = Assignment::unassigned(inst.num_robots(), inst.num_tasks());
        for i in inst.robot_ids() {
            let best = inst
                .task_ids()
                .filter(|&j| partial.has_room(&inst, i, j))
                .map(|j| (j, prices[j.index()] - state.cost(i, j) as f32))
                .fold(None, |b: Option<(TaskId, f32)>, (j, q)| {
                    if b.is_none_or(|(_, bq)| q > bq) {
                        Some((j, q))
                    } else {
                        b
                    }
                });
            let want = best.filter(|&(_, q)| q >= 0.0).map(|(j, _)| j);
            assert_eq!(a.task_of(i), want, "seed {seed}, robot {i}");
            partial.set(i, want);
        }
    }
    assert!(out > 0, "nobody stayed out");
    // The sequential mode plays the game too.
    let options = ModelOptions::default();
    let sequential = load_model(&model("ours/price_n60"), options).unwrap();
    let inst = void_instance(1, 4.0, Some(6));
    let a = sequential.allocate(&inst).unwrap().assignment;
    inst.check(&a).unwrap();
    assert!(a.num_assigned() < inst.num_robots());
}

#[test]
fn q_networks_refuse_the_void_task_in_one_line() {
    let q = load_model(&model("paper/afgnet_ddqn_n60"), ModelOptions::default()).unwrap();
    let err = q.allocate(&void_instance(0, 1.0, None)).unwrap_err();
    assert!(matches!(err, AllocError::VoidNotSupported { .. }), "{err}");
    let line = err.to_string();
    assert!(
        line.contains("paper's game only") && line.contains("void"),
        "{line}"
    );
    assert!(!line.contains('\n'));
}

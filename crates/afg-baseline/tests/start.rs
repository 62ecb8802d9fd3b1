//! The exact team solver given a start: the answer is never worse than it, the proof
//! is the same, and a start of another game is refused in one line.

use std::sync::Arc;
use std::sync::atomic::AtomicBool;

use afg_baseline::{AllocError, Allocator, TeamOptimum};
use afg_game::{Assignment, Family, Instance, TaskId};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// The solver from `start`, stopped before its root (`stop`) or run to the proof.
fn from(start: &Assignment, stop: bool) -> TeamOptimum {
    TeamOptimum {
        start: Some(start.clone()),
        stop: stop.then(|| Arc::new(AtomicBool::new(true))),
        ..TeamOptimum::default()
    }
}

/// A random assignment of `inst` that keeps every capacity (every robot on a task).
fn random_assignment(inst: &Instance, rng: &mut ChaCha8Rng) -> Assignment {
    let mut room: Vec<usize> = inst.task_ids().map(|j| inst.capacity(j)).collect();
    let tasks = (inst.robot_ids())
        .map(|_| {
            let open: Vec<usize> = (0..room.len()).filter(|&j| room[j] > 0).collect();
            let j = open[rng.random_range(0..open.len())];
            room[j] -= 1;
            Some(TaskId(j as u32))
        })
        .collect();
    Assignment::from_tasks(inst, tasks).unwrap()
}

#[test]
fn a_search_stopped_at_once_answers_its_start_and_a_full_one_proves_the_same_optimum() {
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let mut started_better = 0;
    for family in Family::ALL {
        for seed in 0..2u64 {
            let inst = family.config(40, 6, seed).unwrap().generate().unwrap();
            let exact = TeamOptimum::default().solve(&inst).unwrap();
            let at = format!("{family} seed {seed}");
            // Stopped before its root, the search answers its start where the start is
            // better than what the stopped root could build.
            let stopped_alone = TeamOptimum {
                stop: Some(Arc::new(AtomicBool::new(true))),
                ..TeamOptimum::default()
            }
            .solve(&inst)
            .unwrap();
            let stopped = from(&exact.assignment, true).solve(&inst).unwrap();
            assert!((stopped.welfare - exact.welfare).abs() < 1e-9, "{at}");
            assert_eq!(stopped.assignment, exact.assignment, "{at}");
            assert!(stopped.bound >= exact.welfare - 1e-9, "{at}");
            started_better += usize::from(stopped_alone.welfare < exact.welfare - 1e-9);
            // From any start, the proof reaches the optimum (never the start's worse one).
            let start = random_assignment(&inst, &mut rng);
            let proven = from(&start, false).solve(&inst).unwrap();
            assert!(proven.proven, "{at}");
            assert!((proven.welfare - exact.welfare).abs() < 1e-9, "{at}");
            assert!(proven.welfare >= inst.welfare(&start) - 1e-9, "{at}");
            let allocated = from(&start, false).allocate(&inst).unwrap();
            assert!((inst.welfare(&allocated.assignment) - exact.welfare).abs() < 1e-9);
        }
    }
    assert!(
        started_better >= 5,
        "{started_better} of 20 stopped roots below the optimum"
    );
}

#[test]
fn a_start_of_another_game_is_refused_in_one_line() {
    let inst = Family::Skills.config(6, 2, 1).unwrap().generate().unwrap();
    let short = Assignment::from_tasks(
        &Family::Skills.config(5, 2, 1).unwrap().generate().unwrap(),
        vec![Some(TaskId(0)); 5],
    )
    .unwrap();
    let err = from(&short, false).solve(&inst).unwrap_err();
    assert!(matches!(err, AllocError::Game(_)), "{err}");
    let idle = Assignment::from_tasks(
        &inst,
        vec![None, Some(TaskId(0)), Some(TaskId(1)), None, None, None],
    )
    .unwrap();
    let err = from(&idle, false).solve(&inst).unwrap_err();
    assert!(err.to_string().contains("robot 0 on no task"), "{err}");
    // The paper's game is solved without a search, but its start is still checked.
    let paper = afg_game::GeneratorConfig::paper(6, 2, 1)
        .generate()
        .unwrap();
    let err = from(&short, false).allocate(&paper).unwrap_err();
    assert!(matches!(err, AllocError::Game(_)), "{err}");
    // In a game with the void, a robot on no task is a start like any other.
    let void = Family::VoidCapacity
        .config(6, 2, 1)
        .unwrap()
        .generate()
        .unwrap();
    assert!(void.allows_void());
    let none = Assignment::from_tasks(&void, vec![None; 6]).unwrap();
    let best = from(&none, false).solve(&void).unwrap();
    assert!(best.proven && best.welfare >= 0.0);
}

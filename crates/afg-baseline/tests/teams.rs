//! The team-threshold game: the exact solver against brute force and by hand, its
//! bound and gap under a time limit, and what every allocator does with team games.

mod common;

use std::time::Duration;

use afg_baseline::{AllocError, Allocator, Method, Optimum, TeamOptimum, TeamSolution};
use afg_game::{Assignment, Instance, Point, Task, TaskId};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use common::{
    brute_force, scarce, skill_by_hand, skill_by_hand_welfare, small_instance, small_void_instance,
};

/// `inst` with thresholds drawn from 1..=N (so some tasks cannot be staffed together,
/// and some never).
fn with_thresholds(rng: &mut ChaCha8Rng, inst: Instance) -> Instance {
    let n = inst.num_robots();
    let min_team = (0..inst.num_tasks())
        .map(|_| rng.random_range(1..=n + 1))
        .collect();
    inst.with_teams(min_team, &[], &[]).unwrap()
}

/// The solver's answer is the brute-force optimum `brute`, proven: its welfare, its
/// assignment's and its bound.
fn assert_proves(inst: &Instance, best: &TeamSolution, brute: f64, case: usize) {
    let tol = 1e-9 * brute.abs().max(1.0);
    assert!(best.proven && best.gap() == 0.0, "case {case}");
    assert!(
        (best.welfare - brute).abs() < tol,
        "case {case}: {} vs {brute}",
        best.welfare
    );
    assert!(
        (inst.welfare(&best.assignment) - brute).abs() < tol,
        "case {case}"
    );
    assert!(
        (best.bound - brute).abs() < tol,
        "case {case}: bound {}",
        best.bound
    );
}

#[test]
fn the_team_optimum_equals_brute_force_on_small_instances() {
    let mut rng = ChaCha8Rng::seed_from_u64(54);
    for case in 0..300 {
        let plain = if case % 3 == 2 {
            small_void_instance(&mut rng, case)
        } else {
            small_instance(&mut rng, case)
        };
        let inst = with_thresholds(&mut rng, plain);
        let best = TeamOptimum::default().solve(&inst).unwrap();
        let brute = brute_force(&inst);
        let tol = 1e-9 * brute.abs().max(1.0);
        assert_proves(&inst, &best, brute, case);
        inst.check(&best.assignment).unwrap();
        // `opt` solves team games with the same search.
        let opt = Optimum.allocate(&inst).unwrap().assignment;
        assert!((inst.welfare(&opt) - brute).abs() < tol, "case {case}");
    }
}

/// `inst` with thresholds (every second case) and S = 1..=3 binary skills, each task
/// requiring 0..=2 of each.
fn with_skills(rng: &mut ChaCha8Rng, inst: Instance, case: usize) -> Instance {
    let (n, m) = (inst.num_robots(), inst.num_tasks());
    let s = rng.random_range(1..=3);
    let min_team = if case.is_multiple_of(2) {
        (0..m).map(|_| rng.random_range(1..=n.min(4))).collect()
    } else {
        Vec::new()
    };
    let skills: Vec<Vec<u32>> = (0..n)
        .map(|_| (0..s).map(|_| u32::from(rng.random_bool(0.5))).collect())
        .collect();
    let requires: Vec<Vec<u32>> = (0..m)
        .map(|_| (0..s).map(|_| rng.random_range(0..=2)).collect())
        .collect();
    inst.with_teams(min_team, &skills, &requires).unwrap()
}

#[test]
fn the_skill_optimum_equals_brute_force_on_small_instances() {
    let mut rng = ChaCha8Rng::seed_from_u64(55);
    let mut pair_branches = 0;
    for case in 0..300 {
        let plain = if case % 3 == 2 {
            small_void_instance(&mut rng, case)
        } else {
            small_instance(&mut rng, case)
        };
        let inst = with_skills(&mut rng, plain, case);
        let best = TeamOptimum::default().solve(&inst).unwrap();
        assert_proves(&inst, &best, brute_force(&inst), case);
        pair_branches += usize::from(best.nodes > 3);
    }
    // Many searches went past the root and its dive.
    assert!(pair_branches >= 25, "{pair_branches}");
}

#[test]
fn two_robots_needed_by_hand() {
    // Task 0 at the origin needs 2 robots and pays r = 4 (eps = 2: F(2) = 4 log2 3);
    // task 1 at (10, 0) pays 1 to one robot. Robots at (1, 0) and (0, 1).
    let task = |x: f64, reward: f64| Task {
        position: Point::new(x, 0.0),
        reward,
        eps: 2.0,
        capacity: None,
    };
    let robots = vec![Point::new(1.0, 0.0), Point::new(0.0, 1.0)];
    let inst = Instance::new(robots, vec![task(0.0, 4.0), task(10.0, 1.0)], 1.0)
        .unwrap()
        .with_teams(vec![2, 1], &[], &[])
        .unwrap();
    let best = TeamOptimum::default().solve(&inst).unwrap();
    assert_eq!(best.assignment.tasks(), [Some(TaskId(0)); 2]);
    assert!((best.welfare - (4.0 * 3f64.log2() - 2.0)).abs() < 1e-12);
    // With r = 1 the pair is worth log2 3 − 2 < 0 and one robot at task 1 is worth
    // 1 − √101 … still worse: the optimum puts both at task 0 anyway (every robot
    // joins a task), but in GRAPE's game they stay out.
    let robots = vec![Point::new(1.0, 0.0), Point::new(0.0, 1.0)];
    let void = Instance::with_void(robots, vec![task(0.0, 1.0), task(10.0, 1.0)], 1.0)
        .unwrap()
        .with_teams(vec![2, 1], &[], &[])
        .unwrap();
    let best = TeamOptimum::default().solve(&void).unwrap();
    assert_eq!(best.assignment.tasks(), [None, None]);
    assert_eq!(best.welfare, 0.0);
}

/// A skill game (30 robots, 5 tasks, two scarce skills) that takes the exact solver
/// hundreds of nodes: its Lagrangian pricing runs, and a limit that is ignored shows.
fn hard_skill_game() -> Instance {
    let knobs = afg_game::GeneratorKnobs {
        min_team: Some((3, 8)),
        skills: Some(2),
        skill_share: Some(0.2),
        requires: Some((1, 3)),
        ..afg_game::GeneratorKnobs::default()
    };
    knobs.config(30, 5, 4).unwrap().generate().unwrap()
}

#[test]
fn a_time_limit_returns_the_best_found_with_a_certified_bound() {
    for inst in [scarce(100, 10, 3), hard_skill_game()] {
        let exact = TeamOptimum::default().solve(&inst).unwrap();
        assert!(exact.proven);
        let cut = TeamOptimum {
            time_limit: Some(Duration::ZERO),
            ..TeamOptimum::default()
        }
        .solve(&inst)
        .unwrap();
        // A spent limit stops the root's own relaxation where it stands: an answer
        // built from its prices, their Lagrangian bound, and not one node solved.
        assert_eq!(cut.nodes, 0);
        assert!(exact.nodes > cut.nodes && !cut.proven, "{}", exact.nodes);
        assert!((inst.welfare(&cut.assignment) - cut.welfare).abs() < 1e-9);
        assert!(cut.welfare <= exact.welfare + 1e-9);
        assert!(
            cut.bound >= exact.welfare - 1e-9,
            "{} < {}",
            cut.bound,
            exact.welfare
        );
        assert!(
            (cut.gap() - (cut.bound - cut.welfare) / cut.welfare.abs()).abs() < 1e-12,
            "{}",
            cut.gap()
        );
        assert!(cut.gap() > 0.0);
    }
}

/// The states the progress hook was told, in order (the hook is a plain `fn`).
static TOLD: std::sync::Mutex<Vec<afg_baseline::TeamProgress>> = std::sync::Mutex::new(Vec::new());

fn remember(p: &afg_baseline::TeamProgress) {
    TOLD.lock().unwrap().push(*p);
}

#[test]
fn a_gap_target_a_stop_flag_and_the_progress_hook_do_what_they_say() {
    for inst in [scarce(100, 10, 3), hard_skill_game()] {
        let exact = TeamOptimum {
            progress: Some(remember),
            ..TeamOptimum::default()
        }
        .solve(&inst)
        .unwrap();
        // The hook hears every node the search pops: the best found only rises, the
        // bound only falls, and the last state told is no better than the optimum.
        let told = std::mem::take(&mut *TOLD.lock().unwrap());
        assert!(
            told.len() as u64 >= exact.nodes / 3,
            "{} of {}",
            told.len(),
            exact.nodes
        );
        for pair in told.windows(2) {
            assert!(pair[1].welfare >= pair[0].welfare && pair[1].bound <= pair[0].bound + 1e-9);
            assert!(pair[1].seconds >= pair[0].seconds && pair[1].nodes >= pair[0].nodes);
        }
        let last = told.last().unwrap();
        assert!(last.welfare <= exact.welfare + 1e-9 && last.bound >= exact.welfare - 1e-9);

        // A gap target stops as soon as the certified gap reaches it: a loose one
        // before the proof, with a true bound.
        let loose = 0.5 * told.iter().map(|p| p.gap()).fold(0.0, f64::max);
        let near = TeamOptimum::default()
            .stopping(None, Some(loose))
            .unwrap()
            .solve(&inst)
            .unwrap();
        assert!(
            near.nodes < exact.nodes,
            "{} vs {}",
            near.nodes,
            exact.nodes
        );
        assert!(near.gap() <= loose && near.bound >= exact.welfare - 1e-9);
        assert!((inst.welfare(&near.assignment) - near.welfare).abs() < 1e-9);

        // A stop flag already set: as a spent time limit, not one node solved.
        let stop = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(true));
        let stopped = TeamOptimum {
            stop: Some(stop),
            ..TeamOptimum::default()
        }
        .solve(&inst)
        .unwrap();
        assert_eq!(stopped.nodes, 0);
        assert!(!stopped.proven && stopped.bound >= exact.welfare - 1e-9);
    }
}

#[test]
fn the_same_instance_gives_the_same_answer() {
    let inst = scarce(60, 6, 11);
    let a = TeamOptimum::default().solve(&inst).unwrap();
    let b = TeamOptimum::default().solve(&inst).unwrap();
    assert_eq!(a.assignment, b.assignment);
    assert_eq!(
        (a.nodes, a.welfare.to_bits()),
        (b.nodes, b.welfare.to_bits())
    );
}

#[test]
fn a_skill_by_hand_picks_the_robot_that_holds_it() {
    // Robot 2 holds the skill but is further than robots 0 and 1: the optimum takes
    // robots 0 and 2.
    let inst = skill_by_hand();
    let best = TeamOptimum::default().solve(&inst).unwrap();
    let tasks = best.assignment.tasks();
    assert_eq!((tasks[0], tasks[2]), (Some(TaskId(0)), Some(TaskId(0))));
    assert_eq!(tasks[1], Some(TaskId(1)));
    assert!((best.welfare - skill_by_hand_welfare()).abs() < 1e-12);
}

#[test]
fn allocators_play_thresholds_validly_and_skills_or_refuse() {
    let inst = scarce(40, 5, 2);
    let best = TeamOptimum::default().solve(&inst).unwrap().welfare;
    let thresholds = inst.task_ids().map(|j| inst.min_team(j)).collect();
    let skills = inst
        .clone()
        .with_teams(
            thresholds,
            &vec![vec![1]; 40],
            &[vec![1], vec![], vec![], vec![], vec![]],
        )
        .unwrap();
    for method in Method::ALL {
        let allocator = method.allocator(7);
        let a = allocator.allocate(&inst).unwrap().assignment;
        inst.check(&a).unwrap();
        assert!(a.is_complete(), "{method}");
        assert!(inst.welfare(&a) <= best + 1e-9, "{method}");
        match allocator.allocate(&skills) {
            Ok(a) => {
                assert!(
                    matches!(
                        method,
                        Method::Opt | Method::Nearest | Method::Random | Method::Blind
                    ),
                    "{method} played a skill game"
                );
                skills.check(&a.assignment).unwrap();
            }
            Err(err) => assert!(
                matches!(err, AllocError::TeamsNotSupported { .. }),
                "{method}: {err}"
            ),
        }
    }
}

#[test]
fn welfare_counts_a_coalition_only_when_its_team_is_complete() {
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    for case in 0..50 {
        let plain = small_instance(&mut rng, case);
        let inst = with_thresholds(&mut rng, plain);
        let tasks = (0..inst.num_robots())
            .map(|_| Some(TaskId(rng.random_range(0..inst.num_tasks() as u32))))
            .collect();
        let Ok(a) = Assignment::from_tasks(&inst, tasks) else {
            continue;
        };
        let by_hand: f64 = inst
            .task_ids()
            .map(|j| {
                let n = a.size(j);
                if n >= inst.min_team(j) {
                    inst.value_function(j).value(n)
                } else {
                    0.0
                }
            })
            .sum::<f64>()
            - inst
                .robot_ids()
                .map(|i| inst.cost(i, a.task_of(i).unwrap()))
                .sum::<f64>();
        assert!((inst.welfare(&a) - by_hand).abs() < 1e-9);
    }
}

/// The best welfare over every staffing's placement ([`TeamOptimum::staff`]), each
/// placement checked valid and worth what it says, and shown to `check`.
fn best_placed_staffing(inst: &Instance, case: usize, check: impl Fn(&[bool], &Assignment)) -> f64 {
    let m = inst.num_tasks();
    let mut best = f64::NEG_INFINITY;
    for set in 0..1u32 << m {
        let staffed: Vec<bool> = (0..m).map(|j| set >> j & 1 == 1).collect();
        let Some((a, welfare)) = TeamOptimum::staff(inst, &staffed) else {
            continue;
        };
        inst.check(&a).unwrap();
        let tol = 1e-9 * welfare.abs().max(1.0);
        assert!((inst.welfare(&a) - welfare).abs() < tol, "case {case}");
        check(&staffed, &a);
        best = best.max(welfare);
    }
    best
}

/// Placing a staffing is exact: over every set of tasks S, `staff(S)` is an
/// assignment whose tasks of S hold their thresholds and the others do not, worth
/// what it says; the best of them is the brute-force optimum (so the optimum's own
/// staffing is placed at its welfare). The root relaxation bounds the optimum, and a
/// dive (with any rounding) ends at or below it.
#[test]
fn placing_a_staffing_is_exact_and_the_relaxation_bounds_it() {
    let mut rng = ChaCha8Rng::seed_from_u64(77);
    for case in 0..120 {
        let plain = if case % 3 == 2 {
            small_void_instance(&mut rng, case)
        } else {
            small_instance(&mut rng, case)
        };
        let inst = with_thresholds(&mut rng, plain);
        let brute = brute_force(&inst);
        let tol = 1e-9 * brute.abs().max(1.0);
        let best = best_placed_staffing(&inst, case, |staffed, a| {
            for j in inst.task_ids() {
                let full = a.size(j) >= inst.min_team(j);
                assert_eq!(full, staffed[j.index()], "case {case} {staffed:?} task {j}");
            }
        });
        assert!((best - brute).abs() < tol, "case {case}: {best} vs {brute}");
        assert!(
            TeamOptimum::relax(&inst).bound >= brute - tol,
            "case {case}"
        );
        let coin = rng.random::<u64>();
        let (dived, welfare) = TeamOptimum::dive(&inst, |_, fractional| {
            fractional
                .iter()
                .map(|j| (coin >> (j.index() % 64)) & 1 == 1)
                .collect()
        });
        assert!((inst.welfare(&dived) - welfare).abs() < tol && welfare <= brute + tol);
    }
}

#[test]
fn placing_a_staffing_brings_the_skill_its_team_lacks() {
    // Staffing both tasks of `skill_by_hand`, the transport alone sends the two nearest
    // robots to task 0, which lack its skill; the skill dive fixes robot 2 there
    // instead.
    let inst = skill_by_hand();
    let (placed, welfare) = TeamOptimum::staff(&inst, &[true, true]).unwrap();
    assert_eq!(placed.tasks()[2], Some(TaskId(0)));
    assert!(
        (welfare - skill_by_hand_welfare()).abs() < 1e-12,
        "{welfare}"
    );
}

/// On small skill games, every staffing's placement is valid and worth its welfare,
/// and the best of them is the optimum in at least 9 games of 10 (188 of these 200;
/// 155 without the skill dive, which follows one side of the exact solver's skill
/// branching and so may miss).
#[test]
fn placing_staffings_with_skills_nearly_always_reaches_the_optimum() {
    let mut rng = ChaCha8Rng::seed_from_u64(78);
    let mut reached = 0;
    let cases = 200;
    for case in 0..cases {
        let plain = small_instance(&mut rng, case);
        let inst = with_skills(&mut rng, plain, case);
        let brute = brute_force(&inst);
        let tol = 1e-9 * brute.abs().max(1.0);
        let best = best_placed_staffing(&inst, case, |_, _| ());
        assert!(best <= brute + tol, "case {case}");
        reached += usize::from(best >= brute - tol);
    }
    assert!(reached >= cases * 9 / 10, "{reached} of {cases}");
}

/// GRAPE (selfish, over a perfect and a lossy radio) settles on static threshold
/// games, and where it settles every robot is satisfied: no robot prefers another
/// task (Def. 3 with the team game's utilities).
#[test]
fn grape_leaves_every_robot_satisfied_on_threshold_games() {
    use afg_baseline::{Network, Swarm};
    use afg_game::Preference;
    let lossy = Network {
        loss: 0.3,
        ..Network::default()
    };
    for seed in 0..4 {
        let inst = scarce(30, 4, 70 + seed);
        for network in [Network::default(), lossy.clone()] {
            let run = Swarm::grape(Preference::Selfish, network, seed)
                .run(&inst)
                .unwrap();
            let settled = run.assignment.expect("GRAPE settles");
            inst.check(&settled).unwrap();
            assert!(inst.is_stable(&settled, Preference::Selfish), "seed {seed}");
            assert!((inst.welfare(&settled) - run.welfare).abs() < 1e-9);
        }
    }
}

#[test]
fn a_game_too_large_for_memory_is_refused_in_one_line_before_any_is_taken() {
    // 10¹¹ robot–task pairs: terabytes, more than any machine running this has.
    let mut cfg = afg_game::GeneratorConfig::paper(1_000_000, 100_000, 1);
    let paper = cfg.generate().unwrap();
    cfg.min_team = Some(afg_game::CountRange { min: 2, max: 4 });
    let teams = cfg.generate().unwrap();
    let refusals = [
        Optimum.allocate(&paper).unwrap_err(),
        TeamOptimum::default().solve(&teams).unwrap_err(),
    ];
    for err in refusals {
        let text = err.to_string();
        assert!(matches!(err, AllocError::TooLarge { .. }), "{text}");
        assert!(
            text.contains("a 1000000 × 100000 game needs about 5600.1 GB"),
            "{text}"
        );
        assert!(!text.contains('\n'), "{text}");
    }
    assert!(afg_baseline::available_memory().is_some_and(|bytes| bytes > 1 << 20));
}

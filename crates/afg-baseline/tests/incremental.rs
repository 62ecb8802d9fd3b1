//! The optimum kept through events against the optimum from scratch: after every event
//! of random event sequences (tasks appear and are done, robots fail and join), in the
//! paper's game and GRAPE's, with and without capacities, its prices prove its
//! assignment optimal and its welfare is the solve from scratch's.

use afg_baseline::{IncrementalOptimum, Optimum, verify_optimal};
use afg_game::{GOLDEN_RATIO, GeneratorConfig, Instance, Point, RobotId, Task, TaskId};
use proptest::prelude::*;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// A random game: N robots, M tasks, every second case capped (total capacity 1.0–1.5
/// N), and in GRAPE's game with the void where `void`.
fn game(rng: &mut ChaCha8Rng, n: usize, m: usize, capped: bool, void: bool) -> Instance {
    let mut cfg = GeneratorConfig::paper(n, m, rng.random());
    cfg.eps = rng.random_range(GOLDEN_RATIO..8.0);
    cfg.beta = rng.random_range(0.0..3.0);
    if capped {
        cfg = cfg.with_capacity_slack(rng.random_range(1.0..1.5));
    }
    let inst = cfg.generate().unwrap();
    if !void {
        return inst;
    }
    // Robots farther out, so that some places are worth less than staying out.
    let robots = inst
        .robots()
        .iter()
        .map(|p| Point::new(3.0 * p.x, 3.0 * p.y))
        .collect();
    Instance::with_void(robots, inst.tasks().to_vec(), inst.beta()).unwrap()
}

/// A task drawn like the generator's, with a capacity of up to 1.5 N / M where `capped`.
fn new_task(rng: &mut ChaCha8Rng, n: usize, m: usize, capped: bool) -> Task {
    let drawn = GeneratorConfig::paper(1, 1, rng.random())
        .generate()
        .unwrap()
        .tasks()[0];
    Task {
        eps: rng.random_range(GOLDEN_RATIO..8.0),
        capacity: capped.then(|| rng.random_range(1..=(3 * n).div_ceil(2 * m).max(1))),
        ..drawn
    }
}

/// Checks the kept optimum against the game the test expects (its own record of the
/// robots and tasks after each event): the same game, certified by its prices, of the
/// welfare a solve from scratch of that game finds.
fn check(opt: &IncrementalOptimum, expected: &Instance, step: &str) {
    let kept = opt.instance().unwrap();
    assert_eq!(kept.robots(), expected.robots(), "{step}: the robots");
    assert_eq!(kept.tasks(), expected.tasks(), "{step}: the tasks");
    let a = opt.assignment();
    let proof = verify_optimal(expected, &a, &opt.prices())
        .unwrap_or_else(|e| panic!("{step}: not certified: {e}"));
    let (scratch, _) = Optimum.with_prices(expected);
    let best = expected.welfare(&scratch);
    assert!(
        (proof.welfare - best).abs() <= 1e-9 * best.abs().max(1.0),
        "{step}: {} against {best} from scratch",
        proof.welfare
    );
}

/// The game of `robots` and `tasks` with `like`'s β and void.
fn game_of(like: &Instance, robots: &[Point], tasks: &[Task]) -> Instance {
    let (robots, tasks) = (robots.to_vec(), tasks.to_vec());
    if like.allows_void() {
        Instance::with_void(robots, tasks, like.beta()).unwrap()
    } else {
        Instance::new(robots, tasks, like.beta()).unwrap()
    }
}

/// Applies `events` (codes) to the kept optimum of `inst`, checking after each against
/// the robots and tasks the test tracks itself; returns the final assignment's tasks
/// and prices.
fn run(inst: &Instance, seed: u64, events: &[u8], capped: bool) -> (Vec<Option<TaskId>>, Vec<f64>) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut opt = IncrementalOptimum::new(inst);
    let (mut robots, mut tasks) = (inst.robots().to_vec(), inst.tasks().to_vec());
    check(&opt, inst, "the first solve");
    for (e, &code) in events.iter().enumerate() {
        let (n, m) = (robots.len(), tasks.len());
        let step = format!("event {e} (code {code}, N = {n}, M = {m})");
        let (mut next_robots, mut next_tasks) = (robots.clone(), tasks.clone());
        let done = match code % 4 {
            0 => {
                let task = new_task(&mut rng, n, m, capped);
                next_tasks.push(task);
                opt.add_task(task)
                    .map(|id| assert_eq!(id, TaskId(m as u32), "{step}"))
            }
            1 => {
                let j = rng.random_range(0..m);
                next_tasks.remove(j);
                opt.remove_task(TaskId(j as u32))
            }
            2 => {
                let k = rng.random_range(1..=n.div_ceil(10));
                let mut ids: Vec<u32> = (0..n as u32).collect();
                let (gone, _) = ids.partial_shuffle(&mut rng, k);
                let gone: Vec<RobotId> = gone.iter().map(|&r| RobotId(r)).collect();
                next_robots = (0..n)
                    .filter(|&i| !gone.contains(&RobotId(i as u32)))
                    .map(|i| robots[i])
                    .collect();
                opt.remove_robots(&gone)
            }
            _ => {
                let k = rng.random_range(1..=n.div_ceil(10));
                let spots: Vec<Point> = (0..k)
                    .map(|_| Point::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0)))
                    .collect();
                next_robots.extend(&spots);
                opt.add_robots(&spots)
            }
        };
        // Refused events (the last task, the last robots, no room left) leave the game
        // as it was; no other event is refused (a kept optimum that refused every
        // event would fail here).
        match done {
            Ok(_) => (robots, tasks) = (next_robots, next_tasks),
            Err(err) => {
                let room = (next_tasks.iter())
                    .map(|t| t.capacity.unwrap_or(usize::MAX))
                    .fold(0usize, usize::saturating_add);
                let crowded = !inst.allows_void() && room < next_robots.len();
                let why = match code % 4 {
                    1 => m == 1 || crowded,
                    2 => next_robots.is_empty(),
                    3 => crowded,
                    _ => false,
                };
                assert!(why, "{step}: refused ({err})");
            }
        }
        assert_eq!(
            (opt.num_robots(), opt.num_tasks()),
            (robots.len(), tasks.len()),
            "{step}"
        );
        check(&opt, &game_of(inst, &robots, &tasks), &step);
    }
    (opt.assignment().tasks().to_vec(), opt.prices())
}

use rand::seq::SliceRandom;

proptest! {
    #![proptest_config(ProptestConfig::with_cases(40))]

    /// Every event of a random sequence leaves the certified optimum.
    #[test]
    fn kept_optimum_equals_the_optimum_from_scratch_after_every_event(
        seed in any::<u64>(),
        n in 2usize..400,
        m in 1usize..9,
        capped in any::<bool>(),
        void in any::<bool>(),
        events in prop::collection::vec(any::<u8>(), 1..12),
    ) {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let inst = game(&mut rng, n, m, capped, void);
        run(&inst, seed, &events, capped);
    }
}

/// Large enough for the subsample levels of the first solve (N ≥ 2 048), then events.
#[test]
fn kept_optimum_after_events_on_a_multi_level_solve() {
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    for (case, void) in [(0, false), (1, true)] {
        let inst = game(&mut rng, 5_000, 12, case == 1, void);
        run(&inst, case, &[0, 1, 2, 3, 0, 0, 1, 2], case == 1);
    }
}

/// The same game and events give the same assignment and prices.
#[test]
fn the_same_events_give_the_same_optimum() {
    let mut rng = ChaCha8Rng::seed_from_u64(6);
    let inst = game(&mut rng, 300, 5, true, false);
    let events = [0, 2, 1, 3, 0, 2];
    assert_eq!(run(&inst, 9, &events, true), run(&inst, 9, &events, true));
}

/// Bad events are refused with a clear error and change nothing.
#[test]
fn bad_events_are_refused() {
    let inst = GeneratorConfig::paper(20, 2, 1)
        .with_capacity_slack(1.0)
        .generate()
        .unwrap();
    let mut opt = IncrementalOptimum::new(&inst);
    let err = |e: afg_baseline::AllocError| e.to_string();
    assert!(err(opt.remove_task(TaskId(2)).unwrap_err()).contains("not a task"));
    assert!(err(opt.remove_task(TaskId(0)).unwrap_err()).contains("room for"));
    let twice = opt.remove_robots(&[RobotId(1), RobotId(1)]).unwrap_err();
    assert!(err(twice).contains("named twice"));
    let all: Vec<RobotId> = inst.robot_ids().collect();
    assert!(err(opt.remove_robots(&all).unwrap_err()).contains("needs a robot"));
    assert!(err(opt.add_robots(&[Point::new(0.0, 0.0)]).unwrap_err()).contains("room for"));
    let bad = Task {
        eps: 1.0,
        ..inst.tasks()[0]
    };
    assert!(opt.add_task(bad).is_err());
    assert_eq!((opt.num_robots(), opt.num_tasks()), (20, 2));
    let one = IncrementalOptimum::new(&GeneratorConfig::paper(5, 1, 1).generate().unwrap());
    let mut one = one;
    assert!(err(one.remove_task(TaskId(0)).unwrap_err()).contains("its last"));
    check(&opt, &inst, "after the refusals");
}

//! OPT against brute force: the optimum, its completions, action values and prices,
//! the price-based optimum across levels and its certificates.

mod common;

use afg_baseline::{AllocError, Allocator, Optimum, verify_optimal};
use afg_game::{Assignment, GOLDEN_RATIO, GeneratorConfig, Instance, RobotId, TaskId};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use common::{
    brute_force, brute_force_completion, brute_force_fixing, into_void, small_instance,
    small_void_instance,
};

#[test]
fn opt_equals_brute_force_on_small_instances() {
    let mut rng = ChaCha8Rng::seed_from_u64(2024);
    for case in 0..1200 {
        let inst = small_instance(&mut rng, case);
        let opt = Optimum.allocate(&inst).unwrap().assignment;
        inst.check(&opt).unwrap();
        assert!(opt.is_complete());
        let (got, want) = (inst.welfare(&opt), brute_force(&inst));
        assert!(
            (got - want).abs() < 1e-9 * want.abs().max(1.0),
            "case {case}: OPT {got} vs brute force {want}"
        );
    }
}

#[test]
fn completion_equals_brute_force_with_fixed_prefixes() {
    let mut rng = ChaCha8Rng::seed_from_u64(2025);
    for case in 0..1200 {
        let inst = small_instance(&mut rng, case);
        let k = rng.random_range(0..=inst.num_robots());
        let partial = random_prefix(&mut rng, &inst, k);
        let done = Optimum.complete(&inst, &partial).unwrap();
        inst.check(&done).unwrap();
        assert!(done.is_complete());
        for i in inst.robot_ids() {
            if let Some(j) = partial.task_of(i) {
                assert_eq!(
                    done.task_of(i),
                    Some(j),
                    "case {case}: fixed robot {i} moved"
                );
            }
        }
        let (got, want) = (inst.welfare(&done), brute_force_completion(&inst, &partial));
        assert!(
            (got - want).abs() < 1e-9 * want.abs().max(1.0),
            "case {case}: completion {got} vs brute force {want}"
        );
    }
}

/// A random prefix of robots 0..k on random tasks with room, as in the MDP (where every
/// task is full, in GRAPE's game, the robot stays free).
fn random_prefix(rng: &mut ChaCha8Rng, inst: &Instance, k: usize) -> Assignment {
    let mut partial = Assignment::unassigned(inst.num_robots(), inst.num_tasks());
    for i in 0..k {
        let robot = RobotId(i as u32);
        let open: Vec<TaskId> = inst
            .task_ids()
            .filter(|&j| partial.has_room(inst, robot, j))
            .collect();
        if !open.is_empty() {
            partial.set(robot, Some(open[rng.random_range(0..open.len())]));
        }
    }
    partial
}

/// `Optimum::action_values`, one completion for all tasks, against brute force on
/// small instances and against one completion per task on larger ones.
#[test]
fn action_values_equal_one_completion_per_task() {
    let mut rng = ChaCha8Rng::seed_from_u64(2027);
    let close = |a: f64, b: f64| (a - b).abs() < 1e-9 * b.abs().max(1.0);
    for case in 0..1200 {
        let inst = small_instance(&mut rng, case);
        let n = inst.num_robots();
        let t = rng.random_range(0..n);
        let partial = random_prefix(&mut rng, &inst, t);
        let actor = RobotId(t as u32);
        let values = Optimum.action_values(&inst, &partial, actor).unwrap();
        for j in inst.task_ids() {
            let want = partial.has_room(&inst, actor, j).then(|| {
                let mut forced = partial.clone();
                forced.set(actor, Some(j));
                brute_force_completion(&inst, &forced)
            });
            match (values[j.index()], want) {
                (Some(got), Some(want)) => assert!(
                    close(got, want),
                    "case {case}, task {j}: {got} vs brute force {want}"
                ),
                (got, want) => assert_eq!(got, want, "case {case}, task {j}"),
            }
        }
    }
    for case in 0..40 {
        let (n, m) = (rng.random_range(20..200), rng.random_range(2..30));
        let mut cfg = GeneratorConfig::paper(n, m, case);
        if case % 2 == 1 {
            cfg = cfg.with_capacity_slack(1.1);
        }
        let inst = cfg.generate().unwrap();
        let t = rng.random_range(0..n);
        let partial = random_prefix(&mut rng, &inst, t);
        let actor = RobotId(t as u32);
        let values = Optimum.action_values(&inst, &partial, actor).unwrap();
        for j in inst.task_ids() {
            let mut forced = partial.clone();
            forced.set(actor, Some(j));
            let want = partial
                .has_room(&inst, actor, j)
                .then(|| inst.welfare(&Optimum.complete(&inst, &forced).unwrap()));
            match (values[j.index()], want) {
                (Some(got), Some(want)) => assert!(
                    close(got, want),
                    "N = {n}, M = {m}, task {j}: {got} vs {want}"
                ),
                (got, want) => assert_eq!(got, want, "N = {n}, M = {m}, task {j}"),
            }
        }
    }
    // Bad input is an error, not a panic.
    let inst = GeneratorConfig::paper(5, 2, 0).generate().unwrap();
    let mut partial = Assignment::unassigned(5, 2);
    partial.set(RobotId(0), Some(TaskId(1)));
    for actor in [RobotId(0), RobotId(5)] {
        assert!(Optimum.action_values(&inst, &partial, actor).is_err());
    }
    assert!(
        Optimum
            .action_values(&inst, &Assignment::unassigned(4, 2), RobotId(1))
            .is_err()
    );
}

#[test]
fn prices_reproduce_the_optimum_up_to_ties() {
    let mut rng = ChaCha8Rng::seed_from_u64(2026);
    let (mut robots, mut unique) = (0usize, 0usize);
    for case in 0..400 {
        let n = rng.random_range(1..=80);
        let m = rng.random_range(1..=6);
        let mut cfg = GeneratorConfig::paper(n, m, rng.random());
        cfg.eps = rng.random_range(1.62..12.0);
        cfg.beta = rng.random_range(0.1..3.0);
        if case % 2 == 1 {
            cfg = cfg.with_capacity_slack(rng.random_range(1.0..1.5));
        }
        let inst = cfg.generate().unwrap();
        let (opt, prices) = Optimum.with_prices(&inst);
        let best = inst.welfare(&Optimum.allocate(&inst).unwrap().assignment);
        assert!((inst.welfare(&opt) - best).abs() < 1e-9 * best.abs().max(1.0));
        for i in inst.robot_ids() {
            let value = |j: TaskId| inst.cost(i, j) - prices[j.index()];
            let own = value(opt.task_of(i).unwrap());
            let mut others: Vec<f64> = inst
                .task_ids()
                .filter(|&j| Some(j) != opt.task_of(i))
                .map(value)
                .collect();
            others.sort_by(f64::total_cmp);
            // Every robot sits at a minimum of β d − π ...
            assert!(
                others.first().is_none_or(|&o| own <= o + 1e-9),
                "case {case}"
            );
            // ... and where the minimum is unique, argmin alone puts it there.
            robots += 1;
            unique += usize::from(others.first().is_none_or(|&o| own < o - 1e-9));
        }
    }
    // Ties are the exception (a price is set by a robot indifferent between two tasks).
    assert!(
        unique * 10 > robots * 8,
        "{unique} of {robots} robots decided by price alone"
    );
}

#[test]
fn completion_rejects_a_partial_assignment_of_another_shape_or_over_capacity() {
    let inst = GeneratorConfig::paper(6, 2, 1)
        .with_capacity_slack(1.0)
        .generate()
        .unwrap();
    assert!(
        Optimum
            .complete(&inst, &Assignment::unassigned(5, 2))
            .is_err()
    );
    assert!(
        Optimum
            .complete(&inst, &Assignment::unassigned(6, 3))
            .is_err()
    );
    // Capacities of ⌈6 / 2⌉ = 3 each: four robots on task 0 are over capacity.
    assert_eq!(inst.capacity(TaskId(0)), 3);
    let mut over = Assignment::unassigned(6, 2);
    for i in 0..4 {
        over.set(RobotId(i), Some(TaskId(0)));
    }
    let err = Optimum.complete(&inst, &over).unwrap_err().to_string();
    assert!(err.contains("above its capacity 3"), "{err}");
}

/// An instance of `n` robots for the multi-scale solver: any eps ≥ φ and β, every
/// second case with capacities, every third with the robots on a 10 × 10 grid (many
/// robots at one spot: exact ties between robots at every level).
fn scaled_instance(rng: &mut ChaCha8Rng, case: usize, n: usize, m: usize) -> Instance {
    let mut cfg = GeneratorConfig::paper(n, m, rng.random());
    cfg.eps = rng.random_range(GOLDEN_RATIO..12.0);
    cfg.beta = rng.random_range(0.05..3.0);
    if case % 2 == 1 {
        cfg = cfg.with_capacity_slack(rng.random_range(1.0..1.3));
    }
    let inst = cfg.generate().unwrap();
    if case % 3 != 2 {
        return inst;
    }
    let snap = |v: f64| (v * 10.0).round() / 10.0;
    let robots = inst
        .robots()
        .iter()
        .map(|p| afg_game::Point::new(snap(p.x), snap(p.y)))
        .collect();
    Instance::new(robots, inst.tasks().to_vec(), inst.beta()).unwrap()
}

/// The optimum from prices (subsample levels from N = 2 048 on) reaches the robot by
/// robot reference's welfare, and its prices prove it.
#[test]
fn optimum_from_prices_equals_the_reference_across_levels() {
    let mut rng = ChaCha8Rng::seed_from_u64(30);
    for case in 0..24 {
        let n = rng.random_range(300..=4_000);
        let m = rng.random_range(1..=24);
        let inst = scaled_instance(&mut rng, case, n, m);
        let (opt, prices) = Optimum.with_prices(&inst);
        let empty = Assignment::unassigned(n, m);
        let reference = inst.welfare(&Optimum.complete(&inst, &empty).unwrap());
        let got = inst.welfare(&opt);
        assert!(
            (got - reference).abs() <= 1e-9 * reference.abs().max(1.0),
            "case {case} (N = {n}, M = {m}): {got} vs reference {reference}"
        );
        let proof = verify_optimal(&inst, &opt, &prices).unwrap();
        assert_eq!(proof.welfare, got);
    }
}

/// Weak duality, checked against brute force: whatever the assignment and the prices,
/// the certificate's bound is at least the optimum, so an accepted assignment is
/// optimal; and the solver's own prices are always accepted.
#[test]
fn certificates_bound_the_optimum_and_accept_only_optima() {
    let mut rng = ChaCha8Rng::seed_from_u64(31);
    let mut rejected = 0;
    for case in 0..600 {
        let inst = small_instance(&mut rng, case);
        let (n, m) = (inst.num_robots(), inst.num_tasks());
        let best = brute_force(&inst);
        let tol = 1e-9 * best.abs().max(1.0);
        let (opt, prices) = Optimum.with_prices(&inst);
        assert!(verify_optimal(&inst, &opt, &prices).is_ok(), "case {case}");
        let tasks = (0..n)
            .map(|_| Some(TaskId(rng.random_range(0..m as u32))))
            .collect();
        let Ok(any) = Assignment::from_tasks(&inst, tasks) else {
            continue;
        };
        let shaken: Vec<f64> = prices
            .iter()
            .map(|p| p + rng.random_range(-1.0..1.0) * f64::from(u8::from(case % 2 == 0)))
            .collect();
        match verify_optimal(&inst, &any, &shaken) {
            Ok(proof) => assert!(
                proof.welfare >= best - tol,
                "case {case}: accepted below OPT"
            ),
            Err(AllocError::NotOptimal { upper_bound, .. }) => {
                assert!(upper_bound >= best - tol, "case {case}: bound below OPT");
                rejected += 1;
            }
            Err(e) => panic!("case {case}: {e}"),
        }
    }
    assert!(rejected > 100, "only {rejected} rejections");
}

#[test]
fn certificate_rejects_inputs_that_do_not_fit() {
    let inst = GeneratorConfig::paper(10, 3, 5).generate().unwrap();
    let (opt, prices) = Optimum.with_prices(&inst);
    assert!(verify_optimal(&inst, &opt, &prices[..2]).is_err());
    assert!(verify_optimal(&inst, &opt, &[0.0, f64::NAN, 0.0]).is_err());
    let mut partial = opt.clone();
    partial.set(RobotId(0), None);
    assert!(verify_optimal(&inst, &partial, &prices).is_err());
    // The same one-line error for starting prices that do not fit.
    let err = Optimum.with_prices_from(&inst, &prices[..2]).unwrap_err();
    assert_eq!(
        err.to_string(),
        "invalid parameter: need 3 finite task prices, got [".to_owned()
            + &format!("{}, {}]", prices[0], prices[1])
    );
    assert!(
        Optimum
            .with_prices_from(&inst, &[0.0, f64::INFINITY, 0.0])
            .is_err()
    );
}

/// The same instance gives the same optimum and prices, bit for bit, on one core or all.
#[test]
fn optimum_from_prices_is_deterministic() {
    let inst = GeneratorConfig::paper(20_000, 12, 4).generate().unwrap();
    let (a, p) = Optimum.with_prices(&inst);
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let (b, q) = one.install(|| Optimum.with_prices(&inst));
    assert_eq!(a, b);
    assert_eq!(p, q);
}

/// GRAPE's game against brute force over the (M + 1)^N assignments: the optimum (from
/// prices and robot by robot), its certificate, the completions and the action values
/// with the void as one more action; and the void is used.
#[test]
fn optimum_with_the_void_equals_brute_force() {
    let mut rng = ChaCha8Rng::seed_from_u64(2030);
    let close = |a: f64, b: f64| (a - b).abs() < 1e-9 * b.abs().max(1.0);
    let mut stayed_out = 0;
    for case in 0..800 {
        let inst = small_void_instance(&mut rng, case);
        let (n, m) = (inst.num_robots(), inst.num_tasks());
        let best = brute_force(&inst);
        let (opt, prices) = Optimum.with_prices(&inst);
        assert!(
            close(inst.welfare(&opt), best),
            "case {case}: {} vs {best}",
            inst.welfare(&opt)
        );
        verify_optimal(&inst, &opt, &prices).unwrap();
        let empty = Assignment::unassigned(n, m);
        let reference = Optimum.complete(&inst, &empty).unwrap();
        assert!(
            close(inst.welfare(&reference), best),
            "case {case}: reference"
        );
        stayed_out += usize::from(opt.num_assigned() < n);
        // Robots 0..t fixed on random tasks (none stays out: unassigned is free).
        let t = rng.random_range(0..n);
        let partial = random_prefix(&mut rng, &inst, t);
        let done = Optimum.complete(&inst, &partial).unwrap();
        assert!(close(
            inst.welfare(&done),
            brute_force_completion(&inst, &partial)
        ));
        let actor = RobotId(t as u32);
        let values = Optimum.action_values(&inst, &partial, actor).unwrap();
        assert_eq!(values.len(), m + 1);
        for (a, got) in values.iter().enumerate() {
            let want = if a == m {
                Some(brute_force_fixing(&inst, &partial, Some(actor)))
            } else {
                let j = TaskId(a as u32);
                partial.has_room(&inst, actor, j).then(|| {
                    let mut forced = partial.clone();
                    forced.set(actor, Some(j));
                    brute_force_completion(&inst, &forced)
                })
            };
            match (*got, want) {
                (Some(got), Some(want)) => {
                    assert!(close(got, want), "case {case}, action {a}: {got} vs {want}")
                }
                (got, want) => assert_eq!(got, want, "case {case}, action {a}"),
            }
        }
    }
    assert!(
        stayed_out > 200,
        "the void was used in {stayed_out} cases only"
    );
}

/// Weak duality in GRAPE's game: any assignment (robots out included) and any prices
/// give a bound at least the brute-forced optimum; zero prices start the solver from
/// the nearest places and still reach it.
#[test]
fn certificates_with_the_void_bound_the_optimum() {
    let mut rng = ChaCha8Rng::seed_from_u64(2031);
    let mut rejected = 0;
    for case in 0..400 {
        let inst = small_void_instance(&mut rng, case);
        let (n, m) = (inst.num_robots(), inst.num_tasks());
        let best = brute_force(&inst);
        let tol = 1e-9 * best.abs().max(1.0);
        let (cold, prices) = Optimum.with_prices_from(&inst, &vec![0.0; m]).unwrap();
        assert!((inst.welfare(&cold) - best).abs() <= tol, "case {case}");
        verify_optimal(&inst, &cold, &prices).unwrap();
        let tasks = (0..n)
            .map(|_| {
                let j = rng.random_range(0..=m as u32);
                (j < m as u32).then_some(TaskId(j))
            })
            .collect();
        let Ok(any) = Assignment::from_tasks(&inst, tasks) else {
            continue;
        };
        let shaken: Vec<f64> = prices
            .iter()
            .map(|p| p + rng.random_range(-1.0..1.0))
            .collect();
        match verify_optimal(&inst, &any, &shaken) {
            Ok(proof) => assert!(
                proof.welfare >= best - tol,
                "case {case}: accepted below OPT"
            ),
            Err(AllocError::NotOptimal { upper_bound, .. }) => {
                assert!(upper_bound >= best - tol, "case {case}: bound below OPT");
                rejected += 1;
            }
            Err(e) => panic!("case {case}: {e}"),
        }
    }
    assert!(rejected > 100, "only {rejected} rejections");
}

/// In GRAPE's game the optimum from prices (subsample levels from N = 2 048 on) reaches
/// the robot by robot reference, and its prices prove it.
#[test]
fn optimum_with_the_void_across_levels() {
    let mut rng = ChaCha8Rng::seed_from_u64(32);
    for case in 0..16 {
        let n = rng.random_range(300..=4_000);
        let m = rng.random_range(1..=24);
        let paper = scaled_instance(&mut rng, case, n, m);
        let inst = into_void(&mut rng, case, &paper);
        let (opt, prices) = Optimum.with_prices(&inst);
        let empty = Assignment::unassigned(n, m);
        let reference = inst.welfare(&Optimum.complete(&inst, &empty).unwrap());
        let got = inst.welfare(&opt);
        assert!(
            (got - reference).abs() <= 1e-9 * reference.abs().max(1.0),
            "case {case} (N = {n}, M = {m}): {got} vs reference {reference}"
        );
        verify_optimal(&inst, &opt, &prices).unwrap();
    }
}

//! OPT against brute force, every method against OPT, the dynamics' guarantees.

use std::path::PathBuf;

use afg_baseline::{
    AllocError, Allocator, Blind, CentralisedDa, DecentralisedDa, Method, Optimum, verify_optimal,
};
use afg_game::io::read_dataset;
use afg_game::{Assignment, GOLDEN_RATIO, GeneratorConfig, Instance, Preference, RobotId, TaskId};
use afg_graph::{GraphKind, RobotGraph};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn dataset(n: usize) -> Vec<Instance> {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(format!("../../datasets/n{n}.jsonl"));
    read_dataset(&path).expect("committed dataset")
}

/// The best welfare over all M^N assignments that respect capacities.
fn brute_force(inst: &Instance) -> f64 {
    brute_force_completion(
        inst,
        &Assignment::unassigned(inst.num_robots(), inst.num_tasks()),
    )
}

/// The best welfare over all complete assignments that respect capacities and keep
/// the robots assigned in `partial` where they are.
fn brute_force_completion(inst: &Instance, partial: &Assignment) -> f64 {
    let (n, m) = (inst.num_robots(), inst.num_tasks());
    let mut best = f64::NEG_INFINITY;
    let mut code = vec![0usize; n];
    'outer: loop {
        let tasks = code
            .iter()
            .enumerate()
            .map(|(i, &j)| {
                partial
                    .task_of(RobotId(i as u32))
                    .or(Some(TaskId(j as u32)))
            })
            .collect();
        if let Ok(a) = Assignment::from_tasks(inst, tasks) {
            best = best.max(inst.welfare(&a));
        }
        for digit in code.iter_mut() {
            *digit += 1;
            if *digit < m {
                continue 'outer;
            }
            *digit = 0;
        }
        return best;
    }
}

/// A random instance small enough for brute force (N ≤ 7, M ≤ 4), any eps ≥ φ and
/// beta; every second case with tight capacities (total just above N, so many tasks
/// are full). One case in four has eps = φ exactly, where F_j(2) = 2 F_j(1): the first
/// two members of a task are worth the same, so the balanced scores of joining an
/// empty task and a task of one tie (and so do the selfish utilities), and one in eight
/// has β = 0 as well, where every task ties on cost.
fn small_instance(rng: &mut ChaCha8Rng, case: usize) -> Instance {
    let n = rng.random_range(1..=7);
    let m = rng.random_range(1..=4);
    let mut cfg = GeneratorConfig::paper(n, m, rng.random());
    cfg.eps = rng.random_range(1.62..6.0);
    cfg.beta = rng.random_range(0.0..3.0);
    if case % 4 >= 2 {
        cfg.eps = GOLDEN_RATIO;
    }
    if case % 8 == 3 {
        cfg.beta = 0.0;
    }
    if case % 2 == 1 {
        cfg = cfg.with_capacity_slack(rng.random_range(1.0..1.5));
    }
    cfg.generate().unwrap()
}

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

/// A random prefix of robots 0..k on random tasks with room, as in the MDP.
fn random_prefix(rng: &mut ChaCha8Rng, inst: &Instance, k: usize) -> Assignment {
    let mut partial = Assignment::unassigned(inst.num_robots(), inst.num_tasks());
    for i in 0..k {
        let robot = RobotId(i as u32);
        let open: Vec<TaskId> = inst
            .task_ids()
            .filter(|&j| partial.has_room(inst, robot, j))
            .collect();
        partial.set(robot, Some(open[rng.random_range(0..open.len())]));
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

/// Checks every method on one instance: valid, complete, capacity-respecting, ≤ OPT,
/// and OPT balanced-stable. Returns OPT's welfare.
fn check_all_methods(inst: &Instance) -> f64 {
    let opt = Optimum.allocate(inst).unwrap().assignment;
    let best = inst.welfare(&opt);
    assert!(
        inst.is_stable(&opt, Preference::Balanced),
        "Lemma 1: OPT is balanced-stable"
    );
    for method in Method::ALL {
        let a = method.allocator(1).allocate(inst).unwrap().assignment;
        inst.check(&a).unwrap();
        assert!(a.is_complete(), "{method}");
        let w = inst.welfare(&a);
        assert!(
            w <= best + 1e-9 * best.abs().max(1.0),
            "{method}: {w} above OPT {best}"
        );
    }
    best
}

#[test]
fn opt_dominates_every_method_on_the_table_datasets() {
    for n in [20, 60, 100] {
        for inst in dataset(n) {
            check_all_methods(&inst);
        }
    }
}

#[test]
fn opt_dominates_the_centralised_methods_at_scale() {
    for n in [500, 1000] {
        for inst in &dataset(n) {
            let best = inst.welfare(&Optimum.allocate(inst).unwrap().assignment);
            for method in [
                Method::Da,
                Method::DaBalanced,
                Method::Greedy,
                Method::Nearest,
                Method::Random,
            ] {
                let a = method.allocator(1).allocate(inst).unwrap().assignment;
                assert!(inst.welfare(&a) <= best + 1e-9 * best.abs());
            }
        }
    }
}

#[test]
fn capacities_are_respected_by_every_method() {
    for seed in 0..30 {
        let inst = GeneratorConfig::paper(40, 5, seed)
            .with_capacity_slack(1.2)
            .generate()
            .unwrap();
        check_all_methods(&inst);
    }
    let inst = GeneratorConfig::paper(40, 5, 3)
        .with_capacity_slack(1.0)
        .generate()
        .unwrap();
    let opt = Optimum.allocate(&inst).unwrap().assignment;
    assert!(
        inst.task_ids().all(|j| opt.size(j) == inst.capacity(j)),
        "capacities sum to N: all full"
    );
}

#[test]
fn dynamics_end_stable_within_the_grape_bound_and_twins_agree() {
    for n in [20, 60, 100] {
        let bound = (n * (n + 1) / 2) as u64;
        for (idx, inst) in dataset(n).iter().enumerate() {
            for pref in [Preference::Selfish, Preference::Balanced] {
                let central = CentralisedDa::new(pref).allocate(inst).unwrap();
                assert!(
                    inst.is_stable(&central.assignment, pref),
                    "N={n} #{idx} {pref:?} centralised"
                );
                assert!(central.stats.iterations <= bound);

                let run = DecentralisedDa::new(pref, idx as u64).run(inst).unwrap();
                let a = &run.allocation.assignment;
                assert!(
                    inst.is_stable(a, pref),
                    "N={n} #{idx} {pref:?} decentralised"
                );
                assert!(
                    run.allocation.stats.iterations <= bound,
                    "{} changes",
                    run.allocation.stats.iterations
                );
                assert_eq!(run.chain.len() as u64, run.allocation.stats.iterations);

                // The centralised twin, given the surviving chain's robot order, makes the same
                // changes and stops at the same partition.
                let twin = CentralisedDa {
                    preference: pref,
                    schedule: run.chain.clone(),
                }
                .allocate(inst)
                .unwrap();
                assert_eq!(&twin.assignment, a, "N={n} #{idx} {pref:?}");
                assert_eq!(twin.stats.iterations, run.allocation.stats.iterations);
            }
        }
    }
}

/// GRAPE's rounds as plainly as they can be written (every view a full copy, every
/// robot sends and compares every round): the reference the event-driven simulation
/// must equal. Returns the final partition, the chain of changes, rounds and messages.
fn plain_grape(
    inst: &Instance,
    pref: Preference,
    seed: u64,
) -> (Assignment, Vec<RobotId>, u64, u64) {
    #[derive(Clone)]
    struct View {
        assignment: Assignment,
        key: (u64, u64),
        chain: Vec<RobotId>,
    }
    let n = inst.num_robots();
    let mut graph = RobotGraph::build(inst.robots(), GraphKind::default()).unwrap();
    graph.connect_components(inst.robots());
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let empty = View {
        assignment: Assignment::unassigned(n, inst.num_tasks()),
        key: (0, 0),
        chain: Vec::new(),
    };
    let mut views = vec![empty; n];
    let mut satisfied = vec![false; n];
    let (mut rounds, mut messages) = (0u64, 0u64);
    loop {
        rounds += 1;
        let mut active = false;
        for i in inst.robot_ids() {
            let a = i.index();
            if std::mem::replace(&mut satisfied[a], true) {
                continue;
            }
            if let Some(j) = inst.best_response(&views[a].assignment, i, pref) {
                let v = &mut views[a];
                v.assignment.set(i, Some(j));
                v.key = (v.key.0 + 1, rng.random());
                v.chain.push(i);
                active = true;
            }
        }
        let sent = views.clone();
        for i in inst.robot_ids() {
            let a = i.index();
            messages += graph.degree(i) as u64;
            let best = graph
                .neighbours(i)
                .iter()
                .map(|&b| &sent[b as usize])
                .max_by_key(|v| v.key)
                .filter(|v| v.key > sent[a].key);
            if let Some(v) = best {
                views[a] = v.clone();
                satisfied[a] = false;
                active = true;
            }
        }
        if !active {
            let v = views.swap_remove(0);
            return (v.assignment, v.chain, rounds, messages);
        }
    }
}

#[test]
fn decentralised_grape_equals_its_plain_simulation() {
    let mut rng = ChaCha8Rng::seed_from_u64(2029);
    let mut instances: Vec<Instance> = dataset(60).into_iter().take(10).collect();
    for case in 0..60 {
        let n = rng.random_range(1..=150);
        let mut cfg = GeneratorConfig::paper(n, rng.random_range(1..=8), rng.random());
        if case % 3 == 0 {
            cfg = cfg.with_capacity_slack(rng.random_range(1.0..1.5));
        }
        instances.push(cfg.generate().unwrap());
    }
    for (idx, inst) in instances.iter().enumerate() {
        for pref in [Preference::Selfish, Preference::Balanced] {
            let seed = idx as u64 * 7 + 1;
            let run = DecentralisedDa::new(pref, seed).run(inst).unwrap();
            let (assignment, chain, rounds, messages) = plain_grape(inst, pref, seed);
            let stats = &run.allocation.stats;
            assert_eq!(run.allocation.assignment, assignment, "#{idx} {pref:?}");
            assert_eq!(run.chain, chain, "#{idx} {pref:?}");
            assert_eq!(
                (stats.rounds, stats.messages),
                (rounds, messages),
                "#{idx} {pref:?}"
            );
            assert_eq!(stats.iterations, chain.len() as u64);
        }
    }
}

/// Exact ties (eps = φ, β = 0, full tasks) neither stop the dynamics early nor keep
/// them going: both twins end stable, and OPT is stable under the balanced rule
/// (a strictly better move would raise the welfare).
#[test]
fn dynamics_end_stable_at_exact_ties() {
    let mut rng = ChaCha8Rng::seed_from_u64(2028);
    for case in 0..800 {
        let inst = small_instance(&mut rng, case);
        let opt = Optimum.allocate(&inst).unwrap().assignment;
        assert!(inst.is_stable(&opt, Preference::Balanced), "case {case}");
        for pref in [Preference::Selfish, Preference::Balanced] {
            let central = CentralisedDa::new(pref).allocate(&inst).unwrap();
            assert!(
                inst.is_stable(&central.assignment, pref),
                "case {case} {pref:?}"
            );
            let run = DecentralisedDa::new(pref, case as u64).run(&inst).unwrap();
            let a = &run.allocation.assignment;
            assert!(
                inst.is_stable(a, pref),
                "case {case} {pref:?} decentralised"
            );
        }
    }
}

#[test]
fn seeded_methods_repeat_and_vary() {
    let inst = dataset(60).swap_remove(0);
    for method in [Method::Random, Method::DaDecentralised] {
        let a = method.allocator(5).allocate(&inst).unwrap();
        let b = method.allocator(5).allocate(&inst).unwrap();
        assert_eq!(a.assignment, b.assignment, "{method}");
        assert_eq!(
            (a.stats.rounds, a.stats.messages),
            (b.stats.rounds, b.stats.messages)
        );
        assert_eq!(a.stats.seed, Some(5));
    }
    let differs = (0..10).any(|s| {
        Method::Random
            .allocator(s)
            .allocate(&inst)
            .unwrap()
            .assignment
            != Method::Random
                .allocator(s + 100)
                .allocate(&inst)
                .unwrap()
                .assignment
    });
    assert!(differs);
}

#[test]
fn greedy_is_the_first_sweep_of_balanced_dynamics() {
    // Hand-made: two tasks on a line, robots at 0.1 and 0.9.
    let inst = Instance::new(
        vec![
            afg_game::Point::new(0.1, 0.0),
            afg_game::Point::new(0.9, 0.0),
        ],
        vec![
            afg_game::Task {
                position: afg_game::Point::new(0.0, 0.0),
                reward: 1.0,
                eps: 2.0,
                capacity: None,
            },
            afg_game::Task {
                position: afg_game::Point::new(1.0, 0.0),
                reward: 1.0,
                eps: 2.0,
                capacity: None,
            },
        ],
        1.0,
    )
    .unwrap();
    let a = Method::Greedy
        .allocator(0)
        .allocate(&inst)
        .unwrap()
        .assignment;
    assert_eq!(a.tasks(), &[Some(TaskId(0)), Some(TaskId(1))]);
    // Welfare 1 + 1 - 0.1 - 0.1 = 1.8, which is also the optimum.
    assert!((inst.welfare(&a) - 1.8).abs() < 1e-12);
    let opt = Optimum.allocate(&inst).unwrap().assignment;
    assert_eq!(opt, a);
    assert_eq!(a.task_of(RobotId(1)), Some(TaskId(1)));
}

#[test]
fn method_names_round_trip_and_unknown_names_are_errors() {
    for m in Method::ALL {
        assert_eq!(m.name().parse::<Method>().unwrap(), m);
        assert_eq!(m.allocator(0).name(), m.name());
    }
    let err = "hungarian".parse::<Method>().unwrap_err();
    assert!(err.contains("expected one of opt"), "{err}");
}

#[test]
fn schedule_naming_a_missing_robot_is_an_error() {
    let inst = GeneratorConfig::paper(3, 2, 0).generate().unwrap();
    let da = CentralisedDa {
        preference: Preference::Selfish,
        schedule: vec![RobotId(3)],
    };
    assert!(matches!(
        da.allocate(&inst),
        Err(afg_baseline::AllocError::InvalidParameter(_))
    ));
}

#[test]
fn blind_balances_sizes_whatever_the_positions() {
    for n in [1, 7, 20, 37] {
        let first = Blind
            .allocate(&GeneratorConfig::paper(n, 5, 0).generate().unwrap())
            .unwrap()
            .assignment;
        for seed in 1..20 {
            let inst = GeneratorConfig::paper(n, 5, seed).generate().unwrap();
            let a = Blind.allocate(&inst).unwrap().assignment;
            assert_eq!(a, first, "N = {n}: the positions changed the choice");
            let (lo, hi) = (a.sizes().iter().min(), a.sizes().iter().max());
            assert!(hi.unwrap() - lo.unwrap() <= 1, "N = {n}: {:?}", a.sizes());
        }
    }
}

#[test]
fn blind_beats_random_where_tasks_can_be_left_empty() {
    // At N = 20 (four robots per task) a random pass often leaves a task empty and
    // loses its whole reward; equal sizes never do.
    let insts = dataset(20);
    let mean = |m: Method| {
        insts
            .iter()
            .map(|i| i.welfare(&m.allocator(0).allocate(i).unwrap().assignment))
            .sum::<f64>()
            / insts.len() as f64
    };
    let (blind, random) = (mean(Method::Blind), mean(Method::Random));
    assert!(blind > random + 1.0, "blind {blind}, random {random}");
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

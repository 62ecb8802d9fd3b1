//! Every method against OPT, and the dynamics' guarantees.

mod common;

use std::path::PathBuf;

use afg_baseline::{Allocator, Blind, CentralisedDa, DecentralisedDa, Method, Optimum};
use afg_game::io::read_dataset;
use afg_game::{Assignment, GeneratorConfig, Instance, Preference, RobotId, TaskId};
use afg_graph::{GraphKind, RobotGraph};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use common::{small_instance, small_void_instance};

fn dataset(n: usize) -> Vec<Instance> {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(format!("../../datasets/n{n}.jsonl"));
    read_dataset(&path).expect("committed dataset")
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

/// Robot by robot in index order, what the one-pass rule `rule` says robot i does given
/// the places of robots 0..i in `a`; panics where `a` differs.
fn replay(
    inst: &Instance,
    a: &Assignment,
    why: &str,
    rule: impl Fn(&Assignment, RobotId) -> Option<TaskId>,
) {
    let mut partial = Assignment::unassigned(inst.num_robots(), inst.num_tasks());
    for i in inst.robot_ids() {
        assert_eq!(a.task_of(i), rule(&partial, i), "{why}: robot {i}");
        partial.set(i, a.task_of(i));
    }
}

/// GRAPE's game: every method's assignment fits and is at most the void optimum; each
/// stays out by its own rule (greedy and nearest replayed here); the dynamics end
/// stable with the void move and the decentralised run equals its centralised twin;
/// and every method leaves robots out somewhere.
#[test]
fn every_method_plays_grapes_game() {
    let mut rng = ChaCha8Rng::seed_from_u64(2032);
    let mut out = [0usize; Method::ALL.len()];
    for case in 0..300 {
        let inst = small_void_instance(&mut rng, case);
        let best = inst.welfare(&Optimum.allocate(&inst).unwrap().assignment);
        for (k, method) in Method::ALL.iter().enumerate() {
            let a = method
                .allocator(case as u64)
                .allocate(&inst)
                .unwrap()
                .assignment;
            inst.check(&a).unwrap();
            let w = inst.welfare(&a);
            assert!(
                w <= best + 1e-9 * best.abs().max(1.0),
                "case {case} {method}: {w} > {best}"
            );
            out[k] += inst.num_robots() - a.num_assigned();
        }
        let why = format!("case {case}");
        let greedy = Method::Greedy
            .allocator(0)
            .allocate(&inst)
            .unwrap()
            .assignment;
        replay(&inst, &greedy, &why, |p, i| {
            let (mut best, mut score) = (None, f64::NEG_INFINITY);
            for j in inst.task_ids().filter(|&j| p.has_room(&inst, i, j)) {
                let s = inst.score(p, i, j, Preference::Balanced);
                if s > score {
                    (best, score) = (Some(j), s);
                }
            }
            best.filter(|_| score >= 0.0)
        });
        let nearest = Method::Nearest
            .allocator(0)
            .allocate(&inst)
            .unwrap()
            .assignment;
        replay(&inst, &nearest, &why, |p, i| {
            let j = inst
                .task_ids()
                .filter(|&j| p.has_room(&inst, i, j))
                .min_by(|&x, &y| inst.distance(i, x).total_cmp(&inst.distance(i, y)))?;
            let worth = inst.marginal_value(j, p.size(j) + 1) - inst.cost(i, j);
            (worth >= 0.0).then_some(j)
        });
        for pref in [Preference::Selfish, Preference::Balanced] {
            let central = CentralisedDa::new(pref).allocate(&inst).unwrap().assignment;
            assert!(inst.is_stable(&central, pref), "{why} {pref:?}");
            let run = DecentralisedDa::new(pref, case as u64).run(&inst).unwrap();
            assert!(
                inst.is_stable(&run.allocation.assignment, pref),
                "{why} {pref:?}"
            );
            let twin = CentralisedDa {
                preference: pref,
                schedule: run.chain.clone(),
            };
            let twin = twin.allocate(&inst).unwrap().assignment;
            assert_eq!(twin, run.allocation.assignment, "{why} {pref:?}");
        }
    }
    for (k, method) in Method::ALL.iter().enumerate() {
        assert!(out[k] > 0, "{method} never left a robot out");
    }
}

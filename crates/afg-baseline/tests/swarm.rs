//! GRAPE over failing networks: the perfect network is today's decentralised GRAPE,
//! every run repeats per seed, and whatever the network does, the survivors end on
//! one stable partition that places no crashed robot.

mod common;

use afg_baseline::{
    AllocError, Allocator, DecentralisedDa, Failure, Network, Optimum, Swarm, SwarmReport,
};
use afg_game::{GeneratorConfig, Instance, Preference, RobotId};
use afg_graph::GraphKind;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// `count` paper instances of 2..=`most` robots, 1..=8 tasks, every third with capacities.
fn instances(count: usize, most: usize, seed: u64) -> Vec<Instance> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..count)
        .map(|case| {
            let n = rng.random_range(2..=most);
            let mut cfg = GeneratorConfig::paper(n, rng.random_range(1..=8), rng.random());
            if case % 3 == 0 {
                cfg = cfg.with_capacity_slack(rng.random_range(1.05..1.5));
            }
            cfg.generate().unwrap()
        })
        .collect()
}

/// The knobs one at a time, then all together.
fn networks() -> Vec<(&'static str, Network)> {
    let base = Network::default;
    vec![
        (
            "loss",
            Network {
                loss: 0.3,
                ..base()
            },
        ),
        (
            "burst",
            Network {
                loss: 0.5,
                burst: Some(6.0),
                ..base()
            },
        ),
        (
            "delay",
            Network {
                max_delay: 3,
                ..base()
            },
        ),
        (
            "async",
            Network {
                activation: 0.3,
                ..base()
            },
        ),
        (
            "crash",
            Network {
                failure: Some(Failure::new(0.3, 4)),
                ..base()
            },
        ),
        (
            "late crash",
            Network {
                failure: Some(Failure::new(0.6, 400)),
                ..base()
            },
        ),
        (
            "partition",
            Network {
                partition_until: Some(40),
                ..base()
            },
        ),
        (
            "radius",
            Network {
                graph: GraphKind::Radius { radius: 0.4 },
                loss: 0.2,
                ..base()
            },
        ),
        (
            "all",
            Network {
                loss: 0.3,
                burst: Some(3.0),
                max_delay: 2,
                activation: 0.5,
                failure: Some(Failure {
                    fraction: 0.1,
                    at_round: 30,
                    detect_after: 5,
                }),
                partition_until: Some(20),
                ..base()
            },
        ),
    ]
}

#[test]
fn the_perfect_network_is_decentralised_grape() {
    for (idx, inst) in instances(40, 160, 31).iter().enumerate() {
        for pref in [Preference::Selfish, Preference::Balanced] {
            let seed = idx as u64 + 3;
            let grape = DecentralisedDa::new(pref, seed).run(inst).unwrap();
            let report = Swarm::grape(pref, Network::default(), seed)
                .run(inst)
                .unwrap();
            let stats = grape.allocation.stats;
            assert_eq!(
                report.assignment.as_ref(),
                Some(&grape.allocation.assignment),
                "#{idx}"
            );
            assert_eq!(
                (report.rounds, report.messages, report.changes),
                (stats.rounds, stats.messages, stats.iterations),
                "#{idx} {pref:?}"
            );
            assert!(report.converged && report.stable && report.agreeing == 1.0);
            assert_eq!(report.survivors, inst.num_robots());
            // Each robot places itself by a change of its own, and holds the others'
            // only by taking a view from a neighbour at least once.
            let n = inst.num_robots() as u64;
            assert!(
                report.proposals >= report.changes && report.changes >= n,
                "#{idx}"
            );
            assert!(report.adoptions >= n || n < 2, "#{idx}");
            // Every message carries the whole partition: 20 bytes, then a byte per robot.
            let full = 20 + inst.num_robots() as u64;
            assert_eq!(report.bytes, report.messages * full);
            assert!(report.delta_bytes < report.bytes || inst.num_robots() < 3);
        }
    }
}

#[test]
fn survivors_agree_on_a_stable_partition_whatever_the_network() {
    for (idx, inst) in instances(12, 160, 32).iter().enumerate() {
        for (name, network) in networks() {
            let pref = [Preference::Selfish, Preference::Balanced][idx % 2];
            let report = Swarm::grape(pref, network.clone(), idx as u64)
                .run(inst)
                .unwrap();
            let why = format!("#{idx} N={} {name}", inst.num_robots());
            assert!(report.converged, "{why}");
            assert_eq!(report.agreeing, 1.0, "{why}");
            assert!(report.stable, "{why}");
            assert!(
                report.percent_of_opt.is_none_or(|p| p <= 100.0 + 1e-9),
                "{why}"
            );
            let a = report.assignment.as_ref().unwrap();
            let placed = inst.robot_ids().filter(|&i| a.task_of(i).is_some()).count();
            assert_eq!(
                placed, report.survivors,
                "{why}: survivors placed, crashed not"
            );
            if let Some(f) = network.failure {
                let n = inst.num_robots();
                let crashed = ((f.fraction * n as f64).round() as usize).min(n - 1);
                assert_eq!(report.survivors, n - crashed, "{why}");
            }
            assert!(report.delta_bytes <= report.bytes, "{why}");
        }
    }
}

/// The survivors' game is judged on its own: welfare, optimum and stability of the
/// survivors alone, recomputed here.
#[test]
fn the_report_scores_the_survivors_alone() {
    let inst = GeneratorConfig::paper(120, 5, 8).generate().unwrap();
    let network = Network {
        loss: 0.2,
        failure: Some(Failure::new(0.25, 10)),
        ..Network::default()
    };
    let report = Swarm::grape(Preference::Selfish, network, 4)
        .run(&inst)
        .unwrap();
    let a = report.assignment.clone().unwrap();
    let survivors: Vec<RobotId> = inst
        .robot_ids()
        .filter(|&i| a.task_of(i).is_some())
        .collect();
    assert_eq!(survivors.len(), 90);
    let points = survivors
        .iter()
        .map(|&i| inst.robots()[i.index()])
        .collect();
    let sub = Instance::new(points, inst.tasks().to_vec(), inst.beta()).unwrap();
    let tasks = survivors.iter().map(|&i| a.task_of(i)).collect();
    let sub_a = afg_game::Assignment::from_tasks(&sub, tasks).unwrap();
    assert!((sub.welfare(&sub_a) - report.welfare).abs() < 1e-9);
    let opt = sub.welfare(&Optimum.allocate(&sub).unwrap().assignment);
    assert!((opt - report.opt_welfare).abs() < 1e-9);
    assert!(sub.is_stable(&sub_a, Preference::Selfish));
    assert_eq!(
        sub.ns_rate(&sub_a, Preference::Selfish),
        report.ns_rate_selfish
    );
}

fn comparable(r: &SwarmReport) -> String {
    let mut r = r.clone();
    r.wall_time_s = 0.0;
    format!("{:?}", r)
}

#[test]
fn every_run_repeats_per_seed_and_seeds_differ() {
    let inst = GeneratorConfig::paper(100, 5, 2).generate().unwrap();
    for (name, network) in networks() {
        let run = |seed| {
            let mut swarm = Swarm::grape(Preference::Selfish, network.clone(), seed);
            swarm.trace = true;
            swarm.run(&inst).unwrap()
        };
        assert_eq!(comparable(&run(5)), comparable(&run(5)), "{name}");
        let differs = (6..12).any(|s| {
            let (a, b) = (run(5), run(s));
            (a.rounds, a.messages, a.assignment) != (b.rounds, b.messages, b.assignment)
        });
        assert!(differs, "{name}: six other seeds give the same run");
    }
}

/// Losing messages costs rounds, not the result's quality: the final partition is as
/// stable, and GRAPE still sends every round, so more rounds mean more messages.
#[test]
fn loss_costs_rounds_and_messages() {
    let inst = GeneratorConfig::paper(150, 5, 6).generate().unwrap();
    let run = |loss| {
        let network = Network {
            loss,
            ..Network::default()
        };
        Swarm::grape(Preference::Selfish, network, 1)
            .run(&inst)
            .unwrap()
    };
    let (clean, lossy) = (run(0.0), run(0.5));
    assert!(
        lossy.rounds > clean.rounds,
        "{} vs {}",
        lossy.rounds,
        clean.rounds
    );
    assert_eq!(
        lossy.messages,
        lossy.rounds * (clean.messages / clean.rounds)
    );
}

#[test]
fn the_trace_ends_at_the_final_partition() {
    let inst = GeneratorConfig::paper(80, 4, 3).generate().unwrap();
    let mut swarm = Swarm::grape(
        Preference::Selfish,
        Network {
            loss: 0.4,
            ..Network::default()
        },
        2,
    );
    swarm.trace = true;
    let report = swarm.run(&inst).unwrap();
    let last = report.trace.last().unwrap();
    assert_eq!(last.round, report.rounds);
    assert_eq!(last.agreeing, 1.0);
    assert!((last.welfare - report.welfare).abs() < 1e-9);
    assert!(report.trace.windows(2).all(|w| w[0].round < w[1].round));
    assert!(report.trace.len() <= 256);
}

#[test]
fn bad_networks_are_refused_with_the_reason() {
    let inst = GeneratorConfig::paper(10, 2, 1).generate().unwrap();
    let cases = [
        (
            Network {
                loss: -0.1,
                ..Network::default()
            },
            "loss",
        ),
        (
            Network {
                activation: 0.0,
                ..Network::default()
            },
            "activation",
        ),
        (
            Network {
                loss: 0.9,
                burst: Some(2.0),
                ..Network::default()
            },
            "at most 0.667",
        ),
        (
            Network {
                burst: Some(0.5),
                ..Network::default()
            },
            "burst",
        ),
        (
            Network {
                failure: Some(Failure::new(1.0, 3)),
                ..Network::default()
            },
            "failing share",
        ),
        (
            Network {
                failure: Some(Failure::new(0.1, 0)),
                ..Network::default()
            },
            "round 1",
        ),
        (
            Network {
                graph: GraphKind::Radius { radius: -1.0 },
                ..Network::default()
            },
            "radius",
        ),
    ];
    for (network, says) in cases {
        let err = Swarm::grape(Preference::Selfish, network, 0)
            .run(&inst)
            .unwrap_err();
        assert!(
            matches!(err, AllocError::InvalidParameter(_) | AllocError::Graph(_)),
            "{err}"
        );
        assert!(err.to_string().contains(says), "{err}");
    }
}

/// A run that hits its round limit says so instead of reporting a stable result.
#[test]
fn a_run_cut_short_reports_it() {
    let inst = GeneratorConfig::paper(100, 5, 2).generate().unwrap();
    let mut swarm = Swarm::grape(Preference::Selfish, Network::default(), 0);
    swarm.max_rounds = 3;
    let report = swarm.run(&inst).unwrap();
    assert!(!report.converged);
    assert_eq!(report.rounds, 3);
}

/// The bar at N = 1000: 30 % of the messages lost and 10 % of the robots
/// crashing mid-run (round 1700 of the ~3400 the run takes without them).
#[test]
fn a_thousand_robots_survive_loss_and_failures() {
    let inst = GeneratorConfig::paper(1000, 5, 1).generate().unwrap();
    let network = Network {
        loss: 0.3,
        failure: Some(Failure::new(0.1, 1700)),
        ..Network::default()
    };
    let report = Swarm::grape(Preference::Selfish, network, 0)
        .run(&inst)
        .unwrap();
    assert!(report.converged && report.stable);
    assert_eq!((report.survivors, report.agreeing), (900, 1.0));
    assert!(
        report.rounds > 1700,
        "the crash came after the end: {} rounds",
        report.rounds
    );
    assert!(
        report.percent_of_opt.unwrap() > 99.0,
        "{:?}",
        report.percent_of_opt
    );
}

/// The auction ends within 2N·ε of the survivors' optimum (LP duality, 2ε-CS), on
/// every network, every survivor agreeing.
#[test]
fn the_auction_ends_within_2n_epsilon_of_the_optimum() {
    let epsilon = 1e-3;
    for (idx, inst) in instances(8, 80, 33).iter().enumerate() {
        for (name, network) in networks() {
            let report = Swarm::auction(epsilon, network, idx as u64)
                .run(inst)
                .unwrap();
            let why = format!("#{idx} N={} {name}", inst.num_robots());
            assert!(report.converged, "{why}");
            assert_eq!(report.agreeing, 1.0, "{why}");
            // Each robot wrote only its own bids, so every other survivor's record
            // was taken from a neighbour.
            let s = report.survivors as u64;
            assert_eq!(report.proposals, report.changes, "{why}");
            assert!(report.adoptions >= s * (s - 1), "{why}");
            let bound = 2.0 * report.survivors as f64 * epsilon;
            assert!(
                report.welfare >= report.opt_welfare - bound - 1e-9,
                "{why}: {} < {} − {bound}",
                report.welfare,
                report.opt_welfare
            );
            let a = report.assignment.as_ref().unwrap();
            let placed = inst.robot_ids().filter(|&i| a.task_of(i).is_some()).count();
            assert_eq!(placed, report.survivors, "{why}");
            assert!(
                inst.task_ids().all(|j| a.size(j) <= inst.capacity(j)),
                "{why}"
            );
        }
    }
}

#[test]
fn the_auction_repeats_per_seed_and_refuses_a_bad_increment() {
    let inst = GeneratorConfig::paper(60, 4, 2).generate().unwrap();
    let network = Network {
        loss: 0.3,
        activation: 0.5,
        ..Network::default()
    };
    let run = |seed| {
        Swarm::auction(1e-3, network.clone(), seed)
            .run(&inst)
            .unwrap()
    };
    assert_eq!(comparable(&run(3)), comparable(&run(3)));
    assert!((4..10).any(|s| run(s).rounds != run(3).rounds));
    for epsilon in [0.0, -1.0, f64::NAN] {
        let err = Swarm::auction(epsilon, Network::default(), 0)
            .run(&inst)
            .unwrap_err();
        assert!(err.to_string().contains("increment"), "{err}");
    }
}

/// GRAPE's game on every network: GRAPE's survivors end on one partition that is stable
/// with the void move (on the perfect network, decentralised GRAPE's), the auction's
/// within 2N·ε of the void optimum; and robots stay out.
#[test]
fn the_swarm_plays_grapes_game() {
    let (mut rng, epsilon, mut out) = (ChaCha8Rng::seed_from_u64(34), 1e-3, 0);
    for (idx, paper) in instances(10, 80, 35).iter().enumerate() {
        let inst = common::into_void(&mut rng, idx, paper);
        let pref = [Preference::Selfish, Preference::Balanced][idx % 2];
        let seed = idx as u64;
        let plain = DecentralisedDa::new(pref, seed).run(&inst).unwrap();
        let perfect = Swarm::grape(pref, Network::default(), seed)
            .run(&inst)
            .unwrap();
        assert_eq!(
            perfect.assignment.as_ref(),
            Some(&plain.allocation.assignment)
        );
        for (name, network) in networks() {
            let why = format!("#{idx} N={} {name}", inst.num_robots());
            let grape = Swarm::grape(pref, network.clone(), seed)
                .run(&inst)
                .unwrap();
            assert!(grape.converged && grape.stable, "{why}");
            assert_eq!(grape.agreeing, 1.0, "{why}");
            let auction = Swarm::auction(epsilon, network, seed).run(&inst).unwrap();
            assert!(auction.converged, "{why}");
            assert_eq!(auction.agreeing, 1.0, "{why}");
            let bound = 2.0 * auction.survivors as f64 * epsilon;
            assert!(
                auction.welfare >= auction.opt_welfare - bound - 1e-9,
                "{why}"
            );
            for report in [&grape, &auction] {
                let a = report.assignment.as_ref().unwrap();
                out += report.survivors - a.num_assigned();
            }
        }
    }
    assert!(out > 0, "nobody stayed out");
}

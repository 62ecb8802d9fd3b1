//! GRAPE inside a mission ([`LiveSwarm`]): robots that know only some tasks, tasks
//! that appear and are done, robots that fail and come back, links that follow the
//! robots.

use afg_baseline::{AllocError, Allocator, Failure, LiveSwarm, Network, Optimum, SwarmMethod};
use afg_game::{Assignment, GeneratorConfig, Instance, Point, Preference, RobotId, TaskId};
use afg_graph::GraphKind;
use proptest::prelude::*;

const GRAPE: SwarmMethod = SwarmMethod::Grape {
    preference: Preference::Selfish,
};
const EPSILON: f64 = 1e-3;
const AUCTION: SwarmMethod = SwarmMethod::Auction { epsilon: EPSILON };

/// Everyone hears everyone: the swarm is one component wherever the robots go.
fn everyone(loss: f64) -> Network {
    Network {
        graph: GraphKind::Radius { radius: 10.0 },
        loss,
        ..Network::default()
    }
}

/// Rounds (robots standing still) until the swarm settles; the rounds it took.
fn settle(swarm: &mut LiveSwarm, points: &[Point]) -> u64 {
    let start = swarm.rounds();
    while !swarm.settled() {
        swarm.round(points).unwrap();
        assert!(swarm.rounds() - start < 100_000, "the swarm never settled");
    }
    swarm.rounds() - start
}

/// The partition of the robots in `robots` by their own views, in the game of those
/// robots.
fn partition(game: &Instance, swarm: &LiveSwarm, robots: &[usize]) -> (Instance, Assignment) {
    let points = robots.iter().map(|&i| game.robots()[i]).collect();
    let sub = game.with_robots(points).unwrap();
    let mut a = Assignment::unassigned(robots.len(), game.num_tasks());
    for (k, &i) in robots.iter().enumerate() {
        a.set(
            RobotId(k as u32),
            swarm.task_of(i).map(|j| TaskId(j as u32)),
        );
    }
    (sub, a)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(16))]

    /// Tasks appear one by one, one is done, a robot fails: after each event the swarm
    /// settles and every robot's own view is one partition. GRAPE's is stable under its
    /// preference among the tasks still open and the robots still alive; the auction's
    /// is within 2Nε of the optimum of those robots and tasks (over a lossy network
    /// too).
    #[test]
    fn after_every_event_the_swarm_settles_on_a_stable_partition(
        seed in 0u64..500,
        n in 2usize..25,
        m in 2usize..5,
        lossy in any::<bool>(),
        auction in any::<bool>(),
    ) {
        let game = GeneratorConfig::paper(n, m, seed).generate().unwrap();
        let network = everyone(if lossy { 0.3 } else { 0.0 });
        let method = if auction { AUCTION } else { GRAPE };
        let mut swarm = LiveSwarm::new(game.clone(), method, &network, None, seed).unwrap();
        let points = game.robots().to_vec();
        let mut alive: Vec<usize> = (0..n).collect();
        let check = |swarm: &LiveSwarm, alive: &[usize], open: &[usize]| {
            let (sub, a) = partition(&game, swarm, alive);
            for i in sub.robot_ids() {
                let task = a.task_of(i).map(|t| t.index());
                assert!(task.is_none_or(|j| open.contains(&j)), "robot on a closed task");
                if auction {
                    continue;
                }
                // Stable among the open tasks: no open task it strictly prefers.
                let best = sub.best_move_among(i, a.task_of(i), a.sizes(), Preference::Selfish, |t| open.contains(&t.index()));
                assert_eq!(best, None, "robot {i} would move");
            }
            if auction {
                let tasks = open.iter().map(|&j| game.tasks()[j]).collect();
                let open_game = Instance::new(sub.robots().to_vec(), tasks, game.beta()).unwrap();
                let opt = open_game.welfare(&Optimum.allocate(&open_game).unwrap().assignment);
                let slack = 2.0 * alive.len() as f64 * EPSILON + 1e-9 * opt.abs().max(1.0);
                let welfare = sub.welfare(&a);
                assert!(welfare >= opt - slack, "auction {welfare} against the optimum {opt}");
            }
        };
        let mut open = Vec::new();
        for j in 0..m {
            swarm.task_appears(j);
            open.push(j);
            settle(&mut swarm, &points);
            check(&swarm, &alive, &open);
        }
        swarm.task_done(0);
        open.retain(|&j| j != 0);
        settle(&mut swarm, &points);
        check(&swarm, &alive, &open);
        swarm.fail(n - 1).unwrap();
        alive.pop();
        settle(&mut swarm, &points);
        if !alive.is_empty() {
            check(&swarm, &alive, &open);
        }
    }
}

/// The same seed gives the same rounds, views and traffic; robots that move relink.
#[test]
fn the_same_seed_gives_the_same_run() {
    let game = GeneratorConfig::paper(40, 4, 3).generate().unwrap();
    let network = Network {
        graph: GraphKind::Radius { radius: 0.4 },
        loss: 0.3,
        burst: Some(3.0),
        ..Network::default()
    };
    let run = || {
        let mut swarm = LiveSwarm::new(game.clone(), GRAPE, &network, Some(0.5), 9).unwrap();
        let mut points = game.robots().to_vec();
        let mut seen = Vec::new();
        for j in 0..4 {
            swarm.task_appears(j);
            for _ in 0..200 {
                // Every robot drifts towards its task.
                for (i, p) in points.iter_mut().enumerate() {
                    if let Some(j) = swarm.task_of(i) {
                        let t = game.tasks()[j].position;
                        *p = Point::new(p.x + 0.01 * (t.x - p.x), p.y + 0.01 * (t.y - p.y));
                    }
                }
                swarm.round(&points).unwrap();
                seen.push((0..40).map(|i| swarm.task_of(i)).collect::<Vec<_>>());
            }
        }
        (seen, swarm.messages(), swarm.bytes())
    };
    assert_eq!(run(), run());
}

/// With a sensing radius and no one to tell them, robots never take a task out of
/// their sight; once one robot sees it, the news spreads over the links.
#[test]
fn robots_take_only_the_tasks_they_know_of() {
    let task = |x: f64| afg_game::Task {
        position: Point::new(x, 0.0),
        reward: 10.0,
        eps: 2.0,
        capacity: None,
    };
    // Robots along a line 0.1 apart; task 0 at the left end, task 1 at the right.
    let points: Vec<Point> = (0..10).map(|i| Point::new(0.1 * i as f64, 0.0)).collect();
    let game = Instance::with_void(points.clone(), vec![task(0.0), task(0.9)], 0.1).unwrap();
    let deaf = Network {
        graph: GraphKind::Radius { radius: 0.01 },
        ..Network::default()
    };
    let mut swarm = LiveSwarm::new(game.clone(), GRAPE, &deaf, Some(0.15), 1).unwrap();
    swarm.task_appears(1);
    for _ in 0..50 {
        swarm.round(&points).unwrap();
    }
    // Only robots 8 and 9 see task 1 (within 0.15); the others have heard of nothing.
    let on_task_1: Vec<usize> = (0..10).filter(|&i| swarm.task_of(i) == Some(1)).collect();
    assert_eq!(on_task_1, vec![8, 9]);
    // Linked at 0.1 apart, the news reaches everyone.
    let chain = Network {
        graph: GraphKind::Radius { radius: 0.11 },
        ..Network::default()
    };
    let mut swarm = LiveSwarm::new(game, GRAPE, &chain, Some(0.15), 1).unwrap();
    swarm.task_appears(1);
    settle(&mut swarm, &points);
    assert!((0..10).all(|i| swarm.task_of(i) == Some(1)));
}

/// A robot that comes back rejoins: the swarm settles with it placed again.
#[test]
fn a_robot_that_returns_rejoins() {
    let game = GeneratorConfig::paper(12, 3, 5).generate().unwrap();
    let points = game.robots().to_vec();
    for method in [GRAPE, AUCTION] {
        let mut swarm = LiveSwarm::new(game.clone(), method, &everyone(0.0), None, 2).unwrap();
        for j in 0..3 {
            swarm.task_appears(j);
        }
        settle(&mut swarm, &points);
        swarm.fail(4).unwrap();
        settle(&mut swarm, &points);
        swarm.revive(4).unwrap();
        settle(&mut swarm, &points);
        assert!((0..12).all(|i| swarm.task_of(i).is_some()), "{method:?}");
    }
}

/// Knobs out of range are refused with what is wrong.
#[test]
fn bad_knobs_are_refused() {
    let game = GeneratorConfig::paper(5, 2, 1).generate().unwrap();
    let refused = |method, network: &Network, sensing| match LiveSwarm::new(
        game.clone(),
        method,
        network,
        sensing,
        0,
    ) {
        Err(AllocError::InvalidParameter(what)) => what,
        _ => panic!("accepted"),
    };
    let bad_auction = SwarmMethod::Auction { epsilon: 0.0 };
    assert!(refused(bad_auction, &Network::default(), None).contains("ε"));
    let failing = Network {
        failure: Some(Failure::new(0.1, 5)),
        ..Network::default()
    };
    assert!(refused(GRAPE, &failing, None).contains("failure"));
    assert!(refused(GRAPE, &Network::default(), Some(-1.0)).contains("sensing"));
    let lossy = Network {
        loss: 1.0,
        ..Network::default()
    };
    assert!(refused(GRAPE, &lossy, None).contains("loss"));
}

//! The auction on games whose tasks need teams: the robots staff the tasks a shared
//! rule picks (value per member, first fit in the robots), fill every team, and place
//! themselves as well as the exact placement of that staffing, within 2N·ε; a task
//! done in a mission frees its robots without breaking the other teams; on skill
//! games a team's skill places go to robots that hold the skill.

mod common;

use afg_baseline::{LiveSwarm, Network, Swarm, SwarmMethod, TeamOptimum};
use afg_game::{Instance, Point, Task, TaskId};
use afg_graph::GraphKind;

use common::{scarce, skill_by_hand, skill_by_hand_welfare};

const EPSILON: f64 = 1e-3;

/// The rule, written out again: tasks by value per member `F(k)/k` (then index),
/// each taken while its threshold fits in the robots left.
fn rule(inst: &Instance) -> Vec<bool> {
    let per_member = |j: TaskId| {
        let k = inst.min_team(j);
        inst.value_function(j).value(k) / k as f64
    };
    let mut order: Vec<TaskId> = inst.task_ids().collect();
    order.sort_by(|&a, &b| per_member(b).total_cmp(&per_member(a)).then(a.cmp(&b)));
    let (mut room, mut staffed) = (inst.num_robots(), vec![false; inst.num_tasks()]);
    for j in order {
        if inst.min_team(j) <= room && inst.min_team(j) <= inst.capacity(j) {
            room -= inst.min_team(j);
            staffed[j.index()] = true;
        }
    }
    staffed
}

fn networks() -> Vec<(&'static str, Network)> {
    vec![
        ("perfect", Network::default()),
        (
            "loss 30 %",
            Network {
                loss: 0.3,
                ..Network::default()
            },
        ),
        (
            "loss 30 %, delay ≤ 2, half awake",
            Network {
                loss: 0.3,
                max_delay: 2,
                activation: 0.5,
                ..Network::default()
            },
        ),
    ]
}

#[test]
fn the_auction_staffs_the_rules_tasks_at_their_best_placement() {
    for (idx, (n, m)) in [(12, 3), (20, 4), (30, 5), (40, 6)].into_iter().enumerate() {
        let inst = scarce(n, m, 40 + idx as u64);
        let staffed = rule(&inst);
        let (_, best_placement) = TeamOptimum::staff(&inst, &staffed).unwrap();
        for (name, network) in networks() {
            let why = format!("N={n} M={m} {name}");
            let mut swarm = Swarm::auction(EPSILON, network, idx as u64);
            // The robots beyond the teams raise the team places' prices in steps of
            // about ε (module docs): more rounds than the concave game's limit.
            swarm.max_rounds = 1_000_000;
            let report = swarm.run(&inst).unwrap();
            assert!(report.converged && report.agreeing == 1.0, "{why}");
            let a = report.assignment.as_ref().unwrap();
            for j in inst.task_ids() {
                let size = a.size(j);
                if staffed[j.index()] {
                    assert!(size >= inst.min_team(j), "{why}: task {j:?} has {size}");
                } else {
                    assert_eq!(size, 0, "{why}: task {j:?} is not staffed");
                }
            }
            let bound = 2.0 * n as f64 * EPSILON;
            assert!(
                report.welfare >= best_placement - bound - 1e-9,
                "{why}: {} < {best_placement} − {bound}",
                report.welfare
            );
            assert!(report.welfare <= report.opt_welfare + 1e-9, "{why}");
        }
    }
}

/// Tasks on a line at 0, 1 and 2 (F(k)/k falling with the index) and five robots: the
/// first task (k = 3) is staffed, the second (k = 3) does not fit in the two robots
/// left and is passed over, the third (k = 2) fits. Computed by hand.
#[test]
fn the_rule_passes_over_a_team_too_large_and_takes_one_that_fits() {
    let task = |x, reward| Task {
        position: Point::new(x, 0.0),
        reward,
        eps: 2.0,
        capacity: None,
    };
    let robots = [0.0, 0.1, 0.2, 1.9, 2.0]
        .map(|x| Point::new(x, 0.0))
        .to_vec();
    let tasks = vec![task(0.0, 9.0), task(1.0, 6.0), task(2.0, 3.0)];
    let inst = Instance::new(robots, tasks, 0.1)
        .unwrap()
        .with_teams(vec![3, 3, 2], &[], &[])
        .unwrap();
    assert_eq!(rule(&inst), [true, false, true]);
    let report = Swarm::auction(EPSILON, Network::default(), 0)
        .run(&inst)
        .unwrap();
    let tasks = report.assignment.unwrap().tasks().to_vec();
    let expected = [0, 0, 0, 2, 2].map(|j| Some(TaskId(j)));
    assert_eq!(tasks, expected);
}

/// Rounds (robots standing still) until the swarm settles, checking after each that
/// `kept` robots still head for `task`.
fn settle_keeping(swarm: &mut LiveSwarm, points: &[Point], kept: &[usize], task: usize) {
    for _ in 0..100_000 {
        if swarm.settled() {
            return;
        }
        swarm.round(points).unwrap();
        for &i in kept {
            assert_eq!(swarm.task_of(i), Some(task), "robot {i} left its team");
        }
    }
    panic!("the swarm never settled");
}

/// Three tasks needing two robots each and four robots: the rule staffs the first
/// two. When the second is done its robots staff the third, and the first task's
/// team keeps its places all along (no restart).
#[test]
fn a_task_done_frees_its_robots_for_the_next_team_and_keeps_the_others() {
    let task = |x, reward| Task {
        position: Point::new(x, 0.5),
        reward,
        eps: 2.0,
        capacity: None,
    };
    let points = [0.0, 0.05, 0.5, 0.55].map(|x| Point::new(x, 0.5)).to_vec();
    let tasks = vec![task(0.0, 9.0), task(0.5, 6.0), task(1.0, 3.0)];
    let game = Instance::new(points.clone(), tasks, 0.1)
        .unwrap()
        .with_teams(vec![2, 2, 2], &[], &[])
        .unwrap();
    let network = Network {
        graph: GraphKind::Radius { radius: 10.0 },
        loss: 0.3,
        ..Network::default()
    };
    let auction = SwarmMethod::Auction { epsilon: EPSILON };
    let mut swarm = LiveSwarm::new(game, auction, &network, None, 3).unwrap();
    for j in 0..3 {
        swarm.task_appears(j);
    }
    settle_keeping(&mut swarm, &points, &[], 0);
    let tasks = |swarm: &LiveSwarm| (0..4).map(|i| swarm.task_of(i)).collect::<Vec<_>>();
    assert_eq!(tasks(&swarm), [Some(0), Some(0), Some(1), Some(1)]);
    swarm.task_done(1);
    settle_keeping(&mut swarm, &points, &[0, 1], 0);
    assert_eq!(tasks(&swarm), [Some(0), Some(0), Some(2), Some(2)]);
}

#[test]
fn the_team_auction_repeats_per_seed() {
    let inst = scarce(30, 4, 5);
    let network = Network {
        loss: 0.3,
        activation: 0.5,
        ..Network::default()
    };
    let run = |seed| {
        let r = Swarm::auction(EPSILON, network.clone(), seed)
            .run(&inst)
            .unwrap();
        (r.rounds, r.messages, r.welfare.to_bits(), r.assignment)
    };
    assert_eq!(run(3), run(3));
}

#[test]
fn a_skill_place_goes_to_the_robot_that_holds_the_skill() {
    // In `skill_by_hand`, robot 2 takes the skill place, robot 0 the other (robot 1 is
    // 0.085 dearer there, far more than 2Nε), robot 1 the spare task.
    let inst = skill_by_hand();
    for (name, network) in networks() {
        let r = Swarm::auction(EPSILON, network, 1).run(&inst).unwrap();
        let tasks = r.assignment.expect("converged").tasks().to_vec();
        assert_eq!(
            tasks,
            [Some(TaskId(0)), Some(TaskId(1)), Some(TaskId(0))],
            "{name}"
        );
        assert!((r.welfare - skill_by_hand_welfare()).abs() < 1e-9, "{name}");
    }
}

/// On skill games with enough holders, every team the auction forms is complete and
/// holds its skills (its skill places went to holders), over every network, at 95 % of
/// the optimum or more and 96.5 % on average.
#[test]
fn the_auction_forms_teams_that_hold_their_skills() {
    let (mut earning, mut shares) = (0, Vec::new());
    for (idx, (n, m)) in [(20, 4), (30, 5), (40, 6)].into_iter().enumerate() {
        let plain = scarce(n, m, 60 + idx as u64);
        let skills: Vec<Vec<u32>> = (0..n)
            .map(|i| vec![u32::from(i % 2 == 0), u32::from(i % 3 == 0)])
            .collect();
        let requires: Vec<Vec<u32>> = (0..m).map(|j| vec![1 + (j % 2) as u32, 1]).collect();
        let inst = plain
            .clone()
            .with_teams(
                plain.task_ids().map(|j| plain.min_team(j)).collect(),
                &skills,
                &requires,
            )
            .unwrap();
        let best = TeamOptimum::default().solve(&inst).unwrap().welfare;
        for (name, network) in networks() {
            let r = Swarm::auction(EPSILON, network, 2).run(&inst).unwrap();
            let a = r.assignment.expect("converged");
            let held = inst.skills_held(&a);
            for j in inst.task_ids().filter(|&j| a.size(j) > 0) {
                let why = format!("{name}, N = {n}, task {j:?}");
                assert!(a.size(j) >= inst.min_team(j), "{why}");
                assert!(inst.skills_met(j, &held[j.index() * 2..][..2]), "{why}");
                earning += 1;
            }
            assert!(
                r.welfare <= best + 1e-9 && r.welfare >= 0.95 * best,
                "{name}: {} vs {best}",
                r.welfare
            );
            shares.push(r.welfare / best);
        }
    }
    assert!(earning > 20, "{earning}");
    // The range docs/teams.md measures on the committed skill games starts at 96.5 %.
    let mean = shares.iter().sum::<f64>() / shares.len() as f64;
    assert!(mean >= 0.965, "{mean}");
}

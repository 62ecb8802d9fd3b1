//! The welfare climb on random assignments of small games of every named family: the
//! welfare never falls, the rules hold, and where it stops no single move or swap gains
//! (checked against the game's own welfare, change by change).

use afg_baseline::climb;
use afg_game::{Assignment, Family, Instance, Point, RobotId, Task, TaskId};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Every robot at a random task with room (the void where none has room, or now and
/// then where the game has one).
fn random_assignment(inst: &Instance, rng: &mut ChaCha8Rng) -> Assignment {
    let mut a = Assignment::unassigned(inst.num_robots(), inst.num_tasks());
    for i in inst.robot_ids() {
        if inst.allows_void() && rng.random_bool(0.2) {
            continue;
        }
        let open: Vec<TaskId> = inst
            .task_ids()
            .filter(|&j| a.has_room(inst, i, j))
            .collect();
        if !open.is_empty() {
            a.set(i, Some(open[rng.random_range(0..open.len())]));
        }
    }
    a
}

/// The largest welfare a single move or swap of `a` reaches, by the game's welfare.
fn best_neighbour(inst: &Instance, a: &Assignment) -> f64 {
    let mut places: Vec<Option<TaskId>> = inst.task_ids().map(Some).collect();
    if inst.allows_void() {
        places.push(None);
    }
    let mut best = f64::NEG_INFINITY;
    let robots: Vec<RobotId> = inst.robot_ids().collect();
    for &i in &robots {
        for &to in &places {
            if to == a.task_of(i) || to.is_some_and(|b| !a.has_room(inst, i, b)) {
                continue;
            }
            let mut b = a.clone();
            b.set(i, to);
            best = best.max(inst.welfare(&b));
        }
        for &k in &robots {
            let (x, y) = (a.task_of(i), a.task_of(k));
            if x != y {
                let mut b = a.clone();
                b.set(i, y);
                b.set(k, x);
                best = best.max(inst.welfare(&b));
            }
        }
    }
    best
}

#[test]
fn the_climb_gains_until_no_move_or_swap_does_on_every_family() {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let (mut climbed, mut games) = (0, 0);
    for family in Family::ALL {
        for seed in 0..6u64 {
            let inst = family
                .config(10 + seed as usize, 4, seed)
                .unwrap()
                .generate()
                .unwrap();
            let mut a = random_assignment(&inst, &mut rng);
            let assigned = a.num_assigned();
            let before = inst.welfare(&a);
            let changes = climb(&inst, &mut a);
            let after = inst.welfare(&a);
            let at = format!("{family} seed {seed}");
            inst.check(&a).unwrap();
            assert!(after >= before - 1e-9, "{at}: {after} < {before}");
            if !inst.allows_void() {
                assert_eq!(
                    a.num_assigned(),
                    assigned,
                    "{at}: a robot left for a void the game lacks"
                );
            }
            let tol = 1e-9 * after.abs().max(1.0);
            assert!(
                best_neighbour(&inst, &a) <= after + tol,
                "{at}: a single change still gains"
            );
            climbed += usize::from(changes > 0 && after > before + tol);
            games += 1;
        }
    }
    assert!(climbed > games / 2, "{climbed} of {games} climbed");
}

/// Two robots at the origin with three tasks there, rewards and thresholds `(reward,
/// min_team)`, starting at tasks `start`: no cost, so the welfare is the coalitions'
/// values alone.
fn stuck_game(tasks: [(f64, usize); 3], start: [u32; 2]) -> (Instance, Assignment) {
    let task = |reward| Task {
        position: Point::new(0.0, 0.0),
        reward,
        eps: 2.0,
        capacity: None,
    };
    let inst = Instance::new(
        vec![Point::new(0.0, 0.0); 2],
        tasks.iter().map(|&(r, _)| task(r)).collect(),
        1.0,
    )
    .unwrap()
    .with_teams(tasks.iter().map(|&(_, k)| k).collect(), &[], &[])
    .unwrap();
    let a = Assignment::from_tasks(&inst, start.map(|j| Some(TaskId(j))).to_vec()).unwrap();
    (inst, a)
}

/// The best welfare of any assignment of a two-robot game, by brute force.
fn brute_force_best(inst: &Instance) -> f64 {
    let tasks: Vec<TaskId> = inst.task_ids().collect();
    let mut best = f64::NEG_INFINITY;
    for &x in &tasks {
        for &y in &tasks {
            let a = Assignment::from_tasks(inst, vec![Some(x), Some(y)]).unwrap();
            best = best.max(inst.welfare(&a));
        }
    }
    best
}

/// Where no single move or swap gains, the climb still dissolves a team worth less
/// than its members elsewhere (a pair earning F(2) = 2 ln 3 / ln 2 ≈ 3.17 at task 2,
/// against 2 + 2 apart) and staffs a task no single robot can open (a pair earning
/// 10 ln 3 / ln 2 ≈ 15.85 against 1 + 1): both reach the brute-force optimum.
#[test]
fn the_climb_dissolves_and_staffs_whole_teams_where_no_single_change_gains() {
    let dissolve = stuck_game([(2.0, 1), (2.0, 1), (2.0, 2)], [2, 2]);
    let open = stuck_game([(1.0, 1), (1.0, 1), (10.0, 2)], [0, 1]);
    for (name, (inst, mut a), ends_at) in [("dissolve", dissolve, [0, 1]), ("open", open, [2, 2])] {
        let start = inst.welfare(&a);
        assert!(
            best_neighbour(&inst, &a) <= start + 1e-12,
            "{name}: not stuck"
        );
        assert!(climb(&inst, &mut a) > 0, "{name}");
        let mut tasks: Vec<usize> = a.tasks().iter().map(|t| t.unwrap().index()).collect();
        tasks.sort_unstable();
        assert_eq!(tasks, ends_at, "{name}");
        assert!(
            (inst.welfare(&a) - brute_force_best(&inst)).abs() < 1e-12,
            "{name}"
        );
    }
}

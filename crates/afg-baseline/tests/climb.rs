//! The welfare climb on random assignments of small games of every named family: the
//! welfare never falls, the rules hold, and where it stops no single move or swap gains
//! (checked against the game's own welfare, change by change).

use afg_baseline::climb;
use afg_game::{Assignment, Family, Instance, RobotId, TaskId};
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

//! The exact team solver on small games of every named family, against brute force:
//! clusters, heavy tails, constant thresholds, rewards and ε per task, sparse and many
//! skills, the void with capacities, and all of them mixed.

mod common;

use afg_baseline::{Allocator, Optimum, TeamOptimum};
use afg_game::Family;

use common::brute_force;

#[test]
fn the_team_optimum_equals_brute_force_on_small_games_of_every_family() {
    let mut checked = 0;
    for family in Family::ALL {
        for seed in 0..8u64 {
            let (robots, tasks) = (5 + seed as usize % 3, 2 + seed as usize % 3);
            let inst = family
                .config(robots, tasks, seed)
                .unwrap()
                .generate()
                .unwrap();
            let best = TeamOptimum::default().solve(&inst).unwrap();
            let brute = brute_force(&inst);
            let tol = 1e-9 * brute.abs().max(1.0);
            let at = format!("{family} seed {seed} ({robots} × {tasks})");
            assert!(
                best.proven && (best.welfare - brute).abs() < tol,
                "{at}: {} vs {brute}",
                best.welfare
            );
            assert!((inst.welfare(&best.assignment) - brute).abs() < tol, "{at}");
            inst.check(&best.assignment).unwrap();
            let opt = Optimum.allocate(&inst).unwrap().assignment;
            assert!((inst.welfare(&opt) - brute).abs() < tol, "{at}");
            checked += 1;
        }
    }
    assert_eq!(checked, 80);
}

/// The skill families on games large enough that the search branches on robots and
/// rules pairs out as it finds better assignments (8–9 robots, 3 tasks), against brute
/// force.
#[test]
fn the_skill_optimum_equals_brute_force_where_the_search_rules_pairs_out() {
    let mut branched = 0;
    for family in Family::ALL.into_iter().filter(|f| f.draws_skills()) {
        for seed in 0..40u64 {
            let robots = 8 + seed as usize % 2;
            let inst = family.config(robots, 3, seed).unwrap().generate().unwrap();
            let best = TeamOptimum::default().solve(&inst).unwrap();
            let brute = brute_force(&inst);
            let tol = 1e-9 * brute.abs().max(1.0);
            assert!(
                best.proven && (best.welfare - brute).abs() < tol,
                "{family} seed {seed}: {} vs {brute}",
                best.welfare
            );
            branched += usize::from(best.nodes > 3);
        }
    }
    assert!(branched >= 20, "{branched}");
}

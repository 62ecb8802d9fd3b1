//! The exact team solver stopped inside its root's relaxation (a time limit already
//! spent, a stop flag already set): it still answers with a real assignment and a
//! proven bound, from the prices the relaxation had reached.

use std::sync::Arc;
use std::sync::atomic::AtomicBool;

use afg_baseline::{Allocator, TeamOptimum};
use afg_game::{Family, Instance};

/// `exact` stopped by a flag set before it starts.
fn stopped_at_once(instance: &Instance) -> afg_baseline::TeamSolution {
    TeamOptimum {
        stop: Some(Arc::new(AtomicBool::new(true))),
        ..TeamOptimum::default()
    }
    .solve(instance)
    .unwrap()
}

#[test]
fn a_root_stopped_on_every_family_answers_validly_below_a_true_bound() {
    let mut stopped_roots = 0;
    for family in Family::ALL {
        for seed in 0..3u64 {
            let inst = family.config(60, 8, seed).unwrap().generate().unwrap();
            let exact = TeamOptimum::default().solve(&inst).unwrap();
            let cut = stopped_at_once(&inst);
            let at = format!("{family} seed {seed}");
            inst.check(&cut.assignment).unwrap();
            assert!(
                (inst.welfare(&cut.assignment) - cut.welfare).abs() < 1e-9,
                "{at}"
            );
            assert!(cut.welfare <= exact.welfare + 1e-9, "{at}");
            assert!(
                cut.bound >= exact.welfare - 1e-9 * exact.welfare.abs().max(1.0),
                "{at}: bound {} below the optimum {}",
                cut.bound,
                exact.welfare
            );
            assert!(!cut.proven || cut.welfare >= exact.welfare - 1e-9, "{at}");
            stopped_roots += usize::from(cut.nodes == 0);
        }
    }
    // From zero prices most roots route more units than the flag lets through.
    assert!(stopped_roots >= 15, "{stopped_roots} of 30 roots stopped");
}

#[test]
fn a_large_root_stopped_before_its_finest_level_bounds_tightly_and_answers() {
    // 2 400 robots: the root starts from the prices of its 300-robot subsample, and
    // the flag stops it there. Those prices already bound the game within a few %.
    let inst = Family::Scarce
        .config(2400, 60, 5)
        .unwrap()
        .generate()
        .unwrap();
    let exact = TeamOptimum::default().solve(&inst).unwrap();
    let cut = stopped_at_once(&inst);
    assert_eq!(cut.nodes, 0);
    assert!(!cut.proven);
    inst.check(&cut.assignment).unwrap();
    assert!(cut.assignment.is_complete());
    assert!(cut.bound >= exact.welfare - 1e-9 * exact.welfare);
    assert!(
        cut.bound <= 1.05 * exact.welfare,
        "bound {} vs optimum {}",
        cut.bound,
        exact.welfare
    );
    // The teams the prices left at least half staffed, completed with the nearest
    // robots: most of the optimum.
    assert!(
        cut.welfare >= 0.75 * exact.welfare,
        "{} vs {}",
        cut.welfare,
        exact.welfare
    );
    // As an allocator: the answer and its bound.
    let allocation = TeamOptimum {
        stop: Some(Arc::new(AtomicBool::new(true))),
        ..TeamOptimum::default()
    }
    .allocate(&inst)
    .unwrap();
    assert_eq!(allocation.assignment, cut.assignment);
    assert_eq!(allocation.stats.bound, Some(cut.bound));
}

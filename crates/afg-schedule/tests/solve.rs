//! The scheduler and the bound against brute force on small instances, on random
//! instances of both families, and on DCMRTA's published set.

use std::path::PathBuf;

use afg_schedule::{Family, Generate, Schedule, ScheduleInstance, SolveOptions, read_instances};
use proptest::prelude::*;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn steps(n: u64, seed: u64) -> SolveOptions {
    SolveOptions {
        steps: Some(n),
        seed,
        ..SolveOptions::default()
    }
}

/// Robots at a random depot, tasks needing 1 or 2 robots, speed 0.2, max_wait 10.
fn small(robots: usize, tasks: usize, seed: u64) -> ScheduleInstance {
    let mut inst = Generate {
        family: Family::Dcmrta,
        robots,
        tasks,
        seed,
    }
    .instance()
    .unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    for t in &mut inst.tasks {
        t.min_team = Some(rng.random_range(1..=2));
    }
    inst
}

/// Every ordering of `items`.
fn orderings(items: &[usize]) -> Vec<Vec<usize>> {
    if items.len() <= 1 {
        return vec![items.to_vec()];
    }
    let mut all = Vec::new();
    for k in 0..items.len() {
        let mut rest = items.to_vec();
        let first = rest.remove(k);
        for mut tail in orderings(&rest) {
            tail.insert(0, first);
            all.push(tail);
        }
    }
    all
}

/// Whether the robots in `set` (a bit mask) staff task j: enough of them, every skill covered.
fn staffs(inst: &ScheduleInstance, j: usize, set: u32) -> bool {
    let members: Vec<usize> = (0..inst.num_robots())
        .filter(|&i| set >> i & 1 == 1)
        .collect();
    members.len() >= inst.tasks[j].team_floor()
        && (0..inst.num_skills()).all(|s| {
            members.iter().map(|&i| inst.robot_skill(i, s)).sum::<u32>() >= inst.task_requires(j, s)
        })
}

/// The least makespan over every schedule whose teams staff their tasks with no member to
/// spare, every order of each robot's tasks, valid under the instance's `max_wait`.
fn brute_force(inst: &ScheduleInstance) -> f64 {
    let (n, m) = (inst.num_robots(), inst.num_tasks());
    let teams: Vec<Vec<u32>> = (0..m)
        .map(|j| {
            (1..1u32 << n)
                .filter(|&set| {
                    staffs(inst, j, set)
                        && (0..n).all(|i| set >> i & 1 == 0 || !staffs(inst, j, set & !(1 << i)))
                })
                .collect()
        })
        .collect();
    let mut best = f64::INFINITY;
    let mut choice = vec![0usize; m];
    loop {
        let mine: Vec<Vec<usize>> = (0..n)
            .map(|i| {
                (0..m)
                    .filter(|&j| teams[j][choice[j]] >> i & 1 == 1)
                    .collect()
            })
            .collect();
        let orders: Vec<Vec<Vec<usize>>> = mine.iter().map(|t| orderings(t)).collect();
        let mut pick = vec![0usize; n];
        loop {
            let schedule = Schedule {
                routes: (0..n).map(|i| orders[i][pick[i]].clone()).collect(),
            };
            if let Ok(run) = inst.evaluate(&schedule)
                && run.is_valid()
            {
                best = best.min(run.makespan);
            }
            if !odometer(&mut pick, |i| orders[i].len()) {
                break;
            }
        }
        if !odometer(&mut choice, |j| teams[j].len()) {
            return best;
        }
    }
}

fn odometer(digits: &mut [usize], base: impl Fn(usize) -> usize) -> bool {
    for (k, d) in digits.iter_mut().enumerate() {
        *d += 1;
        if *d < base(k) {
            return true;
        }
        *d = 0;
    }
    false
}

#[test]
fn the_bound_lies_below_the_optimum_and_the_scheduler_finds_it_on_small_instances() {
    let (mut found, mut cases) = (0, 0);
    for seed in 0..24 {
        let inst = small(3, 4, seed);
        let optimum = brute_force(&inst);
        let bound = inst.lower_bound().makespan;
        let solved = inst.solve(&steps(3_000, seed)).unwrap();
        assert!(
            bound <= optimum + 1e-9,
            "seed {seed}: bound {bound} above the optimum {optimum}"
        );
        assert!(
            solved.makespan() >= optimum - 1e-9,
            "seed {seed}: {} below the optimum {optimum}",
            solved.makespan()
        );
        found += usize::from(solved.makespan() <= optimum + 1e-9);
        cases += 1;
        println!(
            "seed {seed}: bound {bound:.3} optimum {optimum:.3} found {:.3}",
            solved.makespan()
        );
    }
    println!("the scheduler found the optimum on {found} of {cases}");
    assert!(
        found * 10 >= cases * 9,
        "found the optimum on {found} of {cases}"
    );
}

#[test]
fn with_skills_too() {
    // Three robots of three species at three depots; an instance without any schedule
    // within max_wait must be refused, not answered.
    let (mut solved_count, mut none) = (0, 0);
    for seed in 0..16 {
        let inst = Generate {
            family: Family::Heteromrta,
            robots: 3,
            tasks: 4,
            seed,
        }
        .instance()
        .unwrap();
        let optimum = brute_force(&inst);
        let solved = inst.solve(&steps(3_000, seed));
        if optimum.is_infinite() {
            let message = solved.expect_err("no schedule exists").to_string();
            assert!(
                message.contains("found no schedule whose teams all gather within max_wait"),
                "{message}"
            );
            none += 1;
            continue;
        }
        let bound = inst.lower_bound().makespan;
        let found = solved.unwrap().makespan();
        assert!(
            bound <= optimum + 1e-9,
            "seed {seed}: bound {bound} above the optimum {optimum}"
        );
        assert!(
            (found - optimum).abs() < 1e-9,
            "seed {seed}: found {found} against the optimum {optimum}"
        );
        solved_count += 1;
    }
    println!("{solved_count} solved to the optimum, {none} with no valid schedule");
    assert!(solved_count >= 12, "{solved_count} solved");
}

#[test]
fn one_seed_and_step_budget_gives_one_schedule() {
    let inst = Generate {
        family: Family::Dcmrta,
        robots: 8,
        tasks: 20,
        seed: 3,
    }
    .instance()
    .unwrap();
    let a = inst.solve(&steps(2_000, 11)).unwrap();
    let b = inst.solve(&steps(2_000, 11)).unwrap();
    assert_eq!(a.schedule, b.schedule);
    assert_eq!(a.makespan(), b.makespan());
    assert_eq!(a.steps, 2_000);
    let other = inst.solve(&steps(2_000, 12)).unwrap();
    assert_ne!(a.order, other.order, "another seed searches another way");
}

#[test]
fn a_smaller_max_wait_is_kept_and_a_bad_setting_is_refused() {
    let inst = Generate {
        family: Family::Dcmrta,
        robots: 10,
        tasks: 30,
        seed: 5,
    }
    .instance()
    .unwrap();
    let tight = inst
        .solve(&SolveOptions {
            max_wait: Some(2.0),
            ..steps(3_000, 0)
        })
        .unwrap();
    let run = inst.evaluate_with(&tight.schedule, 2.0).unwrap();
    assert!(
        run.is_valid() && run.longest_wait <= 2.0,
        "{}",
        run.longest_wait
    );
    for bad in [
        SolveOptions {
            max_wait: Some(0.0),
            ..steps(10, 0)
        },
        SolveOptions {
            time_limit: Some(f64::NAN),
            ..steps(10, 0)
        },
    ] {
        assert!(inst.solve(&bad).is_err());
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]
    #[test]
    fn every_schedule_is_valid_and_its_makespan_is_the_evaluators_and_above_the_bound(
        seed in 0u64..1_000, robots in 1usize..12, tasks in 1usize..25, skills in any::<bool>(),
    ) {
        let family = if skills { Family::Heteromrta } else { Family::Dcmrta };
        let inst = Generate { family, robots, tasks, seed }.instance().unwrap();
        let solved = inst.solve(&steps(300, seed)).unwrap();
        let run = inst.evaluate(&solved.schedule).unwrap();
        prop_assert!(run.is_valid());
        prop_assert!(run.long_waits.is_empty() && run.longest_wait <= inst.max_wait);
        prop_assert_eq!(run.makespan, solved.makespan());
        prop_assert!(run.visits.iter().flatten().all(|v| v.role == afg_schedule::Role::Team), "no robot is sent where it is not needed");
        let bound = inst.lower_bound();
        prop_assert!(bound.makespan <= run.makespan + 1e-9);
        // Where the time goes adds up to the makespan, and each part is what the run
        // says: the driving is the travel at the instance's speed, the working each
        // team's members times its duration, and neither is below the bound's.
        let use_ = run.time_use();
        let n = robots as f64;
        prop_assert!([use_.working, use_.driving, use_.waiting, use_.idle].iter().all(|&t| t >= -1e-9));
        prop_assert!((use_.working + use_.driving + use_.waiting + use_.idle - run.makespan).abs() <= 1e-9 * run.makespan.max(1.0));
        prop_assert!((use_.driving * n * inst.speed - run.travel).abs() <= 1e-9 * run.travel.max(1.0));
        let members = |j: usize| solved.schedule.routes.iter().filter(|r| r.contains(&j)).count() as f64;
        let work: f64 = inst.tasks.iter().enumerate().map(|(j, t)| members(j) * t.duration).sum();
        prop_assert!((use_.working * n - work).abs() <= 1e-9 * work.max(1.0));
        prop_assert!(bound.work <= work + 1e-9 && bound.driving <= use_.driving * n + 1e-9);
    }
}

#[test]
fn on_dcmrtas_set_every_schedule_keeps_waits_within_10_and_beats_the_best_published() {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../datasets/dcmrta-20a50t");
    let instances = read_instances(&root.join("dcmrta-20a50t.jsonl")).unwrap();
    let published: Vec<serde_json::Value> =
        std::fs::read_to_string(root.join("dcmrta-20a50t-published.jsonl"))
            .unwrap()
            .lines()
            .map(|l| serde_json::from_str(l).unwrap())
            .collect();
    for (inst, row) in instances.iter().zip(&published).take(3) {
        let solved = inst
            .solve(&SolveOptions {
                max_wait: Some(10.0),
                ..steps(20_000, 0)
            })
            .unwrap();
        let run = inst.evaluate_with(&solved.schedule, 10.0).unwrap();
        assert!(run.is_valid());
        let best_published = row["methods"]
            .as_object()
            .unwrap()
            .values()
            .map(|m| m["makespan"].as_f64().unwrap())
            .fold(f64::INFINITY, f64::min);
        assert!(
            run.makespan < best_published,
            "instance {:?}: {} against {best_published}",
            inst.index,
            run.makespan
        );
        assert!(inst.lower_bound().makespan <= run.makespan);
    }
}

/// A schedule given to start from: the search improves on a weak one (the published
/// CTAS-D routes), never returns worse than a valid one (a search of no steps from
/// afg's own schedule gives that schedule back), never returns one that breaks the
/// `max_wait` asked for, and refuses one that is not a schedule of the instance.
#[test]
fn a_start_is_improved_or_given_back() {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../datasets/dcmrta-20a50t");
    let instances = read_instances(&root.join("dcmrta-20a50t.jsonl")).unwrap();
    let published = afg_schedule::read_schedules(&root.join("dcmrta-20a50t-routes.jsonl")).unwrap();
    let (mut given_back, mut bettered) = (0, 0);
    for (inst, record) in instances.iter().zip(&published).take(4) {
        let ctas = record.schedule();
        let ctas_run = inst.evaluate(&ctas).unwrap();
        assert!(ctas_run.is_valid(), "under the set's own max_wait 100");
        let from_ctas = |n: u64| {
            inst.solve(&SolveOptions {
                start: Some(ctas.clone()),
                ..steps(n, 0)
            })
            .unwrap()
        };
        assert!(from_ctas(0).makespan() <= ctas_run.makespan);
        assert!(from_ctas(2_000).makespan() < ctas_run.makespan - 1.0);

        let own = inst.solve(&steps(20_000, 1)).unwrap();
        let again = inst
            .solve(&SolveOptions {
                start: Some(own.schedule.clone()),
                ..steps(0, 2)
            })
            .unwrap();
        assert!(again.makespan() <= own.makespan());
        given_back += usize::from(again.schedule == own.schedule);
        bettered += usize::from(again.makespan() < own.makespan());

        // Under max_wait 10 CTAS-D's routes break it: never given back, only its order used.
        let strict = inst
            .solve(&SolveOptions {
                start: Some(ctas.clone()),
                max_wait: Some(10.0),
                ..steps(0, 0)
            })
            .unwrap();
        assert!(
            !inst
                .evaluate_with(&ctas, 10.0)
                .unwrap()
                .long_waits
                .is_empty()
        );
        assert!(
            inst.evaluate_with(&strict.schedule, 10.0)
                .unwrap()
                .is_valid()
        );
    }
    assert_eq!(given_back + bettered, 4);
    assert!(
        given_back >= 1,
        "{given_back} given back, {bettered} bettered"
    );

    let inst = &instances[0];
    let mut unknown = published[0].schedule();
    unknown.routes[0].push(50);
    let err = inst
        .solve(&SolveOptions {
            start: Some(unknown),
            ..steps(10, 0)
        })
        .unwrap_err()
        .to_string();
    assert!(err.contains("50"), "{err}");
}

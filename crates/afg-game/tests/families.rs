//! The named families of team games: each draws what its name says, seeded, and reads
//! back from its file as it was drawn.

use afg_game::{Family, GOLDEN_RATIO, GeneratorConfig, GeneratorKnobs, Instance, Shape};

fn draw(family: Family, robots: usize, tasks: usize, seed: u64) -> Instance {
    family
        .config(robots, tasks, seed)
        .unwrap()
        .generate()
        .unwrap()
}

fn thresholds(inst: &Instance) -> Vec<usize> {
    inst.task_ids().map(|j| inst.min_team(j)).collect()
}

/// The mean distance from each robot to its nearest task.
fn nearest_task(inst: &Instance) -> f64 {
    let total: f64 = inst
        .robot_ids()
        .map(|i| {
            inst.task_ids()
                .map(|j| inst.distance(i, j))
                .fold(f64::INFINITY, f64::min)
        })
        .sum();
    total / inst.num_robots() as f64
}

#[test]
fn every_family_is_seeded_named_and_reads_back_from_its_file() {
    for family in Family::ALL {
        let inst = draw(family, 60, 6, 3);
        assert_eq!(inst, draw(family, 60, 6, 3), "{family}");
        assert_ne!(inst, draw(family, 60, 6, 4), "{family}");
        assert!(inst.has_teams(), "{family}");
        let text = afg_game::io::dataset_to_jsonl(std::slice::from_ref(&inst));
        assert!(text.contains(&format!("\"family\":\"{family}\"")), "{text}");
        let back = afg_game::io::parse_dataset(&text).unwrap();
        assert_eq!(back, vec![inst.clone()], "{family}");
        assert_eq!(family.name().parse::<Family>(), Ok(family));
        assert_eq!(back[0].generator().unwrap().shape.family, Some(family));
    }
    let err = "uniformish".parse::<Family>().unwrap_err();
    assert!(err.contains("one of scarce, skills, clustered"), "{err}");
    // The paper's game and the committed families draw what they drew before: no shape
    // in the file.
    let scarce = draw(Family::Scarce, 60, 6, 3);
    let knobs = GeneratorKnobs {
        min_team: Some((10, 20)),
        ..GeneratorKnobs::default()
    };
    let by_hand = knobs.config(60, 6, 3).unwrap().generate().unwrap();
    assert_eq!(thresholds(&scarce), thresholds(&by_hand));
    assert!(GeneratorConfig::paper(60, 6, 3).shape.is_plain());
}

#[test]
fn each_family_draws_what_its_name_says() {
    let seeds = 0..10u64;
    // clustered: robots near tasks (the same centres), far nearer than uniform
    let mean = |family, f: fn(&Instance) -> f64| {
        seeds
            .clone()
            .map(|s| f(&draw(family, 200, 20, s)))
            .sum::<f64>()
            / 10.0
    };
    let (clustered, scarce) = (
        mean(Family::Clustered, nearest_task),
        mean(Family::Scarce, nearest_task),
    );
    assert!(clustered < 0.6 * scarce, "{clustered} vs {scarce}");
    // heavy-tail: thresholds 1..=N/4, most of them 1–3, a few far above
    let heavy: Vec<usize> = seeds
        .clone()
        .flat_map(|s| thresholds(&draw(Family::HeavyTail, 200, 20, s)))
        .collect();
    assert!(heavy.iter().all(|&k| (1..=50).contains(&k)));
    let few = heavy.iter().filter(|&&k| k <= 3).count() as f64 / heavy.len() as f64;
    assert!((0.7..0.9).contains(&few), "{few}"); // P(k ≤ 3) = 1 − 4^−1.2 ≈ 0.81
    assert!(heavy.iter().any(|&k| k >= 20));
    // constant: ⌈1.5 N/M⌉ everywhere
    assert!(
        thresholds(&draw(Family::Constant, 200, 20, 1))
            .iter()
            .all(|&k| k == 15)
    );
    // team-rewards: the reward per member of the threshold within the scarce range's
    // reward over its mean threshold, and ε per task in [φ, 2N/M]
    let rich = draw(Family::TeamRewards, 200, 20, 2);
    for j in rich.task_ids() {
        let per_member = rich.task(j).reward / rich.min_team(j) as f64;
        assert!(
            (10.0 / 15.0 - 1e-9..=20.0 / 15.0 + 1e-9).contains(&per_member),
            "{per_member}"
        );
        assert!((GOLDEN_RATIO..=20.0).contains(&rich.task(j).eps));
    }
    assert!(
        rich.task_ids()
            .any(|j| rich.task(j).eps != rich.task(afg_game::TaskId(0)).eps)
    );
    // sparse-skills: 4 skills, about half the tasks requiring none
    let sparse = draw(Family::SparseSkills, 200, 40, 3);
    assert_eq!(sparse.num_skills(), 4);
    let bare = sparse
        .task_ids()
        .filter(|&j| sparse.requires(j).iter().all(|&r| r == 0))
        .count();
    assert!((10..=32).contains(&bare), "{bare}");
    assert!(
        sparse
            .task_ids()
            .all(|j| sparse.requires(j).iter().all(|&r| r <= 3))
    );
    // many-skills: 6 skills, 0–1 of each
    let many = draw(Family::ManySkills, 200, 20, 4);
    assert_eq!(many.num_skills(), 6);
    // void-capacity: GRAPE's game, capacities, β = 2
    let void = draw(Family::VoidCapacity, 200, 20, 5);
    assert!(void.allows_void() && void.beta() == 2.0);
    assert!(
        void.task_ids()
            .all(|j| (10..=15).contains(&void.capacity(j)))
    );
    // mixed: the void in some games and not others, β spread over [0.5, 2]
    let mixed: Vec<Instance> = (0..30).map(|s| draw(Family::Mixed, 60, 6, s)).collect();
    let voids = mixed.iter().filter(|i| i.allows_void()).count();
    assert!((4..=18).contains(&voids), "{voids}");
    assert!(mixed.iter().all(|i| (0.5..=2.0).contains(&i.beta())));
    assert!(mixed.iter().any(|i| i.beta() < 1.0) && mixed.iter().any(|i| i.beta() > 1.5));
}

#[test]
fn knobs_beside_a_family_override_it_and_bad_shapes_are_refused() {
    let knobs = GeneratorKnobs {
        family: Some(Family::VoidCapacity),
        beta: Some(0.5),
        min_team: Some((3, 3)),
        ..GeneratorKnobs::default()
    };
    let inst = knobs.config(30, 5, 1).unwrap().generate().unwrap();
    assert!(inst.allows_void() && inst.beta() == 0.5);
    assert!(thresholds(&inst).iter().all(|&k| k == 3));
    let mut cfg = GeneratorConfig::paper(30, 5, 1);
    for (shape, says) in [
        (
            Shape {
                clusters: Some(afg_game::Clusters {
                    count: 0,
                    spread: 0.1,
                }),
                ..Shape::default()
            },
            "at least 1 centre",
        ),
        (
            Shape {
                threshold_tail: Some(f64::NAN),
                ..Shape::default()
            },
            "tail α",
        ),
        (
            Shape {
                eps_min: Some(1.0),
                ..Shape::default()
            },
            "golden ratio",
        ),
        (
            Shape {
                skill_tasks: Some(1.5),
                ..Shape::default()
            },
            "between 0 and 1",
        ),
    ] {
        cfg.shape = shape;
        let err = cfg.generate().unwrap_err().to_string();
        assert!(err.contains(says), "{err}");
    }
    assert!(Family::Scarce.config(0, 5, 1).is_err());
}

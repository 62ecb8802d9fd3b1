//! The staffing model: its features by hand, training (seeded, resumable, refusing
//! another run's labels), the saved model as an allocator.

use std::path::{Path, PathBuf};

use afg_baseline::{AllocError, TeamOptimum, TeamRelaxation};
use afg_game::{GameSize, Instance, Point, Task};
use afg_learn::LearnError;
use afg_learn::run::{ModelOptions, load_model};
use afg_learn::staffing::{
    STAFF_FEATURES, StaffingModel, StaffingTrainConfig, StaffingTrainer, scarce_game,
    staffing_features,
};

fn tiny() -> StaffingTrainConfig {
    let mut config = StaffingTrainConfig::new(3);
    config.sizes = vec![GameSize {
        robots: 30,
        tasks: 4,
    }];
    (
        config.games,
        config.validation_games,
        config.epochs,
        config.batch,
    ) = (12, 3, 4, 4);
    config
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("afg-staffing-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

fn train(config: StaffingTrainConfig, dir: &Path) -> Result<StaffingModel, LearnError> {
    StaffingTrainer::new(config)?.run_in(dir, "afg train-staffing".into(), |_| (), |_| ())?;
    StaffingModel::load(&dir.join(StaffingModel::FILE_NAME))
}

/// Two tasks at 0 and 1 on the x axis (reward 4, eps 2, uncapped) and `robots`.
fn line_game(robots: Vec<Point>) -> Instance {
    let task = |x: f64| Task {
        position: Point::new(x, 0.0),
        reward: 4.0,
        eps: 2.0,
        capacity: None,
    };
    Instance::new(robots, vec![task(0.0), task(1.0)], 1.0).unwrap()
}

/// Two tasks at the ends of a line, four robots: thresholds 2 and 3, so both cannot
/// be staffed from a relaxation that fills the first and leaves the second empty.
#[test]
fn features_by_hand() {
    let robots = vec![Point::new(0.0, 0.0); 4];
    let inst = line_game(robots).with_teams(vec![2, 3], &[], &[]).unwrap();
    let root = TeamRelaxation {
        sizes: vec![4, 0],
        prices: vec![1.0, 0.0],
        bound: 0.0,
    };
    let f = staffing_features(&inst, &root);
    assert_eq!(f.len(), 2 * STAFF_FEATURES);
    let (a, b) = f.split_at(STAFF_FEATURES);
    // fill n/k (capped at 3), empty, full, k / (N/M) with N/M = 2.
    assert_eq!(&a[..4], &[2.0, 0.0, 1.0, 1.0]);
    assert_eq!(&b[..4], &[0.0, 1.0, 0.0, 1.5]);
    // Thresholds of the tasks filled more, then all thresholds, over N = 4.
    assert_eq!((a[7], b[7]), (0.0, 0.5));
    assert_eq!((a[8], b[8]), (1.25, 1.25));
    // Neither task is unstaffable; without skills, every skill feature is neutral.
    assert_eq!((a[9], b[9]), (0.0, 0.0));
    assert_eq!(
        (&a[10..], &b[10..]),
        (&[1.0, 0.0, 3.0][..], &[1.0, 0.0, 3.0][..])
    );
    // A member's value at the threshold, F(k)/k, over their mean; the price over it;
    // less the nearest k robots' mean cost (0 at the first task, 1 at the second).
    let v = |j: u32, k: f64| inst.value_function(afg_game::TaskId(j)).value(k as usize) / k;
    let unit = (v(0, 2.0) + v(1, 3.0)) / 2.0;
    let close = |x: f32, y: f64| (f64::from(x) - y).abs() < 1e-5;
    assert!(close(a[4], v(0, 2.0) / unit) && close(b[4], v(1, 3.0) / unit));
    assert!(close(a[5], 1.0 / unit) && close(b[5], 0.0));
    assert!(close(a[6], v(0, 2.0) / unit) && close(b[6], (v(1, 3.0) - 1.0) / unit));
}

/// Three robots on a line at 0, 0.1 and 0.5; task 0 at 0 needs two robots and one of
/// skill 0, which only the furthest robot holds; task 1 at 1 needs one robot and no
/// skill.
#[test]
fn skill_features_by_hand() {
    let robots = [0.0, 0.1, 0.5].map(|x| Point::new(x, 0.0)).to_vec();
    let inst = line_game(robots)
        .with_teams(
            vec![2, 1],
            &[vec![0], vec![0], vec![1]],
            &[vec![1], vec![0]],
        )
        .unwrap();
    let root = TeamRelaxation {
        sizes: vec![2, 1],
        prices: vec![0.0, 0.0],
        bound: 0.0,
    };
    let f = staffing_features(&inst, &root);
    let (a, b) = f.split_at(STAFF_FEATURES);
    let v = |j: u32, k: f64| inst.value_function(afg_game::TaskId(j)).value(k as usize) / k;
    let unit = (v(0, 2.0) + v(1, 1.0)) / 2.0;
    // Task 0: its two nearest robots hold none of skill 0 (cover 0); its holder is 0.4
    // further than the second nearest; one robot holds it for one required in all.
    assert_eq!(a[10], 0.0);
    assert!((f64::from(a[11]) - 0.4 / unit).abs() < 1e-5, "{}", a[11]);
    assert_eq!(a[12], 1.0);
    // Task 1 requires nothing.
    assert_eq!(&b[10..], &[1.0, 0.0, 3.0]);
}

#[test]
fn the_same_seed_gives_the_same_weights_and_a_stopped_labelling_resumes() {
    let (one, two) = (scratch("one"), scratch("two"));
    let first = train(tiny(), &one).unwrap();
    // A run stopped after half its games: the labels it wrote (in the order the
    // games finished, not the run's) are read back, the rest solved, and the weights
    // come out the same.
    let labels = std::fs::read_to_string(one.join("labels.jsonl")).unwrap();
    let lines: Vec<&str> = labels.lines().collect();
    let half: String = [7, 2, 0, 5, 3, 11]
        .iter()
        .map(|&k| format!("{}\n", lines[k]))
        .collect();
    std::fs::create_dir_all(&two).unwrap();
    std::fs::write(two.join("labels.jsonl"), half).unwrap();
    let resumed = train(tiny(), &two).unwrap();
    assert_eq!(resumed, first);
    assert_eq!(
        std::fs::read_to_string(two.join("labels.jsonl")).unwrap(),
        labels
    );
    // Another seed's run refuses these labels rather than training on them.
    let mut other = tiny();
    other.seed = 4;
    std::fs::remove_file(two.join(StaffingModel::FILE_NAME)).unwrap();
    let err = train(other, &two).unwrap_err().to_string();
    assert!(err.contains("another run's games"), "{err}");
    for dir in [one, two] {
        std::fs::remove_dir_all(dir).unwrap();
    }
}

/// A run on named families draws `games` of each family per size and records which in
/// every label; a family's games are the same in each run that names it, so a mixture
/// reads back the labels of a run on one of its families and solves only the rest. A
/// model reads the skill features where any of its families draws skills.
#[test]
fn a_run_on_named_families_draws_each_family_and_reuses_another_runs_labels() {
    use afg_game::Family;
    use afg_learn::staffing::LabelledGame;
    let read = |path: &Path| -> Vec<LabelledGame> {
        let text = std::fs::read_to_string(path).unwrap();
        text.lines()
            .map(|l| serde_json::from_str(l).unwrap())
            .collect()
    };
    let with = |families: Vec<Family>| {
        let mut config = tiny();
        (config.games, config.validation_games) = (3, 1);
        config.families = families;
        config
    };
    let (one, both) = (scratch("one-family"), scratch("two-families"));
    std::fs::create_dir_all(&one).unwrap();
    let mut trainer = StaffingTrainer::new(with(vec![Family::Constant])).unwrap();
    trainer
        .label(Some(&one.join("labels.jsonl")), |_| ())
        .unwrap();
    let constant = read(&one.join("labels.jsonl"));
    assert_eq!(constant.len(), 3);
    // ⌈1.5 N/M⌉ = 12 on every task of 30 robots × 4 tasks
    assert!(
        constant
            .iter()
            .all(|g| g.draw.family == Some(Family::Constant)
                && g.thresholds.iter().all(|&k| k == 12))
    );

    let config = with(vec![Family::Constant, Family::HeavyTail]);
    assert_eq!(config.training_game_count(), 6);
    assert!(!config.reads_skills());
    assert!(with(vec![Family::Constant, Family::ManySkills]).reads_skills());
    std::fs::create_dir_all(&both).unwrap();
    // The one-family run's labels, marked (a welfare no solve gives) to tell them apart.
    let marked: Vec<LabelledGame> = (constant.iter().cloned())
        .map(|g| LabelledGame { welfare: -1.0, ..g })
        .collect();
    let text: String = (marked.iter())
        .map(|g| serde_json::to_string(g).unwrap() + "\n")
        .collect();
    std::fs::write(both.join("labels.jsonl"), text).unwrap();
    let mut trainer = StaffingTrainer::new(config).unwrap();
    trainer
        .label(Some(&both.join("labels.jsonl")), |_| ())
        .unwrap();
    let mixture = read(&both.join("labels.jsonl"));
    assert_eq!(mixture[..3], marked[..]);
    assert!(
        mixture[3..]
            .iter()
            .all(|g| g.draw.family == Some(Family::HeavyTail))
    );
    let heavy = Family::HeavyTail
        .config(30, 4, mixture[3].draw.seed)
        .unwrap()
        .generate()
        .unwrap();
    let thresholds: Vec<usize> = heavy.task_ids().map(|j| heavy.min_team(j)).collect();
    assert_eq!(mixture[3].thresholds, thresholds);
    assert!(mixture[3..].iter().all(|g| g.welfare > 0.0));
    for dir in [one, both] {
        std::fs::remove_dir_all(dir).unwrap();
    }
}

#[test]
fn bad_settings_and_files_are_refused() {
    let mut config = tiny();
    config.sizes.clear();
    assert!(matches!(
        StaffingTrainer::new(config),
        Err(LearnError::InvalidConfig(_))
    ));
    let mut config = tiny();
    config.label_time_limit = 0.0;
    assert!(StaffingTrainer::new(config).is_err());
    // Named families draw their own skills: a skill draw beside them is refused.
    let mut config = tiny();
    config.families = vec![afg_game::Family::Constant];
    config.skills = Some(
        afg_game::Family::Skills
            .config(30, 4, 0)
            .unwrap()
            .skills
            .unwrap(),
    );
    let err = StaffingTrainer::new(config).err().unwrap().to_string();
    assert!(err.contains("not both"), "{err}");
    let mut trainer = StaffingTrainer::new(tiny()).unwrap();
    assert!(trainer.epoch().unwrap_err().to_string().contains("label"));

    let dir = scratch("files");
    let model = train(tiny(), &dir).unwrap();
    let path = dir.join(StaffingModel::FILE_NAME);
    let text = std::fs::read_to_string(&path).unwrap();
    std::fs::write(&path, &text[..text.len() / 2]).unwrap();
    assert!(matches!(
        StaffingModel::load(&path),
        Err(LearnError::Weights { .. })
    ));
    let mut wider = model.clone();
    wider.training.network.hidden += 1;
    wider.save(&path).unwrap();
    let err = StaffingModel::load(&path).unwrap_err().to_string();
    assert!(err.contains("width"), "{err}");
    std::fs::remove_dir_all(dir).unwrap();
}

/// The run directory loads as an allocator that places the network's staffing:
/// a valid assignment below the optimum, every task at or above its threshold or
/// earning nothing; options that do not apply and skill games are refused.
#[test]
fn a_trained_run_is_an_allocator_for_threshold_games() {
    let dir = scratch("allocator");
    train(tiny(), &dir).unwrap();
    let policy = load_model(&dir, ModelOptions::default()).unwrap();
    assert_eq!(policy.name(), "staffing");
    for seed in 0..5 {
        let inst = scarce_game(
            GameSize {
                robots: 40,
                tasks: 5,
            },
            None,
            seed,
        )
        .unwrap();
        let out = policy.allocate(&inst).unwrap().assignment;
        inst.check(&out).unwrap();
        let best = TeamOptimum::default().solve(&inst).unwrap().welfare;
        assert!(inst.welfare(&out) <= best + 1e-9);
    }
    let one_shot = ModelOptions {
        one_shot: true,
        ..ModelOptions::default()
    };
    let err = load_model(&dir, one_shot).err().unwrap().to_string();
    assert!(err.contains("staffing model"), "{err}");
    let inst = scarce_game(
        GameSize {
            robots: 20,
            tasks: 3,
        },
        None,
        1,
    )
    .unwrap();
    let skills = inst
        .clone()
        .with_teams(
            (0..3).map(|j| inst.min_team(afg_game::TaskId(j))).collect(),
            &vec![vec![1]; 20],
            &vec![vec![2]; 3],
        )
        .unwrap();
    assert!(matches!(
        policy.allocate(&skills),
        Err(AllocError::TeamsNotSupported { .. })
    ));
    std::fs::remove_dir_all(dir).unwrap();
}

/// A model trained on skill games reads the skill features, keeps its skills in its
/// file, and plays skill games: valid assignments at or below the optimum, whose full
/// teams nearly all hold their skills.
#[test]
fn a_run_trained_on_skill_games_plays_them() {
    let dir = scratch("skills");
    let mut config = tiny();
    config.skills = Some(afg_game::SkillDraw {
        count: 2,
        share: 0.3,
        requires: afg_game::CountRange { min: 1, max: 3 },
    });
    let model = train(config.clone(), &dir).unwrap();
    assert_eq!(model.training.skills, config.skills);
    assert_eq!(model.training.input_width(), 2 * STAFF_FEATURES);
    let policy = load_model(&dir, ModelOptions::default()).unwrap();
    let (mut earning, mut games) = (0, 0);
    for seed in 0..5 {
        let size = GameSize {
            robots: 40,
            tasks: 5,
        };
        let inst = scarce_game(size, config.skills, seed).unwrap();
        let out = policy.allocate(&inst).unwrap().assignment;
        inst.check(&out).unwrap();
        let best = TeamOptimum::default().solve(&inst).unwrap().welfare;
        assert!(inst.welfare(&out) <= best + 1e-9);
        // Every task it fills to its threshold holds its skills: the placement brings
        // them.
        let held = inst.skills_held(&out);
        for j in inst.task_ids().filter(|&j| out.size(j) >= inst.min_team(j)) {
            games += 1;
            earning += usize::from(inst.skills_met(j, &held[j.index() * 2..][..2]));
        }
    }
    assert!(earning * 10 >= games * 9, "{earning} of {games}");
    std::fs::remove_dir_all(dir).unwrap();
}

proptest::proptest! {
    /// The knapsack is exact: its choice fits and no subset that fits is worth more
    /// (brute force over all subsets).
    #[test]
    fn the_knapsack_equals_brute_force(
        items in proptest::collection::vec((1usize..20, -5.0f64..10.0), 0..10),
        capacity in 0usize..60,
    ) {
        let (weights, values): (Vec<usize>, Vec<f64>) = items.into_iter().unzip();
        let take = afg_learn::staffing::knapsack(&weights, &values, capacity);
        let worth = |set: &dyn Fn(usize) -> bool| -> (usize, f64) {
            (0..weights.len()).filter(|&j| set(j)).fold((0, 0.0), |(w, v), j| (w + weights[j], v + values[j]))
        };
        let (used, got) = worth(&|j| take[j]);
        proptest::prop_assert!(used <= capacity);
        let mut best = 0.0f64;
        for set in 0..1u32 << weights.len() {
            let (w, v) = worth(&|j| set >> j & 1 == 1);
            if w <= capacity {
                best = best.max(v);
            }
        }
        proptest::prop_assert!((got - best).abs() < 1e-9, "{got} vs {best}");
    }
}

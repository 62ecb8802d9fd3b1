//! The staffing models' quality: the committed ones, and those trained on named families
//! (docs/families.md), against the exact solver's optimum on held-out games.

use std::path::Path;

use afg_baseline::{Allocator, TeamOptimum};
use afg_game::{Family, Instance};
use afg_learn::run::{ModelOptions, load_model};
use afg_learn::staffing::{StaffingModel, scarce_game};

/// What a model is measured against on `inst`: the exact solver's optimum, or its
/// proven bound where it stops at `seconds` unproven.
fn reference(inst: &Instance, seconds: f64) -> f64 {
    let best = TeamOptimum::with_time_limit(seconds)
        .unwrap()
        .solve(inst)
        .unwrap();
    if best.proven {
        best.welfare
    } else {
        best.bound
    }
}

/// The staffing pipeline without the network: the hand-written knapsack's worth
/// (reading skills where `skills`).
fn hand_knapsack(skills: bool) -> afg_learn::staffing::StaffingPolicy {
    afg_learn::staffing::StaffingPolicy::untrained(
        afg_learn::price::PriceNetConfig { hidden: 1, seed: 0 },
        skills,
    )
}

/// The shares of the reference that `learned` and `hand` reach on held-out games of
/// `family` (100 robots × 20 tasks, `seeds`), the reference at most 2 s a game.
fn family_shares(
    family: Family,
    seeds: std::ops::Range<u64>,
    learned: &dyn Allocator,
    hand: &dyn Allocator,
) -> (Vec<f64>, Vec<f64>) {
    seeds
        .map(|seed| {
            let inst = family.config(100, 20, seed).unwrap().generate().unwrap();
            let reference = reference(&inst, 2.0);
            let share = |allocator: &dyn Allocator| {
                let out = allocator.allocate(&inst).unwrap().assignment;
                inst.check(&out).unwrap();
                inst.welfare(&out) / reference
            };
            (share(learned), share(hand))
        })
        .unzip()
}

/// The mean of `shares`.
fn mean(shares: &[f64]) -> f64 {
    shares.iter().sum::<f64>() / shares.len() as f64
}

/// The least of `shares`.
fn worst(shares: &[f64]) -> f64 {
    shares.iter().copied().fold(f64::INFINITY, f64::min)
}

/// One method's mean share of the reference over `games` (the proven optimum, or the
/// bound where the solver stops).
fn mean_share(games: &[(Instance, f64)], method: impl Fn(&Instance) -> f64) -> f64 {
    games
        .iter()
        .map(|(inst, reference)| method(inst) / reference)
        .sum::<f64>()
        / games.len() as f64
}

/// The committed staffing models on held-out games of their own family (seeds below
/// 2^62, which training and validation never draw): at least 98 % of the exact
/// solver's optimum on average, and strictly above the same pipeline without the
/// network (the hand-written knapsack over nearest robots) and `opt`'s own dive on
/// the same games. A model that sends every robot to one task, or that keeps the
/// hand-written worth, fails.
#[test]
fn the_committed_staffing_models_reach_98_percent_of_the_optimum() {
    let repo = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    for name in ["staffing_teams", "staffing_skills"] {
        let dir = repo.join("models/ours").join(name);
        let model = StaffingModel::load(&dir.join(StaffingModel::FILE_NAME)).unwrap();
        let skills = model.training.skills;
        let policy = load_model(&dir, ModelOptions::default()).unwrap();
        let hand = hand_knapsack(skills.is_some());
        let size = model.training.sizes[0];
        let games: Vec<(Instance, f64)> = (54..64)
            .map(|seed| {
                let inst = scarce_game(size, skills, seed).unwrap();
                let reference = reference(&inst, 5.0);
                (inst, reference)
            })
            .collect();
        let welfare = |allocator: &dyn afg_baseline::Allocator, inst: &Instance| {
            let out = allocator.allocate(inst).unwrap().assignment;
            inst.check(&out).unwrap();
            inst.welfare(&out)
        };
        let learned = mean_share(&games, |inst| welfare(policy.as_ref(), inst));
        let knapsack = mean_share(&games, |inst| welfare(&hand, inst));
        let dive = mean_share(&games, |inst| {
            TeamOptimum::dive(inst, |root, fractional| {
                TeamOptimum::half_rounding(inst, root, fractional)
            })
            .1
        });
        assert!(learned >= 0.98, "{name}: {learned}");
        assert!(
            learned > knapsack && learned > dive,
            "{name}: {learned} against the knapsack's {knapsack} and the dive's {dive}"
        );
    }
}

/// The committed staffing models on held-out games of the families they were not
/// trained on (100 robots × 20 tasks, as docs/families.md measures them): at least
/// 98 % of the exact solver's optimum (its bound where it stops at 2 s) on average
/// where docs/teams.md says they carry — the threshold model on `clustered`,
/// `heavy-tail`, `constant`, `team-rewards` and `void-capacity`, the skill model on
/// `many-skills` — and no game below 90 % on any family either plays, `sparse-skills`
/// and `mixed` included (where the mean is below 98 %). The hand-written knapsack
/// beside them fails the 98 % on `many-skills`; on `clustered`, `heavy-tail` and
/// `sparse-skills` it does as well as the network, so no more is claimed there.
#[test]
fn the_committed_staffing_models_carry_to_the_families_docs_name() {
    let repo = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let carries = [
        ("staffing_teams", Family::Clustered, true),
        ("staffing_teams", Family::HeavyTail, true),
        ("staffing_teams", Family::Constant, true),
        ("staffing_teams", Family::TeamRewards, true),
        ("staffing_teams", Family::VoidCapacity, true),
        ("staffing_skills", Family::ManySkills, true),
        ("staffing_skills", Family::SparseSkills, false),
        ("staffing_skills", Family::Mixed, false),
    ];
    for (name, family, mean_98) in carries {
        let policy = load_model(
            &repo.join("models/ours").join(name),
            ModelOptions::default(),
        )
        .unwrap();
        let hand = hand_knapsack(name == "staffing_skills");
        let (learned, knapsack) = family_shares(family, 54..58, policy.as_ref(), &hand);
        let worst = worst(&learned);
        assert!(worst >= 0.90, "{name} on {family}: worst {worst}");
        assert!(
            !mean_98 || mean(&learned) >= 0.98,
            "{name} on {family}: mean {} (the hand-written knapsack's {})",
            mean(&learned),
            mean(&knapsack)
        );
    }
}

/// The threshold models of `cargo xtask study-families`, each trained on the threshold
/// families but one, on held-out games of the family it never saw (100 robots × 20
/// tasks): at least 98 % of the optimum on average and no game below 95 %, as
/// docs/families.md says, and over the six families at least half a point above the
/// same pipeline with the hand-written worth (which also reaches 98 % on some of them:
/// the network has to add something where it was never trained).
#[test]
fn models_trained_without_a_family_carry_to_it() {
    let repo = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let hand = hand_knapsack(false);
    let (mut learned, mut written) = (Vec::new(), Vec::new());
    for family in Family::ALL.into_iter().filter(|f| !f.draws_skills()) {
        let dir = repo.join(format!(
            "models/ours/families/staffing_teams_without-{family}"
        ));
        let model = StaffingModel::load(&dir.join(StaffingModel::FILE_NAME)).unwrap();
        assert!(!model.training.families.contains(&family));
        let policy = load_model(&dir, ModelOptions::default()).unwrap();
        let (shares, hand_shares) = family_shares(family, 54..58, policy.as_ref(), &hand);
        let (mean, worst) = (mean(&shares), worst(&shares));
        assert!(
            mean >= 0.98 && worst >= 0.95,
            "without {family}: mean {mean}, worst {worst}"
        );
        learned.extend(shares);
        written.extend(hand_shares);
    }
    assert!(
        mean(&learned) >= mean(&written) + 0.005,
        "{} against the hand-written {}",
        mean(&learned),
        mean(&written)
    );
}

/// The committed staffing models with their placement climbed (`--repair`: moves, swaps
/// and dissolved teams, ours) on held-out games of the families they fall short on
/// without it (for `heavy-tail`, the seeds where the threshold model's own placement
/// falls to 88.5 % and 97.3 %): at least 98 % of the optimum on average, no game below
/// 95 %, and at least half a point above the model without the climb, as
/// docs/families.md says. A staffing model that is refused an option gets a typed error.
#[test]
fn the_committed_models_climbed_after_their_placement_reach_98_percent_where_they_fell_short() {
    let models = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../models/ours");
    let repaired = ModelOptions {
        repair: true,
        ..ModelOptions::default()
    };
    for (model, family, seeds) in [
        ("staffing_skills", Family::SparseSkills, 54..58),
        ("staffing_skills", Family::Mixed, 54..58),
        ("staffing_teams", Family::HeavyTail, 58..63),
    ] {
        let climbed = load_model(&models.join(model), repaired).unwrap();
        let plain = load_model(&models.join(model), ModelOptions::default()).unwrap();
        let (with, without) = family_shares(family, seeds, climbed.as_ref(), plain.as_ref());
        let (mean_with, mean_without) = (mean(&with), mean(&without));
        assert!(
            mean_with >= 0.98 && worst(&with) >= 0.95 && mean_with >= mean_without + 0.005,
            "{model} on {family}: {with:?} climbed against {without:?}"
        );
    }
    let dir = models.join("staffing_skills");
    let block = ModelOptions {
        block: Some(2),
        repair: true,
        ..ModelOptions::default()
    };
    let refused = load_model(&dir, block).err().expect("a block size refused");
    assert!(
        refused
            .to_string()
            .starts_with("block, one-shot and the exact Burn rollout"),
        "{refused}"
    );
}

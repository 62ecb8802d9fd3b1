//! models/README.md lists every committed run once, and only those, in the section of
//! its role's folder; each name follows the README's grammar and each line names docs
//! that exist and discuss the run.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use afg_learn::run::RunDir;

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// Whether `word` is one of the README's words for a change from the default training.
fn is_change(word: &str) -> bool {
    let numbered = |prefix: &str, allowed: fn(char) -> bool| {
        word.strip_prefix(prefix)
            .is_some_and(|rest| !rest.is_empty() && rest.chars().all(allowed))
    };
    let digits = |c: char| c.is_ascii_digit();
    let rate = |c: char| c.is_ascii_digit() || matches!(c, '.' | 'e' | '-');
    [
        "gain",
        "price",
        "priceloss",
        "demos",
        "optshape",
        "warmqstar",
        "scalefree",
        "noshape",
        "firstunits",
        "expert",
        "dagger",
    ]
    .contains(&word)
        || ["priceloss", "warm", "m", "seed", "steps", "nstep", "sync"]
            .iter()
            .any(|prefix| numbered(prefix, digits))
        || numbered("lr", rate)
        || word == "mixture"
        || ["on-", "without-"].iter().any(|prefix| {
            word.strip_prefix(prefix)
                .is_some_and(|family| family.parse::<afg_game::Family>().is_ok())
        })
}

/// Whether a run's directory name reads `{model}[_{change}…]_n{N}`, or
/// `staffing_teams[_{change}…]` or `staffing_skills[_{change}…]` (trained on several
/// sizes at once).
fn follows_the_grammar(name: &str) -> bool {
    let words: Vec<&str> = name.split('_').collect();
    if let ["staffing", "teams" | "skills", changes @ ..] = words.as_slice() {
        return changes.iter().all(|w| is_change(w));
    }
    let changes = match words.as_slice() {
        ["price", rest @ ..] => rest,
        ["afgnet" | "s2v", "dqn" | "ddqn" | "qstar", rest @ ..] => rest,
        _ => return false,
    };
    let Some((last, changes)) = changes.split_last() else {
        return false;
    };
    let trained_at = last.strip_prefix('n').unwrap_or("");
    !trained_at.is_empty()
        && trained_at.chars().all(|c| c.is_ascii_digit())
        && changes.iter().all(|w| is_change(w))
}

#[test]
fn the_grammar_takes_the_readme_names_and_refuses_the_old_ones() {
    for name in [
        "afgnet_ddqn_n20",
        "afgnet_qstar_price_priceloss10_n60",
        "s2v_ddqn_lr3e-4_n60",
        "price_dagger_n60",
        "afgnet_ddqn_optshape_warm60_n100",
        "staffing_teams",
        "staffing_teams_seed1",
        "staffing_skills",
        "staffing_teams_on-heavy-tail",
        "staffing_skills_without-mixed",
        "staffing_teams_mixture",
    ] {
        assert!(follows_the_grammar(name), "{name}");
    }
    for name in [
        "afgnet_ddqn_n60_v1",
        "afgnet_ddqn_n60_warm",
        "price_n60_qstar",
        "afgnet_qstar_n60_1000",
        "afgnet_ddqn_warm_n100",
        "afgnet_ddqn",
        "gnn_ddqn_n60",
        "staffing_n60",
        "staffing_teams_big",
        "staffing_both",
        "staffing_teams_on-nowhere",
        "staffing_teams_without",
    ] {
        assert!(!follows_the_grammar(name), "{name}");
    }
}

#[test]
fn the_models_readme_lists_every_run_in_its_folder_and_where_it_is_discussed() {
    let root = repo();
    let text = std::fs::read_to_string(root.join("models/README.md")).unwrap();
    let mut listed = BTreeSet::new();
    let mut section_folder = None;
    for line in text.lines() {
        if let Some(heading) = line.strip_prefix("## ") {
            section_folder = heading
                .strip_prefix('`')
                .and_then(|h| h.split_once("/`"))
                .map(|(folder, _)| folder.to_owned());
            continue;
        }
        let Some(folder) = section_folder.as_deref() else {
            continue;
        };
        if !line.starts_with("| `") {
            continue;
        }
        let cells: Vec<&str> = line.split('|').map(str::trim).collect();
        assert_eq!(cells.len(), 6, "{line}");
        let run = cells[1].trim_matches('`').to_owned();
        let (run_folder, name) = run.rsplit_once('/').unwrap_or(("", &run));
        assert_eq!(run_folder, folder, "{run} is listed under `{folder}/`");
        assert!(
            follows_the_grammar(name),
            "{name} does not follow the grammar"
        );
        for doc in cells[4].split(", ") {
            let doc_text = std::fs::read_to_string(root.join(doc))
                .unwrap_or_else(|e| panic!("{run}: {doc}: {e}"));
            assert!(doc_text.contains(name), "{doc} does not discuss {run}");
        }
        assert!(listed.insert(run.clone()), "{run} listed twice");
    }
    let models = root.join("models");
    let dirs: BTreeSet<String> = RunDir::find_all(&models)
        .unwrap()
        .iter()
        .map(|run| {
            let relative = run.path().strip_prefix(&models).unwrap();
            relative.to_str().unwrap().replace('\\', "/")
        })
        .collect();
    assert!(dirs.len() >= 45, "{} runs", dirs.len());
    let unlisted: Vec<_> = dirs.difference(&listed).collect();
    let missing: Vec<_> = listed.difference(&dirs).collect();
    assert!(
        unlisted.is_empty() && missing.is_empty(),
        "not in models/README.md: {unlisted:?}; listed without a directory: {missing:?}"
    );
}

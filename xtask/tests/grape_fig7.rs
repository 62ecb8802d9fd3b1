//! GRAPE's published Fig. 7 runs: afg scores each published partition at GRAPE's own
//! published utility, Nash stable under GRAPE's preference; docs/baselines.md holds
//! the table of a fresh `cargo xtask grape-fig7`; broken files are refused by name.

use std::path::{Path, PathBuf};

use afg_eval::EvalError;
use afg_game::Preference;
use xtask::grape_fig7::{DATASET, read_runs, source, table};
use xtask::table_diff::table_differences;

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

#[test]
fn the_published_partitions_score_at_the_published_utility() {
    let runs = read_runs(&repo().join(DATASET)).unwrap();
    let names: Vec<&str> = runs.iter().map(|r| r.published.name.as_str()).collect();
    assert_eq!(names, ["circle", "skew", "square"]);
    for run in &runs {
        let inst = &run.instance;
        let welfare = inst.welfare(&run.partition);
        let utility = run.published.utility;
        assert!(
            (welfare - utility).abs() <= 1e-9 * utility,
            "{}: afg {welfare} against GRAPE's {utility}",
            run.published.name
        );
        assert!(inst.is_stable(&run.partition, Preference::Selfish));
        assert!(inst.allows_void() && inst.tasks().iter().all(|t| t.eps == 2.0));
    }
}

#[test]
fn the_docs_hold_a_fresh_table() {
    let dir = repo().join(DATASET);
    let fresh = format!(
        "GRAPE's runs: {}\n\n{}",
        source(&dir).unwrap(),
        table(&dir).unwrap()
    );
    let docs = std::fs::read_to_string(repo().join("docs/baselines.md")).unwrap();
    let start = docs
        .find("$ cargo xtask grape-fig7\n")
        .expect("docs/baselines.md runs cargo xtask grape-fig7")
        + "$ cargo xtask grape-fig7\n".len();
    let end = start + docs[start..].find("```").expect("the block ends");
    let differences = table_differences(docs[start..end].trim_end(), fresh.trim_end());
    assert!(
        differences.is_empty(),
        "docs/baselines.md is stale (rerun cargo xtask grape-fig7): {differences:?}"
    );
}

#[test]
fn broken_files_are_refused_by_name() {
    let dir = std::env::temp_dir().join(format!("afg-grape-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let committed = repo().join(DATASET);
    for file in [
        "instances.jsonl",
        "grape-partitions.jsonl",
        "published.json",
    ] {
        std::fs::copy(committed.join(file), dir.join(file)).unwrap();
    }
    assert_eq!(read_runs(&dir).unwrap().len(), 3);
    // A partition short of one line.
    let partitions = std::fs::read_to_string(committed.join("grape-partitions.jsonl")).unwrap();
    let two: Vec<&str> = partitions.lines().take(2).collect();
    std::fs::write(dir.join("grape-partitions.jsonl"), two.join("\n")).unwrap();
    let err = read_runs(&dir).unwrap_err();
    assert!(matches!(err, EvalError::BadFile { .. }), "{err}");
    assert!(err.to_string().contains("2 partitions"), "{err}");
    // A task index beyond M.
    let bad = partitions.replacen("[3,", "[7,", 1);
    assert_ne!(bad, partitions);
    std::fs::write(dir.join("grape-partitions.jsonl"), bad).unwrap();
    let err = read_runs(&dir).unwrap_err().to_string();
    assert!(err.contains("grape-partitions.jsonl"), "{err}");
    // Another format.
    let published = std::fs::read_to_string(committed.join("published.json")).unwrap();
    std::fs::write(
        dir.join("published.json"),
        published.replace("afg-grape-published", "afg-instance"),
    )
    .unwrap();
    let err = read_runs(&dir).unwrap_err().to_string();
    assert!(
        err.contains("published.json") && err.contains("afg-instance"),
        "{err}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
    let err = read_runs(&dir).unwrap_err().to_string();
    assert!(err.contains("published.json"), "{err}");
}

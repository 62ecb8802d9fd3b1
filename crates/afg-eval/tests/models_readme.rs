//! models/README.md lists every committed run once, and only those; each line names
//! docs that exist and discuss the run.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// The run directories under models/ and models/ablations/, as README names them.
fn run_dirs(models: &Path) -> BTreeSet<String> {
    let mut runs = BTreeSet::new();
    for prefix in ["", "ablations/"] {
        for entry in std::fs::read_dir(models.join(prefix)).unwrap() {
            let entry = entry.unwrap();
            let name = entry.file_name().into_string().unwrap();
            if entry.file_type().unwrap().is_dir() && name != "ablations" {
                runs.insert(format!("{prefix}{name}"));
            }
        }
    }
    runs
}

#[test]
fn the_models_readme_lists_every_run_and_where_it_is_discussed() {
    let root = repo();
    let text = std::fs::read_to_string(root.join("models/README.md")).unwrap();
    let mut listed = BTreeSet::new();
    for line in text.lines().filter(|l| l.starts_with("| `")) {
        let cells: Vec<&str> = line.split('|').map(str::trim).collect();
        let run = cells[1].trim_matches('`').to_owned();
        assert_eq!(cells.len(), 6, "{line}");
        let name = run.rsplit('/').next().unwrap();
        for doc in cells[4].split(", ") {
            let doc_text = std::fs::read_to_string(root.join(doc))
                .unwrap_or_else(|e| panic!("{run}: {doc}: {e}"));
            assert!(doc_text.contains(name), "{doc} does not discuss {run}");
        }
        assert!(listed.insert(run.clone()), "{run} listed twice");
    }
    let dirs = run_dirs(&root.join("models"));
    let unlisted: Vec<_> = dirs.difference(&listed).collect();
    let missing: Vec<_> = listed.difference(&dirs).collect();
    assert!(
        unlisted.is_empty() && missing.is_empty(),
        "not in models/README.md: {unlisted:?}; listed without a directory: {missing:?}"
    );
}

//! docs/architecture.md against the workspace: every crate has its paragraph, the
//! table of arrows is exactly the manifests' dependencies among the workspace's crates
//! (read with `cargo metadata`), and the rules the page states hold.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use std::process::Command;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// Each member's normal dependencies: those among the workspace's and the others.
struct Workspace {
    members: Vec<String>,
    arrows: BTreeMap<String, BTreeSet<String>>,
    external: BTreeMap<String, BTreeSet<String>>,
}

fn workspace() -> Workspace {
    let out = Command::new(env!("CARGO"))
        .args([
            "metadata",
            "--format-version",
            "1",
            "--no-deps",
            "--offline",
        ])
        .current_dir(root())
        .output()
        .expect("cargo metadata runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let metadata: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let packages = metadata["packages"].as_array().unwrap();
    let members: Vec<String> = packages
        .iter()
        .map(|p| p["name"].as_str().unwrap().to_owned())
        .collect();
    let (mut arrows, mut external) = (BTreeMap::new(), BTreeMap::new());
    for p in packages {
        let name = p["name"].as_str().unwrap().to_owned();
        let normal = p["dependencies"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|d| d["kind"].is_null())
            .map(|d| d["name"].as_str().unwrap().to_owned());
        let (ours, theirs): (BTreeSet<_>, BTreeSet<_>) = normal.partition(|d| members.contains(d));
        arrows.insert(name.clone(), ours);
        external.insert(name, theirs);
    }
    Workspace {
        members,
        arrows,
        external,
    }
}

/// The page's table of arrows, in its order: (crate, the crates it uses).
fn documented_arrows(page: &str) -> Vec<(String, BTreeSet<String>)> {
    let table = page
        .split("<!-- arrows -->")
        .nth(1)
        .and_then(|rest| rest.split("<!-- /arrows -->").next())
        .expect("docs/architecture.md has its table of arrows");
    let names = |cell: &str| -> BTreeSet<String> {
        cell.split(',')
            .map(|c| c.trim().trim_matches('`').to_owned())
            .filter(|c| !c.is_empty() && c != "—")
            .collect()
    };
    table
        .lines()
        .filter(|l| l.starts_with("| `"))
        .map(|l| {
            let cells: Vec<&str> = l.split('|').collect();
            (
                cells[1].trim().trim_matches('`').to_owned(),
                names(cells[2]),
            )
        })
        .collect()
}

fn page() -> String {
    std::fs::read_to_string(root().join("docs/architecture.md")).unwrap()
}

#[test]
fn every_crate_of_the_workspace_has_its_paragraph() {
    let ws = workspace();
    assert!(ws.members.len() >= 9, "{:?}", ws.members);
    let doc = page();
    for name in &ws.members {
        assert!(
            doc.contains(&format!("**`{name}`**")),
            "docs/architecture.md has no paragraph for {name}"
        );
    }
}

#[test]
fn the_page_draws_every_arrow_of_the_manifests_and_no_other() {
    let ws = workspace();
    let documented = documented_arrows(&page());
    let drawn: BTreeMap<String, BTreeSet<String>> = documented.iter().cloned().collect();
    assert_eq!(
        drawn.keys().collect::<BTreeSet<_>>(),
        ws.members.iter().collect::<BTreeSet<_>>(),
        "the table of arrows lists every crate once"
    );
    for (name, uses) in &ws.arrows {
        let missing: Vec<_> = uses.difference(&drawn[name]).collect();
        let extra: Vec<_> = drawn[name].difference(uses).collect();
        assert!(
            missing.is_empty() && extra.is_empty(),
            "{name}: the manifests have {missing:?} that docs/architecture.md does not draw, and it draws {extra:?} that they lack"
        );
    }
}

#[test]
fn the_rules_the_page_states_hold() {
    let ws = workspace();
    let order: Vec<String> = documented_arrows(&page())
        .into_iter()
        .map(|(name, _)| name)
        .collect();
    // No arrow runs back up: each crate uses only crates listed before it.
    for (at, name) in order.iter().enumerate() {
        for used in &ws.arrows[name] {
            let below = order[..at].contains(used);
            assert!(below, "{name} → {used} runs up the page's order");
        }
    }
    // The front ends are leaves; xtask borrows afg-cli's training command alone.
    for (name, uses) in &ws.arrows {
        for leaf in ["xtask", "afg-py", "afg-cli"] {
            let allowed = leaf == "afg-cli" && name == "xtask";
            assert!(!uses.contains(leaf) || allowed, "{name} → {leaf}");
        }
    }
    let xtask_src = std::fs::read_dir(root().join("xtask/src"))
        .unwrap()
        .flat_map(|e| {
            let path = e.unwrap().path();
            if path.is_dir() {
                std::fs::read_dir(path)
                    .unwrap()
                    .map(|e| e.unwrap().path())
                    .collect()
            } else {
                vec![path]
            }
        })
        .map(|path| std::fs::read_to_string(path).unwrap())
        .collect::<String>();
    for used in xtask_src.split("afg_cli::").skip(1) {
        assert!(
            used.starts_with("train")
                || used.starts_with("settings::TrainSettings")
                || used.starts_with("Command"),
            "xtask uses afg_cli::{}",
            &used[..used.len().min(40)]
        );
    }
    // clap in the command lines only; burn in the learning crate and xtask only.
    for (name, theirs) in &ws.external {
        let command_line = ["afg-cli", "xtask"].contains(&name.as_str());
        assert!(
            !theirs.contains("clap") || command_line,
            "{name} depends on clap"
        );
        let learns = ["afg-learn", "xtask"].contains(&name.as_str());
        assert!(!theirs.contains("burn") || learns, "{name} depends on burn");
    }
    // afg-mission's arrows never reach afg-learn.
    let mut reach = BTreeSet::from(["afg-mission".to_owned()]);
    let mut todo = vec!["afg-mission".to_owned()];
    while let Some(name) = todo.pop() {
        for used in &ws.arrows[&name] {
            if reach.insert(used.clone()) {
                todo.push(used.clone());
            }
        }
    }
    assert!(
        !reach.contains("afg-learn"),
        "afg-mission reaches {reach:?}"
    );
}

/// The test reads what it checks: an arrow drawn in the page and not in the manifests
/// fails it (here, afg-game → afg-learn added to a copy of the page).
#[test]
fn an_arrow_the_code_lacks_is_found() {
    let doc = page().replace("| `afg-game` | — |", "| `afg-game` | `afg-learn` |");
    let drawn = documented_arrows(&doc);
    let ws = workspace();
    let game = &drawn.iter().find(|(n, _)| n == "afg-game").unwrap().1;
    assert_ne!(game, &ws.arrows["afg-game"]);
}

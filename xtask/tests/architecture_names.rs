//! Every Rust name docs/architecture.md mentions in backticks exists in the code: a
//! map that names a type, function, module or file the workspace does not have is
//! wrong, and this test says which.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// Every `.rs` and `.py`/`.pyi` file under `dir`, its path and text.
fn sources(dir: &Path, out: &mut Vec<(PathBuf, String)>) {
    for entry in std::fs::read_dir(dir).unwrap().flatten() {
        let path = entry.path();
        let name = entry.file_name().to_string_lossy().into_owned();
        if path.is_dir() && name != "target" && !name.starts_with('.') {
            sources(&path, out);
        } else if ["rs", "py", "pyi"]
            .iter()
            .any(|e| name.ends_with(&format!(".{e}")))
        {
            out.push((
                path.clone(),
                std::fs::read_to_string(&path).unwrap_or_default(),
            ));
        }
    }
}

/// The names the code defines: items, enum variants, fields, modules (files and
/// `mod`s) and Python classes and functions.
fn defined(files: &[(PathBuf, String)]) -> BTreeSet<String> {
    let mut names = BTreeSet::new();
    let keywords = [
        "fn", "struct", "enum", "trait", "mod", "const", "type", "static", "class", "def",
    ];
    for (path, text) in files {
        if let Some(stem) = path.file_stem() {
            names.insert(stem.to_string_lossy().into_owned());
        }
        for line in text.lines() {
            let words: Vec<&str> = line
                .split(|c: char| !(c.is_alphanumeric() || c == '_'))
                .filter(|w| !w.is_empty())
                .collect();
            for pair in words.windows(2) {
                if keywords.contains(&pair[0]) {
                    names.insert(pair[1].to_owned());
                }
            }
            // an enum variant or a field: `    Name,` / `    Name {` / `    Name(` / `    name:`
            let trimmed = line
                .trim_start()
                .trim_start_matches("pub ")
                .trim_start_matches("pub(crate) ");
            let head: String = trimmed
                .chars()
                .take_while(|c| c.is_alphanumeric() || *c == '_')
                .collect();
            let rest = &trimmed[head.len()..];
            if !head.is_empty() && [",", " {", "(", ":"].iter().any(|s| rest.starts_with(s)) {
                names.insert(head);
            }
        }
    }
    names
}

/// The Rust-looking names in backticks: paths `a::b::c`, `Type`, `fn()`, and file
/// paths `dir/file.rs` (their stem), not flags, commands or Python calls.
fn mentioned(page: &str) -> BTreeSet<String> {
    let mut names = BTreeSet::new();
    for (k, span) in page.split('`').enumerate() {
        if k % 2 == 0 || span.contains(' ') || span.starts_with('-') || span.starts_with('"') {
            continue;
        }
        let span = span.trim_end_matches("()");
        if let Some(file) = span
            .strip_suffix(".rs")
            .or_else(|| span.strip_suffix(".py"))
        {
            names.insert(file.rsplit('/').next().unwrap().to_owned());
            continue;
        }
        let span = span.split("::").collect::<Vec<_>>();
        let rust = span
            .iter()
            .all(|s| !s.is_empty() && s.chars().all(|c| c.is_alphanumeric() || c == '_'));
        let is_path = span.len() > 1;
        let is_type = span[0].chars().next().is_some_and(char::is_uppercase)
            && span[0].chars().any(char::is_lowercase);
        if rust && (is_path || is_type) {
            for segment in span {
                if !segment.starts_with("afg_") {
                    names.insert(segment.to_owned());
                }
            }
        }
    }
    names
}

/// What the page names that is not afg's code: the standard library's, Python's, and
/// the command line's notation for a size.
const NOT_OURS: [&str; 6] = [
    "Default",
    "Result",
    "ValueError",
    "RuntimeError",
    "FileNotFoundError",
    "NxM",
];

#[test]
fn every_name_the_page_mentions_is_in_the_code() {
    let root = root();
    let mut files = Vec::new();
    for dir in ["crates", "xtask", "scripts"] {
        sources(&root.join(dir), &mut files);
    }
    let defined = defined(&files);
    let page = std::fs::read_to_string(root.join("docs/architecture.md")).unwrap();
    let missing: Vec<String> = mentioned(&page)
        .into_iter()
        .filter(|n| !defined.contains(n) && !NOT_OURS.contains(&n.as_str()))
        .collect();
    assert!(
        missing.is_empty(),
        "docs/architecture.md names what the code lacks: {missing:?}"
    );
}

#[test]
fn a_name_the_code_lacks_is_found() {
    let page = "`TeamOptimum::limits` and `afg_game::NoSuchThing`, `afg solve --json`";
    let names = mentioned(page);
    assert!(names.contains("NoSuchThing") && names.contains("limits"));
    assert!(!names.iter().any(|n| n.contains("solve")));
    let files = vec![(
        PathBuf::from("x/teams.rs"),
        "pub fn limits() {}\nenum A {\n    Variant,\n}".to_owned(),
    )];
    let defined = defined(&files);
    assert!(defined.contains("limits") && defined.contains("teams") && defined.contains("Variant"));
    assert!(!defined.contains("NoSuchThing"));
}

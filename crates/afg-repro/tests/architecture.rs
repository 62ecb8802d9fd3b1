//! docs/architecture.md against the workspace: every crate has its paragraph.

use std::path::Path;

fn root() -> &'static Path {
    Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../.."))
}

/// The package names of the workspace's members, read from the manifests.
fn member_names() -> Vec<String> {
    let manifest = std::fs::read_to_string(root().join("Cargo.toml")).unwrap();
    let members = manifest
        .lines()
        .find(|l| l.starts_with("members = "))
        .expect("a members line");
    members
        .split('"')
        .skip(1)
        .step_by(2)
        .map(|path| {
            let member = std::fs::read_to_string(root().join(path).join("Cargo.toml")).unwrap();
            let name = member
                .lines()
                .find_map(|l| l.strip_prefix("name = \""))
                .unwrap_or_else(|| panic!("{path} has a package name"));
            name.trim_end_matches('"').to_owned()
        })
        .collect()
}

#[test]
fn every_crate_of_the_workspace_has_its_paragraph() {
    let doc = std::fs::read_to_string(root().join("docs/architecture.md")).unwrap();
    let names = member_names();
    assert!(names.len() >= 9, "{names:?}");
    for name in names {
        assert!(
            doc.contains(&format!("**`{name}`**")),
            "docs/architecture.md has no paragraph for {name}"
        );
    }
}

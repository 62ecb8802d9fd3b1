//! The crash harness end to end, briefly: `cargo xtask crash-test` with two kills per
//! trainer must resume every run and end with the uninterrupted run's weights (the
//! full 20-kill run is a command; docs/reliability.md has its table).

use std::process::Command;

#[test]
fn killed_runs_resume_to_the_uninterrupted_weights() {
    let dir = std::env::temp_dir().join(format!("afg-crash-test-{}", std::process::id()));
    let output = Command::new(env!("CARGO_BIN_EXE_xtask"))
        .args(["crash-test", "--kills", "2", "--seed", "3", "--dir"])
        .arg(&dir)
        .output()
        .unwrap();
    let table = String::from_utf8_lossy(&output.stdout);
    assert!(
        output.status.success(),
        "{table}\n{}",
        String::from_utf8_lossy(&output.stderr)
    );
    for trainer in ["train", "train-price"] {
        let row = table
            .lines()
            .find(|l| l.starts_with(&format!("| {trainer} |")))
            .unwrap_or_else(|| panic!("no row for {trainer}: {table}"));
        let cells: Vec<&str> = row.split('|').map(str::trim).collect();
        assert_eq!(cells[2], "2", "kills: {row}");
        assert!(row.ends_with("| yes |"), "{row}");
    }
    // A directory holding anything a crash test did not write is refused, untouched.
    std::fs::write(dir.join("notes.txt"), "mine").unwrap();
    let refused = Command::new(env!("CARGO_BIN_EXE_xtask"))
        .args(["crash-test", "--dir"])
        .arg(&dir)
        .output()
        .unwrap();
    assert_eq!(refused.status.code(), Some(1));
    let err = String::from_utf8_lossy(&refused.stderr);
    assert!(err.contains("notes.txt which no crash test wrote"), "{err}");
    assert!(dir.join("train").exists() && dir.join("notes.txt").exists());
    std::fs::remove_dir_all(&dir).unwrap();
}

//! What a user sees when a command fails: one line on stderr and exit status 1, whatever
//! `RUST_BACKTRACE` says; usage errors exit with 2.

use std::process::{Command, Output};

fn afg(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_afg"))
        .args(args)
        .env("RUST_BACKTRACE", "1")
        .output()
        .expect("afg runs")
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

#[test]
fn a_failing_command_prints_one_line_and_exits_1_even_with_backtraces_on() {
    let missing = std::env::temp_dir().join(format!("afg-no-such-{}.json", std::process::id()));
    let out = afg(&[
        "solve",
        "--method",
        "opt",
        "--input",
        missing.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(1));
    let text = stderr(&out);
    assert_eq!(text.lines().count(), 1, "{text}");
    assert!(
        text.starts_with("error: ") && text.contains("afg-no-such"),
        "{text}"
    );
    // Each cause once, even where an error prints its source in its own message.
    assert_eq!(text.matches("No such file").count(), 1, "{text}");

    let out = afg(&[
        "gen",
        "--robots",
        "10",
        "--capacity-slack",
        "0.5",
        "--out",
        "x.jsonl",
    ]);
    assert_eq!(out.status.code(), Some(1));
    assert_eq!(
        stderr(&out),
        "error: invalid generator parameter: capacity slack must be at least 1 (got 0.5)\n"
    );
}

#[test]
fn a_usage_error_exits_2() {
    let out = afg(&["swarm", "--preference", "kind"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(stderr(&out).contains("[possible values: balanced, selfish]"));
}

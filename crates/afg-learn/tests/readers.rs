//! Every reader of a user's or a run's file, fed mutations of the committed files
//! (truncations, byte flips, numbers made huge, negative or fractional, fields deleted
//! or duplicated, values of another type) and arbitrary JSON: each returns a typed
//! error or a valid value, never a panic.
//!
//! A short run is part of `cargo test`; the long run is
//! `PROPTEST_CASES=100000 cargo test --release -p afg-learn --test readers`. The cases
//! are drawn from a fixed seed, so every run of a given size tries the same inputs.

use std::path::{Path, PathBuf};

use afg_game::io::{parse_dataset, parse_instances};
use afg_game::realloc::PreviousAssignment;
use afg_game::{Assignment, Instance};
use afg_learn::{nets::load_network, run::RunDir, train::Trainer};
use proptest::prelude::*;

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn committed(path: &str) -> String {
    std::fs::read_to_string(repo().join(path)).unwrap()
}

/// One edit of a text.
#[derive(Clone, Debug)]
enum Mutation {
    /// Keep the first `at` (scaled) bytes.
    Truncate(f64),
    /// Replace the byte at `at` by `byte`.
    Flip(f64, u8),
    /// Replace the `k`-th number by `with`.
    Number(usize, &'static str),
    /// Delete the `k`-th `"key": value` pair (up to the next comma).
    DeleteField(usize),
    /// Repeat the `k`-th key.
    DuplicateField(usize),
    /// Replace the `k`-th number by a value of another type.
    Retype(usize, &'static str),
}

fn mutation() -> impl Strategy<Value = Mutation> {
    let numbers = prop::sample::select(vec![
        "1e308",
        "-1e308",
        "1e-39",
        "-1",
        "0",
        "0.5",
        "4294967295",
        "18446744073709551615",
        "1e400",
        "-0.0",
        "99999999999999999999999",
        "3",
    ]);
    let types = prop::sample::select(vec!["null", "\"x\"", "[]", "{}", "true", "[1,2]"]);
    prop_oneof![
        (0.0..1.0f64).prop_map(Mutation::Truncate),
        (0.0..1.0f64, any::<u8>()).prop_map(|(a, b)| Mutation::Flip(a, b)),
        (0..400usize, numbers).prop_map(|(k, n)| Mutation::Number(k, n)),
        (0..60usize).prop_map(Mutation::DeleteField),
        (0..60usize).prop_map(Mutation::DuplicateField),
        (0..400usize, types).prop_map(|(k, t)| Mutation::Retype(k, t)),
    ]
}

/// Byte ranges of the numbers in `text`.
fn numbers(text: &str) -> Vec<(usize, usize)> {
    let b = text.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while i < b.len() {
        if (b[i] == b'-' || b[i].is_ascii_digit()) && (i == 0 || b":[, ".contains(&b[i - 1])) {
            let start = i;
            i += 1;
            while i < b.len() && (b[i].is_ascii_digit() || b".eE+-".contains(&b[i])) {
                i += 1;
            }
            out.push((start, i));
        } else {
            i += 1;
        }
    }
    out
}

/// Byte offsets of the keys (`"name":`) in `text`.
fn keys(text: &str) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut from = 0;
    while let Some(q) = text[from..].find('"') {
        let start = from + q;
        let Some(len) = text[start + 1..].find('"') else {
            break;
        };
        let end = start + 1 + len + 1;
        if text[end..].starts_with(':') {
            out.push((start, end + 1));
        }
        from = end;
    }
    out
}

fn apply(text: &str, m: &Mutation) -> Vec<u8> {
    let mut bytes = text.as_bytes().to_vec();
    let pick = |v: &[(usize, usize)], k: usize| (!v.is_empty()).then(|| v[k % v.len()]);
    match m {
        Mutation::Truncate(at) => bytes.truncate((*at * bytes.len() as f64) as usize),
        Mutation::Flip(at, byte) => {
            let i = ((*at * bytes.len() as f64) as usize).min(bytes.len().saturating_sub(1));
            if let Some(b) = bytes.get_mut(i) {
                *b = *byte;
            }
        }
        Mutation::Number(k, with) | Mutation::Retype(k, with) => {
            if let Some((s, e)) = pick(&numbers(text), *k) {
                bytes.splice(s..e, with.bytes());
            }
        }
        Mutation::DeleteField(k) => {
            if let Some((s, e)) = pick(&keys(text), *k) {
                let end = text[e..].find([',', '}']).map_or(text.len(), |x| e + x);
                let end = if text[end..].starts_with(',') {
                    end + 1
                } else {
                    end
                };
                bytes.drain(s..end);
            }
        }
        Mutation::DuplicateField(k) => {
            if let Some((s, e)) = pick(&keys(text), *k) {
                let end = text[e..].find([',', '}']).map_or(text.len(), |x| e + x);
                let pair = format!("{},", &text[s..end]);
                bytes.splice(s..s, pair.bytes());
            }
        }
    }
    bytes
}

/// The text of `bytes`, if it is UTF-8 (every reader takes text).
fn text_of(bytes: &[u8]) -> Option<&str> {
    std::str::from_utf8(bytes).ok()
}

/// A scratch copy of a committed run directory's `files`, with `name` replaced.
fn scratch_run(from: &str, files: &[&str], name: &str, bytes: &[u8]) -> PathBuf {
    let dir = std::env::temp_dir().join(format!(
        "afg-readers-{}-{:?}",
        std::process::id(),
        std::thread::current().id()
    ));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    for f in files {
        std::fs::copy(repo().join(from).join(f), dir.join(f)).unwrap();
    }
    std::fs::write(dir.join(name), bytes).unwrap();
    dir
}

fn cases(default: u32) -> ProptestConfig {
    let cases = std::env::var("PROPTEST_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default);
    ProptestConfig {
        rng_seed: proptest::test_runner::RngSeed::Fixed(0),
        failure_persistence: None,
        ..ProptestConfig::with_cases(cases)
    }
}

proptest! {
    #![proptest_config(cases(300))]

    #[test]
    fn instance_and_dataset_readers_never_panic(m in mutation(), line in 0usize..3) {
        let dataset = committed("datasets/n20.jsonl");
        let lines: Vec<&str> = dataset.lines().take(3).collect();
        let bytes = apply(lines[line], &m);
        if let Some(text) = text_of(&bytes) {
            if let Ok(inst) = Instance::from_json(text) {
                // What is accepted is valid: it round-trips.
                prop_assert_eq!(Instance::from_json(&inst.to_json()).unwrap(), inst);
            }
            let mut all = lines.clone();
            all[line] = text;
            let _ = parse_dataset(&all.join("\n"));
            let _ = parse_instances(text);
        }
    }

    #[test]
    fn assignment_and_previous_readers_never_panic(m in mutation(), survivors in 1usize..25) {
        let inst = parse_dataset(&committed("datasets/n20.jsonl")).unwrap().remove(0);
        let text = format!(
            r#"{{"format":"afg-assignment","version":1,"tasks":[{}],"left_robots":[1,4],"left_tasks":[]}}"#,
            (0..22).map(|i| (i % 5).to_string()).collect::<Vec<_>>().join(",")
        );
        let bytes = apply(&text, &m);
        if let Some(text) = text_of(&bytes) {
            let _ = Assignment::from_json(text, &inst);
            if let Ok(previous) = PreviousAssignment::from_json(text) {
                let now = Instance::new(
                    inst.robots().iter().cycle().take(survivors).copied().collect(),
                    inst.tasks().to_vec(),
                    inst.beta(),
                ).unwrap();
                if let Ok(a) = previous.carry_over(&now) {
                    prop_assert!(now.check(&a).is_ok());
                }
            }
        }
    }

    #[test]
    fn model_headers_never_panic(m in mutation()) {
        let header = committed("models/paper/afgnet_ddqn_n20/model.json");
        let dir = scratch_run("models/paper/afgnet_ddqn_n20", &["model.mpk"], "model.json", &apply(&header, &m));
        let _ = load_network::<afg_learn::InferBackend>(&dir.join("model"), &Default::default());
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn run_configs_never_panic(m in mutation()) {
        let config = committed("models/paper/afgnet_ddqn_n60/config.json");
        let dir = scratch_run("models/paper/afgnet_ddqn_n60", &[], "config.json", &apply(&config, &m));
        if let Ok(c) = RunDir::new(&dir).config() {
            let _ = c.check();
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn arbitrary_json_is_refused_or_valid(v in arbitrary_json()) {
        let text = v.to_string();
        let _ = Instance::from_json(&text);
        let _ = PreviousAssignment::from_json(&text);
        let _ = serde_json::from_str::<afg_learn::nets::NetworkConfig>(&text);
        let _ = serde_json::from_str::<afg_learn::train::TrainConfig>(&text);
    }
}

/// Checkpoint states: a resume builds networks and a validation set, so fewer cases.
#[test]
fn checkpoint_states_never_panic() {
    use afg_learn::{
        nets::NetworkConfig,
        train::{Algo, TrainConfig},
    };
    let dir = std::env::temp_dir().join(format!("afg-readers-ckpt-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let mut config = TrainConfig::new(10, Algo::Dqn, NetworkConfig::s2v(3, 0), 20, 1);
    (config.batch, config.parallel_envs, config.warmup) = (8, 2, 16);
    (config.replay_capacity, config.validation_instances) = (200, 2);
    let mut t = Trainer::new(config).unwrap();
    for _ in 0..3 {
        t.step().unwrap();
    }
    t.save_checkpoint(&dir).unwrap();
    let state = dir.join("checkpoint/state.json");
    let text = std::fs::read_to_string(&state).unwrap();
    let mut runner = proptest::test_runner::TestRunner::new(cases(40));
    runner
        .run(&mutation(), |m| {
            std::fs::write(&state, apply(&text, &m)).unwrap();
            let _ = Trainer::resume_from(&dir.join("checkpoint"));
            Ok(())
        })
        .unwrap();
    std::fs::remove_dir_all(&dir).unwrap();
}

fn arbitrary_json() -> impl Strategy<Value = serde_json::Value> {
    use serde_json::Value;
    let leaf = prop_oneof![
        Just(Value::Null),
        any::<bool>().prop_map(Value::Bool),
        any::<i64>().prop_map(Value::from),
        any::<f64>()
            .prop_filter("finite", |x| x.is_finite())
            .prop_map(Value::from),
        prop::sample::select(vec!["afg-instance", "afg-assignment", "afgnet", "s2v", "x"])
            .prop_map(|s| Value::String(s.into())),
    ];
    leaf.prop_recursive(4, 64, 8, |inner| {
        let keys = prop::sample::select(vec![
            "format",
            "version",
            "beta",
            "robots",
            "tasks",
            "x",
            "y",
            "position",
            "reward",
            "eps",
            "capacity",
            "net",
            "hidden",
            "layers",
            "left_robots",
        ]);
        prop_oneof![
            prop::collection::vec(inner.clone(), 0..8).prop_map(serde_json::Value::Array),
            prop::collection::btree_map(keys.prop_map(str::to_owned), inner, 0..8)
                .prop_map(|m| serde_json::Value::Object(m.into_iter().collect())),
        ]
    })
}

//! Run directories: typed logs (old and new lines), truncation on resume, manifests,
//! exclusive use, and every committed run read back.

use std::path::{Path, PathBuf};

use afg_learn::{
    LearnError,
    nets::NetworkConfig,
    run::{LogEvent, ModelKind, RunDir, RunManifest, RunRecord, ValidationLine},
    train::{Algo, Preset, TrainConfig, Validation},
};

fn fresh(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("afg-rundir-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

fn config() -> TrainConfig {
    TrainConfig::new(20, Algo::Ddqn, NetworkConfig::afgnet(5, 0), 100, 0)
}

#[test]
fn events_round_trip_and_old_validation_lines_still_read() {
    let dir = fresh("log");
    let (run, _lock) = RunDir::create(&dir, &config()).unwrap();
    let validation = Validation {
        welfare: 12.5,
        percent_of_opt: 97.0,
        largest_task_share: 0.7,
    };
    let events = vec![
        LogEvent::Start {
            version: afg_learn::run::RUN_FORMAT_VERSION,
            config: Box::new(config()),
            git_revision: Some("abc".into()),
            baselines: [(afg_baseline::Method::Opt, 13.0)].into_iter().collect(),
        },
        LogEvent::Step {
            step: 10,
            loss: 0.25,
            epsilon: 0.5,
            elapsed_s: 1.0,
        },
        LogEvent::Validation(ValidationLine::new(20, &validation, 2.5)),
        LogEvent::End {
            step: 20,
            elapsed_s: 3.0,
        },
    ];
    for e in &events {
        run.append(e).unwrap();
    }
    assert_eq!(run.log().unwrap(), events);
    let LogEvent::Validation(v) = &events[2] else {
        unreachable!()
    };
    assert_eq!(v.collapsed, Some(true)); // 0.7 > COLLAPSE_SHARE
    // A line from before the collapse check existed.
    let old = r#"{"elapsed_s":5.0,"event":"validation","percent_of_opt":48.6,"step":30,"welfare":1.0127}"#;
    let parsed: LogEvent = serde_json::from_str(old).unwrap();
    assert_eq!(
        parsed,
        LogEvent::Validation(ValidationLine {
            step: 30,
            welfare: 1.0127,
            percent_of_opt: 48.6,
            largest_task_share: None,
            collapsed: None,
            elapsed_s: 5.0
        })
    );
    // A line that is not an event is named by its line number.
    std::fs::write(
        dir.join(RunDir::LOG),
        format!("{}\n{{\"event\":\"teleport\"}}\n", old),
    )
    .unwrap();
    let err = run.log().unwrap_err();
    assert!(err.to_string().contains("log.jsonl:2"), "{err}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// NaN and the infinities are written as "NaN", "inf" and "-inf" (serde_json alone
/// writes `null`, which no number field reads) and read back.
#[test]
fn non_finite_numbers_in_the_log_read_back() {
    let dir = fresh("nonfinite");
    let (run, _lock) = RunDir::create(&dir, &config()).unwrap();
    let diverged = Validation {
        welfare: f64::NEG_INFINITY,
        percent_of_opt: f64::NAN,
        largest_task_share: f64::INFINITY,
    };
    run.append(&LogEvent::Step {
        step: 10,
        loss: f32::INFINITY,
        epsilon: 0.5,
        elapsed_s: 1.0,
    })
    .unwrap();
    run.append(&LogEvent::Validation(ValidationLine::new(
        10, &diverged, 2.0,
    )))
    .unwrap();
    let text = std::fs::read_to_string(dir.join(RunDir::LOG)).unwrap();
    assert!(
        text.contains(r#""loss":"inf""#) && text.contains(r#""percent_of_opt":"NaN""#),
        "{text}"
    );
    let log = run.log().unwrap();
    let LogEvent::Step { loss, .. } = log[0] else {
        panic!("{:?}", log[0])
    };
    assert_eq!(loss, f32::INFINITY);
    let LogEvent::Validation(v) = &log[1] else {
        panic!("{:?}", log[1])
    };
    assert!(v.percent_of_opt.is_nan());
    assert_eq!(
        (v.welfare, v.largest_task_share),
        (f64::NEG_INFINITY, Some(f64::INFINITY))
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_torn_last_line_is_reported_left_out_and_dropped_on_resume() {
    let dir = fresh("torn");
    let (run, _lock) = RunDir::create(&dir, &config()).unwrap();
    let step = |s: u64| LogEvent::Step {
        step: s,
        loss: 0.5,
        epsilon: 1.0,
        elapsed_s: s as f64,
    };
    run.append(&step(10)).unwrap();
    run.append(&step(20)).unwrap();
    assert_eq!(run.torn_log_line().unwrap(), None);
    // A crash in the middle of the third line.
    let whole = serde_json::to_string(&step(30)).unwrap();
    let mut f = std::fs::OpenOptions::new()
        .append(true)
        .open(dir.join(RunDir::LOG))
        .unwrap();
    std::io::Write::write_all(&mut f, &whole.as_bytes()[..whole.len() / 2]).unwrap();
    assert_eq!(run.torn_log_line().unwrap(), Some(3));
    assert_eq!(run.log().unwrap(), vec![step(10), step(20)]);
    assert_eq!(run.truncate_log(100).unwrap(), 20.0);
    run.append(&step(30)).unwrap();
    assert_eq!(run.log().unwrap(), vec![step(10), step(20), step(30)]);
    // A bad line that does end in a line break is no torn line: an error.
    std::fs::write(dir.join(RunDir::LOG), "{\"event\":\"step\"}\n").unwrap();
    assert!(run.log().is_err());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn truncating_a_log_keeps_earlier_steps_and_their_clock() {
    let dir = fresh("truncate");
    let (run, _lock) = RunDir::create(&dir, &config()).unwrap();
    assert_eq!(run.truncate_log(0).unwrap(), 0.0); // no log yet
    let lines = [
        format!(
            r#"{{"event":"start","version":2,"config":{},"git_revision":null,"baselines":{{}}}}"#,
            serde_json::to_string(&config()).unwrap()
        ),
        r#"{"event":"step","step":10,"loss":0.5,"epsilon":1.0,"elapsed_s":1.0}"#.to_owned(),
        r#"{"event":"validation","step":20,"welfare":1.0,"percent_of_opt":50.0,"elapsed_s":2.5}"#
            .to_owned(),
        r#"{"event":"step","step":30,"loss":0.5,"epsilon":1.0,"elapsed_s":4.0}"#.to_owned(),
    ];
    std::fs::write(dir.join(RunDir::LOG), lines.join("\n") + "\n").unwrap();
    assert_eq!(run.truncate_log(20).unwrap(), 2.5);
    // The kept lines are the lines as written, not re-serialised events.
    assert_eq!(
        std::fs::read_to_string(dir.join(RunDir::LOG)).unwrap(),
        lines[..3].join("\n") + "\n"
    );
    let kept = run.log().unwrap();
    assert_eq!(kept.len(), 3);
    assert_eq!(kept.last().unwrap().step(), Some(20));
    assert!(matches!(kept[0], LogEvent::Start { .. }));
    assert_eq!(run.truncate_log(0).unwrap(), 0.0);
    assert_eq!(run.log().unwrap().len(), 1);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_directory_holds_one_run_and_one_trainer_at_a_time() {
    let dir = fresh("lock");
    let (run, lock) = RunDir::create(&dir, &config()).unwrap();
    // While the first holds it, even a second create is refused as in use.
    assert!(matches!(
        RunDir::create(&dir, &config()),
        Err(LearnError::RunInUse { .. })
    ));
    assert!(matches!(
        RunDir::new(&dir).lock(),
        Err(LearnError::RunInUse { .. })
    ));
    drop(lock);
    let err = RunDir::create(&dir, &config()).unwrap_err();
    assert!(err.to_string().contains("already holds"), "{err}");
    let _again = RunDir::new(&dir).lock().unwrap();
    // Missing and foreign files are clear errors.
    let empty = RunDir::new(fresh("empty"));
    assert!(
        empty
            .config()
            .unwrap_err()
            .to_string()
            .contains("no training run")
    );
    std::fs::write(dir.join("config.json"), "{\"version\": 2, \"robots\": 3}").unwrap();
    assert!(
        run.config()
            .unwrap_err()
            .to_string()
            .contains("not a training configuration")
    );
    // Without a version, the file is an older format's: the error says how to migrate.
    std::fs::write(dir.join("config.json"), "{\"robots\": 3}").unwrap();
    assert!(
        run.config()
            .unwrap_err()
            .to_string()
            .contains("afg migrate")
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn manifests_round_trip() {
    let dir = fresh("manifest");
    let (run, _lock) = RunDir::create(&dir, &config()).unwrap();
    assert!(run.manifest().is_err());
    // Not finished: no kind of model yet.
    assert!(
        run.kind()
            .unwrap_err()
            .to_string()
            .contains("no finished run")
    );
    let record = RunRecord::QNetwork {
        steps: 100,
        final_validation: None,
    };
    let manifest = RunManifest {
        wall_time_s: Some(60.0),
        ..RunManifest::new("cargo xtask train --scale 20".into(), 0, record)
    };
    assert_eq!(manifest.weights, ["model.json", "model.mpk"]);
    run.write_manifest(&manifest).unwrap();
    assert_eq!(run.manifest().unwrap(), manifest);
    assert_eq!(run.kind().unwrap(), ModelKind::QNetwork);
    // A manifest of format 1 (no version, no kind) is named as such.
    let text = std::fs::read_to_string(dir.join("manifest.json")).unwrap();
    let old = text
        .replace("\"version\": 2,", "")
        .replace("\"kind\": \"q-network\",", "");
    assert_ne!(old, text);
    std::fs::write(dir.join("manifest.json"), old).unwrap();
    assert!(
        run.manifest()
            .unwrap_err()
            .to_string()
            .contains("afg migrate")
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn presets_are_recorded_and_every_field_is_required() {
    let paper = TrainConfig::paper(20, Algo::Dqn, NetworkConfig::s2v(5, 0), 100, 0);
    let text = serde_json::to_string(&paper).unwrap();
    assert!(text.contains("\"preset\":\"paper\""));
    let back: TrainConfig = serde_json::from_str(&text).unwrap();
    assert_eq!(back, paper);
    assert_eq!(config().preset, Preset::Ours);
    // Format 1 left the preset out; format 2 refuses that (`afg migrate` fills it in).
    let mut old: serde_json::Value = serde_json::to_value(config()).unwrap();
    old.as_object_mut().unwrap().remove("preset");
    let err = serde_json::from_value::<TrainConfig>(old).unwrap_err();
    assert!(err.to_string().contains("missing field `preset`"), "{err}");
}

/// Every committed Q-network run directory (every run below models/ with a config).
fn committed_runs() -> Vec<PathBuf> {
    let models = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../models");
    RunDir::find_all(&models)
        .unwrap()
        .into_iter()
        .map(|run| run.path().to_path_buf())
        .filter(|path| path.join("config.json").exists())
        .collect()
}

#[test]
fn every_committed_run_reads_back_typed() {
    let runs = committed_runs();
    assert!(runs.len() >= 10, "{} runs", runs.len());
    for path in runs {
        let run = RunDir::new(&path);
        let config = run.config().unwrap();
        let log = run.log().unwrap();
        assert!(
            matches!(&log[0], LogEvent::Start { config: c, .. } if **c == config),
            "{}",
            path.display()
        );
        if path.join("manifest.json").exists() {
            let record = run.manifest().unwrap().record;
            assert!(
                matches!(record, RunRecord::QNetwork { steps, .. } if steps == config.steps),
                "{}",
                path.display()
            );
        }
    }
}

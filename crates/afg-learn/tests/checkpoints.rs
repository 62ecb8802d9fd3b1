//! Checkpoints and sessions: bit-identical resume, the run directory a session writes,
//! truncated, missing or broken checkpoints, a run stopped before its first checkpoint.

mod tiny_runs;

use std::path::PathBuf;

use afg_learn::{
    LearnError,
    nets::NetworkConfig,
    policy::LearnedPolicy,
    run::{LogEvent, RunDir},
    train::{Algo, Session, Trainer},
};

use tiny_runs::{tiny, weight_bits};

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("afg-train-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn run_to(trainer: &mut Trainer, steps: u64) {
    while trainer.steps_done() < steps {
        trainer.step().unwrap();
    }
}

#[test]
fn resumed_run_ends_with_bit_identical_weights() {
    let config = tiny(Algo::Ddqn, NetworkConfig::afgnet(5, 2), 60);
    let mut straight = Trainer::new(config.clone()).unwrap();
    run_to(&mut straight, 60);

    let dir = temp_dir("resume");
    let mut first = Trainer::new(config).unwrap();
    run_to(&mut first, 25);
    first.save_checkpoint(&dir).unwrap();
    drop(first); // "killed"
    let mut resumed = Trainer::resume(&dir).unwrap();
    assert_eq!(resumed.steps_done(), 25);
    run_to(&mut resumed, 60);
    assert_eq!(
        weight_bits(&resumed.network()),
        weight_bits(&straight.network())
    );
    // A later checkpoint replaces the earlier one.
    resumed.save_checkpoint(&dir).unwrap();
    assert_eq!(Trainer::resume(&dir).unwrap().steps_done(), 60);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_session_logs_and_saves_its_run_and_refuses_a_second_writer() {
    let dir = temp_dir("session").join("run");
    let config = tiny(Algo::Ddqn, NetworkConfig::s2v(5, 4), 40);
    let mut session = Session::start(&dir, config.clone(), Some("abc".into())).unwrap();
    // The directory is locked while the session lives.
    assert!(matches!(
        Session::resume(&dir),
        Err(LearnError::RunInUse { .. })
    ));
    let mut seen = 0;
    let v = session
        .run(std::time::Duration::from_secs(3600), |r| {
            seen += 1;
            assert_eq!(r.step, seen);
        })
        .unwrap();
    assert_eq!(seen, 40);
    drop(session);
    let run = RunDir::new(&dir);
    let log = run.log().unwrap();
    let LogEvent::Start {
        version,
        config: logged,
        git_revision,
        baselines,
    } = &log[0]
    else {
        panic!("the log starts with {:?}", log[0]);
    };
    assert_eq!(
        (**logged == config, git_revision.as_deref(), *version),
        (true, Some("abc"), afg_learn::run::RUN_FORMAT_VERSION)
    );
    assert!(baselines[&afg_baseline::Method::Opt] >= baselines[&afg_baseline::Method::Greedy]);
    let steps: Vec<u64> = log
        .iter()
        .filter(|e| matches!(e, LogEvent::Step { .. }))
        .map(|e| e.step().unwrap())
        .collect();
    assert_eq!(steps, [10, 20, 30, 40]);
    let validations = log
        .iter()
        .filter(|e| matches!(e, LogEvent::Validation(_)))
        .count();
    assert_eq!(validations, 2);
    assert!(matches!(log.last(), Some(LogEvent::End { step: 40, .. })));
    let manifest = run.manifest_from_log("train it".into()).unwrap();
    assert_eq!(
        (manifest.command.as_str(), manifest.seed, manifest.kind()),
        ("train it", config.seed, afg_learn::run::ModelKind::QNetwork)
    );
    assert_eq!(manifest.git_revision.as_deref(), Some("abc"));
    let afg_learn::run::RunRecord::QNetwork {
        steps,
        final_validation,
    } = manifest.record
    else {
        unreachable!("a Q network's run")
    };
    assert_eq!((steps, final_validation.map(|v| v.step)), (40, Some(40)));
    // The final weights are the trainer's: the same validation.
    let policy = LearnedPolicy::load(&run.weights()).unwrap();
    assert_eq!(policy.config(), &config.network);
    assert_eq!(Trainer::resume(&dir).unwrap().validate().unwrap(), v);
    // A second run into the same directory is refused; resuming a finished one is not.
    assert!(Session::start(&dir, config, None).is_err());
    Session::resume(&dir).unwrap();
    std::fs::remove_dir_all(dir.parent().unwrap()).unwrap();
}

#[test]
fn truncated_or_missing_checkpoints_are_clear_errors() {
    let dir = temp_dir("bad");
    assert!(matches!(
        Trainer::resume(&dir),
        Err(LearnError::Checkpoint { .. })
    ));
    let mut t = Trainer::new(tiny(Algo::Dqn, NetworkConfig::s2v(5, 0), 20)).unwrap();
    run_to(&mut t, 5);
    t.save_checkpoint(&dir).unwrap();
    let state = dir.join("checkpoint/state.json");
    let text = std::fs::read_to_string(&state).unwrap();
    std::fs::write(&state, &text[..text.len() / 2]).unwrap();
    let err = Trainer::resume(&dir).err().unwrap();
    assert!(err.to_string().contains("corrupt or truncated"), "{err}");
    std::fs::write(&state, &text).unwrap();
    let optim = dir.join("checkpoint/optim.mpk");
    let bytes = std::fs::read(&optim).unwrap();
    std::fs::write(&optim, &bytes[..bytes.len() / 3]).unwrap();
    assert!(matches!(
        Trainer::resume(&dir),
        Err(LearnError::Weights { .. })
    ));
    std::fs::write(&optim, &bytes).unwrap();
    // A state that parses but cannot be this run's: an action beyond M, an episode of
    // the wrong length, an unknown field.
    let value: serde_json::Value = serde_json::from_str(&text).unwrap();
    type Edit = fn(&mut serde_json::Value);
    let edits: [(&str, Edit); 3] = [
        ("takes task 9", |v| v["running"][0]["actions"][0] = 9.into()),
        ("has 11 actions", |v| {
            let actions = v["running"][0]["actions"].as_array_mut().unwrap();
            actions.resize(11, 0.into());
        }),
        ("unknown field", |v| v["extra"] = 1.into()),
    ];
    for (says, edit) in edits {
        let mut v = value.clone();
        edit(&mut v);
        std::fs::write(&state, v.to_string()).unwrap();
        let err = Trainer::resume(&dir).err().unwrap();
        assert!(err.to_string().contains(says), "{says}: {err}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_broken_checkpoint_falls_back_to_the_previous_one() {
    let config = tiny(Algo::Dqn, NetworkConfig::s2v(5, 0), 30);
    let dir = temp_dir("fallback");
    let mut t = Trainer::new(config.clone()).unwrap();
    run_to(&mut t, 10);
    t.save_checkpoint(&dir).unwrap();
    run_to(&mut t, 20);
    t.save_checkpoint(&dir).unwrap();
    assert!(
        dir.join("checkpoint.old").exists(),
        "the previous one is kept"
    );
    assert_eq!(Trainer::resume(&dir).unwrap().steps_done(), 20);
    // The newest truncated (as by a full disk), or gone (a crash between the renames).
    let state = dir.join("checkpoint/state.json");
    std::fs::write(&state, "{\"format\":").unwrap();
    assert_eq!(Trainer::resume(&dir).unwrap().steps_done(), 10);
    std::fs::remove_dir_all(dir.join("checkpoint")).unwrap();
    let mut resumed = Trainer::resume(&dir).unwrap();
    assert_eq!(resumed.steps_done(), 10);
    // And the run from the older one ends where an uninterrupted run does.
    run_to(&mut resumed, 30);
    let mut straight = Trainer::new(config).unwrap();
    run_to(&mut straight, 30);
    assert_eq!(
        weight_bits(&resumed.network()),
        weight_bits(&straight.network())
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_run_stopped_before_its_first_checkpoint_starts_again_on_resume() {
    let dir = temp_dir("early").join("run");
    let config = tiny(Algo::Ddqn, NetworkConfig::s2v(5, 4), 20);
    drop(Session::start(&dir, config.clone(), None).unwrap()); // killed at once
    assert!(!dir.join("checkpoint").exists());
    let mut session = Session::resume(&dir).unwrap();
    assert_eq!(session.trainer().steps_done(), 0);
    session
        .run(std::time::Duration::from_secs(3600), |_| {})
        .unwrap();
    let mut straight = Trainer::new(config).unwrap();
    run_to(&mut straight, 20);
    assert_eq!(
        weight_bits(&session.trainer().network()),
        weight_bits(&straight.network())
    );
    std::fs::remove_dir_all(dir.parent().unwrap()).unwrap();
}

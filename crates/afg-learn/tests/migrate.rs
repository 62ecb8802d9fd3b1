//! Run directories of format 1 (before every field was written and files carried a
//! version): refused with a word on the migration, then migrated once to exactly the
//! committed (format 2) files, and loaded as the committed runs are.

use std::path::{Path, PathBuf};

use afg_baseline::Allocator;
use afg_game::GeneratorConfig;
use afg_learn::{
    nets::NetworkConfig,
    policy::LearnedPolicy,
    run::{RunDir, migrate_run},
    train::{Algo, TrainConfig, Trainer},
};
use serde_json::{Value, json};

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("afg-migrate-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// A format-2 network configuration as format 1 wrote it: units left out when they
/// were mean-reward, the AFGNet switches `null` when off.
fn network_as_v1(network: &mut Value) {
    let fields = network.as_object_mut().unwrap();
    if fields["units"] == json!("mean-reward") {
        fields.remove("units");
    }
    for key in ["gain_residual", "price_head"] {
        if fields.get(key) == Some(&json!(false)) {
            fields.insert(key.into(), Value::Null);
        }
    }
}

/// A format-2 training configuration as format 1 wrote it: no version, the fields
/// added since left out where they hold what format 1 meant by their absence, and the
/// shaping as the boolean flag.
fn config_as_v1(config: &mut Value) {
    network_as_v1(&mut config["network"]);
    let fields = config.as_object_mut().unwrap();
    fields.remove("version");
    for (key, absent) in [
        ("preset", json!("ours")),
        ("lr_decay", json!(false)),
        ("n_step", json!(1)),
    ] {
        if fields[key] == absent {
            fields.remove(key);
        }
    }
    let shaping = fields.remove("shaping").unwrap();
    if shaping != json!("optimal") {
        fields.insert("greedy_shaping".into(), json!(shaping == json!("greedy")));
    } else {
        fields.insert("shaping".into(), shaping);
    }
}

fn read(path: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

fn write(path: &Path, value: &Value) {
    std::fs::write(path, serde_json::to_string_pretty(value).unwrap()).unwrap();
}

/// Every committed Q-network run, written back as format 1 and migrated, gives its
/// committed configuration and weights header back; before the migration each file is
/// refused with a word on `afg migrate`.
#[test]
fn every_committed_run_written_as_format_1_migrates_back_to_itself() {
    let runs: Vec<PathBuf> = RunDir::find_all(&repo().join("models"))
        .unwrap()
        .into_iter()
        .map(|run| run.path().to_path_buf())
        .filter(|p| p.join("config.json").exists() && p.join("model.json").exists())
        .collect();
    assert!(runs.len() >= 30, "{}", runs.len());
    for committed in runs {
        let name = committed
            .file_name()
            .unwrap()
            .to_string_lossy()
            .into_owned();
        let dir = scratch(&name);
        let mut config = read(&committed.join("config.json"));
        config_as_v1(&mut config);
        write(&dir.join("config.json"), &config);
        let mut header = read(&committed.join("model.json"));
        header["version"] = json!(1);
        network_as_v1(&mut header["network"]);
        write(&dir.join("model.json"), &header);
        let run = RunDir::new(&dir);
        let refused = run.config().unwrap_err().to_string();
        assert!(refused.contains("afg migrate"), "{name}: {refused}");

        let rewritten = migrate_run(&dir).unwrap();
        assert_eq!(rewritten.len(), 2, "{name}");
        let original = RunDir::new(&committed);
        assert_eq!(run.config().unwrap(), original.config().unwrap(), "{name}");
        assert_eq!(
            std::fs::read_to_string(dir.join("model.json")).unwrap(),
            std::fs::read_to_string(committed.join("model.json")).unwrap(),
            "{name}"
        );
        assert!(migrate_run(&dir).unwrap().is_empty(), "{name}: twice");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}

/// A format-1 run with weights and a log: refused, then after the migration it loads
/// and allocates exactly as the committed run, and its log's start line reads.
#[test]
fn a_format_1_run_allocates_as_the_committed_one_after_migration() {
    let committed = repo().join("models/paper/afgnet_ddqn_n20");
    let dir = scratch("n20");
    std::fs::copy(committed.join("model.mpk"), dir.join("model.mpk")).unwrap();
    let mut header = read(&committed.join("model.json"));
    header["version"] = json!(1);
    network_as_v1(&mut header["network"]);
    write(&dir.join("model.json"), &header);
    let mut config = read(&committed.join("config.json"));
    config_as_v1(&mut config);
    let start = json!({"event": "start", "config": config});
    let step = r#"{"event":"step","step":10,"loss":0.5,"epsilon":0.9,"elapsed_s":1.0}"#;
    std::fs::write(dir.join(RunDir::LOG), format!("{start}\n{step}\n")).unwrap();
    let run = RunDir::new(&dir);
    let refused = LearnedPolicy::load(&run.weights())
        .err()
        .unwrap()
        .to_string();
    assert!(refused.contains("afg migrate"), "{refused}");
    assert!(run.log().unwrap_err().to_string().contains("afg migrate"));

    assert_eq!(migrate_run(&dir).unwrap().len(), 2);
    let log = run.log().unwrap();
    assert_eq!((log.len(), log[1].step()), (2, Some(10)));
    let ours = LearnedPolicy::load(&run.weights()).unwrap();
    let theirs = LearnedPolicy::load(&RunDir::new(&committed).weights()).unwrap();
    for seed in 0..3 {
        let inst = GeneratorConfig::paper(20, 5, seed).generate().unwrap();
        assert_eq!(
            ours.allocate(&inst).unwrap().assignment,
            theirs.allocate(&inst).unwrap().assignment
        );
    }
    assert!(migrate_run(&dir).unwrap().is_empty());
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The boolean shaping flag of format 1 reads as greedy or none, and no flag as none.
#[test]
fn the_format_1_shaping_flag_becomes_the_shaping() {
    let committed = read(&repo().join("models/paper/afgnet_ddqn_n60/config.json"));
    for (flag, shaping) in [
        (Some(true), "greedy"),
        (Some(false), "none"),
        (None, "none"),
    ] {
        let dir = scratch(&format!("flag-{flag:?}"));
        let mut config = committed.clone();
        config_as_v1(&mut config);
        let fields = config.as_object_mut().unwrap();
        fields.remove("greedy_shaping");
        if let Some(flag) = flag {
            fields.insert("greedy_shaping".into(), json!(flag));
        }
        write(&dir.join("config.json"), &config);
        migrate_run(&dir).unwrap();
        let migrated = read(&dir.join("config.json"));
        assert_eq!(migrated["shaping"], json!(shaping), "{flag:?}");
        assert_eq!(migrated["version"], json!(2));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}

/// A format-1 price run (`summary.json` beside `price.json`) gets the committed run's
/// format-2 manifest, and its summary is gone; a format-1 Q-network manifest (no version,
/// no kind) gets its version and kind.
#[test]
fn format_1_summaries_and_manifests_become_format_2_manifests() {
    let committed = repo().join("models/ours/price_n60");
    let dir = scratch("price");
    std::fs::copy(committed.join("price.json"), dir.join("price.json")).unwrap();
    // Its log of rounds is not a Q network's log of events: left as it is.
    std::fs::copy(committed.join(RunDir::LOG), dir.join(RunDir::LOG)).unwrap();
    let manifest = read(&committed.join("manifest.json"));
    let summary = json!({
        "command": manifest["command"],
        "wall_s": manifest["wall_time_s"],
        "last": manifest["last_round"],
    });
    write(&dir.join("summary.json"), &summary);
    assert!(RunDir::new(&dir).kind().is_err());
    assert_eq!(migrate_run(&dir).unwrap().len(), 2);
    assert!(!dir.join("summary.json").exists());
    assert_eq!(
        std::fs::read(dir.join(RunDir::LOG)).unwrap(),
        std::fs::read(committed.join(RunDir::LOG)).unwrap()
    );
    assert_eq!(
        RunDir::new(&dir).manifest().unwrap(),
        RunDir::new(&committed).manifest().unwrap()
    );
    assert_eq!(
        RunDir::new(&dir).kind().unwrap(),
        afg_learn::run::ModelKind::PriceModel
    );
    std::fs::remove_dir_all(&dir).unwrap();

    let committed = repo().join("models/paper/afgnet_ddqn_n60");
    let dir = scratch("q-manifest");
    let mut manifest = read(&committed.join("manifest.json"));
    let fields = manifest.as_object_mut().unwrap();
    fields.remove("version");
    fields.remove("kind");
    write(&dir.join("manifest.json"), &manifest);
    assert!(
        RunDir::new(&dir)
            .manifest()
            .unwrap_err()
            .to_string()
            .contains("afg migrate")
    );
    assert_eq!(migrate_run(&dir).unwrap().len(), 1);
    assert_eq!(
        RunDir::new(&dir).manifest().unwrap(),
        RunDir::new(&committed).manifest().unwrap()
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A format-1 checkpoint (its two weights headers and the trainer's state): resuming
/// is refused with a word on the migration; after it the run resumes where it was.
#[test]
fn a_format_1_checkpoint_resumes_after_migration() {
    let dir = scratch("checkpoint");
    let mut config = TrainConfig::new(10, Algo::Dqn, NetworkConfig::s2v(5, 0), 20, 3);
    (config.batch, config.parallel_envs, config.warmup) = (32, 4, 64);
    (config.replay_capacity, config.validation_instances) = (2_000, 4);
    let mut trainer = Trainer::new(config).unwrap();
    while trainer.steps_done() < 5 {
        trainer.step().unwrap();
    }
    trainer.save_checkpoint(&dir).unwrap();
    let checkpoint = afg_learn::train::checkpoint_dir(&dir);
    for file in ["online.json", "target.json"] {
        let mut header = read(&checkpoint.join(file));
        header["version"] = json!(1);
        network_as_v1(&mut header["network"]);
        write(&checkpoint.join(file), &header);
    }
    let state_path = checkpoint.join("state.json");
    let mut state = read(&state_path);
    state["version"] = json!(1);
    config_as_v1(&mut state["config"]);
    std::fs::write(&state_path, state.to_string()).unwrap();
    let refused = Trainer::resume(&dir).err().unwrap().to_string();
    assert!(refused.contains("afg migrate"), "{refused}");

    assert_eq!(migrate_run(&dir).unwrap().len(), 3);
    let resumed = Trainer::resume(&dir).unwrap();
    assert_eq!(
        (resumed.steps_done(), resumed.config()),
        (5, trainer.config())
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

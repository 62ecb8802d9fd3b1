//! Run directories written by earlier versions of afg, brought to the current format
//! once ([`migrate_run`], `afg migrate DIR…`). Readers accept the current format only
//! and name this migration when they meet an older one.
//!
//! | format | files |
//! |---|---|
//! | 1 | a Q network's `manifest.json` without version or kind, a price run's `summary.json` instead of a manifest; weights headers (`model.json`, the checkpoint's) of version 1, whose network may leave out `gain_residual` and `price_head` (off) and `units` (mean reward); `config.json` and the log's start line without a version, and possibly without `preset` (ours), `lr_decay` (off), `n_step` (1) or `shaping` (none), or with the boolean `greedy_shaping` instead; start lines possibly without `git_revision` or `baselines` |
//! | 2 | every field written; `config.json`, `manifest.json` (with the `kind` of model) and the log's start line carry `"version": 2`, weights headers version 2 |

use std::path::{Path, PathBuf};

use serde_json::{Map, Value, json};

use crate::LearnError;
use crate::format::RUN_FORMAT_VERSION;
use crate::run_dir::LogEvent;
use crate::train::TrainConfig;

fn bad(path: &Path, reason: impl Into<String>) -> LearnError {
    LearnError::RunFile {
        path: path.display().to_string(),
        reason: reason.into(),
    }
}

/// Fills in what a format-1 network configuration left out.
fn network_v1(network: &mut Value) {
    let Some(fields) = network.as_object_mut() else {
        return;
    };
    let afgnet = fields.get("net") == Some(&json!("afgnet"));
    let mut fill = |key: &str, value: Value| {
        if fields.get(key).is_none_or(Value::is_null) {
            fields.insert(key.to_owned(), value);
        }
    };
    fill("units", json!("mean-reward"));
    if afgnet {
        fill("gain_residual", json!(false));
        fill("price_head", json!(false));
    }
}

/// Fills in what a format-1 training configuration left out.
fn config_v1(config: &mut Value) {
    let Some(fields) = config.as_object_mut() else {
        return;
    };
    if let Some(network) = fields.get_mut("network") {
        network_v1(network);
    }
    if let Some(flag) = fields.remove("greedy_shaping") {
        let shaping = if flag == json!(true) {
            "greedy"
        } else {
            "none"
        };
        fields.insert("shaping".into(), json!(shaping));
    }
    for (key, value) in [
        ("preset", json!("ours")),
        ("lr_decay", json!(false)),
        ("n_step", json!(1)),
        ("shaping", json!("none")),
    ] {
        fields.entry(key).or_insert(value);
    }
}

/// A format-1 start line's fields brought to format 2 (other events are unchanged).
fn start_v1(event: &mut Map<String, Value>) {
    if let Some(config) = event.get_mut("config") {
        config_v1(config);
    }
    event.entry("git_revision").or_insert(Value::Null);
    event.entry("baselines").or_insert(json!({}));
    event.insert("version".into(), json!(RUN_FORMAT_VERSION));
}

/// The version a file's JSON object records (`None`: format 1, before versions).
fn version_of(value: &Value) -> Option<u64> {
    value.get("version").and_then(Value::as_u64)
}

/// Whether a file that records its version (`what`, read from `path`) is of format 1;
/// `false` if it is current.
///
/// # Errors
/// [`LearnError::RunFile`] for any other version.
fn is_format_1(path: &Path, value: &Value, what: &str) -> Result<bool, LearnError> {
    match version_of(value) {
        Some(1) => Ok(true),
        Some(v) if v == u64::from(RUN_FORMAT_VERSION) => Ok(false),
        _ => Err(bad(path, format!("not {what} of a known version"))),
    }
}

fn read_json(path: &Path) -> Result<Value, LearnError> {
    let text = std::fs::read_to_string(path).map_err(|e| bad(path, e.to_string()))?;
    serde_json::from_str(&text).map_err(|e| bad(path, format!("not JSON: {e}")))
}

fn write(path: &Path, text: &str) -> Result<(), LearnError> {
    afg_game::fs::write_atomic(path, text.as_bytes())?;
    Ok(())
}

/// A weights header brought to format 2; `false` if it already was.
fn migrate_weights_header(path: &Path) -> Result<bool, LearnError> {
    let mut header = read_json(path)?;
    if !is_format_1(path, &header, "a weights header")? {
        return Ok(false);
    }
    if let Some(network) = header.get_mut("network") {
        network_v1(network);
    }
    header["version"] = json!(RUN_FORMAT_VERSION);
    // Read back as the current format, so that what is written is what loads.
    let network: crate::qnetwork::NetworkConfig = serde_json::from_value(header["network"].clone())
        .map_err(|e| bad(path, format!("not a network configuration: {e}")))?;
    let text = crate::weights::header_json(&network);
    write(path, &text)?;
    Ok(true)
}

/// A checkpoint's trainer state brought to format 2; `false` if it already was.
fn migrate_state(path: &Path) -> Result<bool, LearnError> {
    let mut state = read_json(path)?;
    if !is_format_1(path, &state, "a trainer state")? {
        return Ok(false);
    }
    if let Some(config) = state.get_mut("config") {
        config_v1(config);
    }
    state["version"] = json!(RUN_FORMAT_VERSION);
    write(path, &state.to_string())?;
    Ok(true)
}

/// `config.json` brought to format 2; `false` if it already was.
fn migrate_config(path: &Path) -> Result<bool, LearnError> {
    let mut config = read_json(path)?;
    if version_of(&config).is_some() {
        return Ok(false);
    }
    config_v1(&mut config);
    let config: TrainConfig = serde_json::from_value(config)
        .map_err(|e| bad(path, format!("not a training configuration: {e}")))?;
    write(path, &crate::run_dir::config_json(&config))?;
    Ok(true)
}

/// `log.jsonl` with its start lines brought to format 2 (every other line kept as
/// written, a price run's rounds included: they have no `event`); `false` if there was
/// nothing to change.
fn migrate_log(path: &Path) -> Result<bool, LearnError> {
    let text = std::fs::read_to_string(path).map_err(|e| bad(path, e.to_string()))?;
    let mut changed = false;
    let mut out = String::with_capacity(text.len());
    for (number, line) in text.lines().enumerate() {
        let mut kept = line.to_owned();
        if let Ok(Value::Object(mut event)) = serde_json::from_str::<Value>(line)
            && event.get("event") == Some(&json!("start"))
            && !event.contains_key("version")
        {
            start_v1(&mut event);
            let event: LogEvent = serde_json::from_value(Value::Object(event))
                .map_err(|e| bad(path, format!("line {}: not a start event: {e}", number + 1)))?;
            kept = serde_json::to_string(&event).expect("an event serialises");
            changed = true;
        }
        out.push_str(&kept);
        out.push('\n');
    }
    if changed {
        write(path, &out)?;
    }
    Ok(changed)
}

/// Brings the run directory `dir` (a Q network's weights headers, checkpoints,
/// `config.json`, `log.jsonl` and manifest; a price run's summary) to format
/// [`RUN_FORMAT_VERSION`], rewriting each file atomically; returns the files rewritten
/// (none if it already was current).
/// Running it twice changes nothing the second time.
///
/// # Errors
/// [`LearnError::RunFile`] naming a file that is not what its name says, and
/// [`LearnError::Io`] if one cannot be rewritten.
///
/// # Examples
/// ```
/// use afg_learn::run::{RUN_FORMAT_VERSION, migrate_run};
/// let dir = std::env::temp_dir().join(format!("afg-doc-migrate-{}", std::process::id()));
/// std::fs::create_dir_all(&dir)?;
/// let v1 = r#"{"format":"afg-weights","version":1,"network":{"net":"s2v","tasks":5,"hidden":64,"iterations":4,"activation":"relu","seed":0}}"#;
/// std::fs::write(dir.join("model.json"), v1)?;
/// assert_eq!(migrate_run(&dir)?.len(), 1);
/// let header = std::fs::read_to_string(dir.join("model.json"))?;
/// assert!(header.contains(r#""units": "mean-reward""#) && header.contains(&format!(r#""version": {RUN_FORMAT_VERSION}"#)));
/// assert!(migrate_run(&dir)?.is_empty()); // already current
/// # std::fs::remove_dir_all(&dir)?;
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn migrate_run(dir: &Path) -> Result<Vec<PathBuf>, LearnError> {
    let mut rewritten = Vec::new();
    let mut headers = vec![dir.join("model.json")];
    let mut states = Vec::new();
    for checkpoint in crate::train::checkpoint_dirs(dir) {
        headers.extend(["online.json", "target.json"].map(|f| checkpoint.join(f)));
        states.push(checkpoint.join("state.json"));
    }
    for path in headers {
        if path.exists() && migrate_weights_header(&path)? {
            rewritten.push(path);
        }
    }
    for path in states {
        if path.exists() && migrate_state(&path)? {
            rewritten.push(path);
        }
    }
    let config = dir.join("config.json");
    if config.exists() && migrate_config(&config)? {
        rewritten.push(config);
    }
    rewritten.extend(migrate_manifest(dir)?);
    let log = dir.join(crate::run_dir::RunDir::LOG);
    if log.exists() && migrate_log(&log)? {
        rewritten.push(log);
    }
    Ok(rewritten)
}

/// A format-1 manifest (a Q network's, without version or kind) brought to format 2,
/// and a format-1 price run's `summary.json` (command, wall time, last round) made its
/// `manifest.json`; the files rewritten, removed or made.
fn migrate_manifest(dir: &Path) -> Result<Vec<PathBuf>, LearnError> {
    let run = crate::run_dir::RunDir::new(dir);
    let path = dir.join("manifest.json");
    let mut rewritten = Vec::new();
    if path.exists() {
        let mut manifest = read_json(&path)?;
        if version_of(&manifest).is_none() {
            manifest["version"] = json!(RUN_FORMAT_VERSION);
            manifest["kind"] = json!("q-network");
            let manifest = serde_json::from_value(manifest)
                .map_err(|e| bad(&path, format!("not a run manifest: {e}")))?;
            run.write_manifest(&manifest)?;
            rewritten.push(path.clone());
        }
    }
    let summary_path = dir.join("summary.json");
    if summary_path.exists() {
        let summary = read_json(&summary_path)?;
        let model = crate::price::PriceModel::load(&dir.join(crate::price::PriceModel::FILE_NAME))?;
        let last_round = serde_json::from_value(summary["last"].clone())
            .map_err(|e| bad(&summary_path, format!("not a price-run summary: {e}")))?;
        let command = summary["command"].as_str().unwrap_or_default().to_owned();
        let record = crate::manifest::RunRecord::PriceModel {
            rounds: model.training.rounds,
            last_round: Some(last_round),
        };
        let manifest = crate::manifest::RunManifest {
            wall_time_s: summary["wall_s"].as_f64(),
            ..crate::manifest::RunManifest::new(command, model.training.seed, record)
        };
        run.write_manifest(&manifest)?;
        std::fs::remove_file(&summary_path).map_err(|source| LearnError::Io {
            path: summary_path.display().to_string(),
            source,
        })?;
        rewritten.extend([path, summary_path]);
    }
    Ok(rewritten)
}

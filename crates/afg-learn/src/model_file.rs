//! The one file format of the small task-MLP models (the price model, the staffing
//! model): JSON with a format name and version, written atomically, read back with
//! its format, version and weights' shape checked.

use std::path::Path;

use serde::Serialize;

use crate::LearnError;

/// Writes a model file (the price model's, the staffing model's) as JSON, atomically.
pub(crate) fn write_model_file<T: Serialize>(model: &T, path: &Path) -> Result<(), LearnError> {
    let json = serde_json::to_string(model).expect("a model always serialises");
    afg_game::fs::write_atomic(path, json.as_bytes())?;
    Ok(())
}

/// Reads a model file written by [`write_model_file`]; `what` names it in errors.
pub(crate) fn read_model_file<T: serde::de::DeserializeOwned>(
    path: &Path,
    what: &str,
) -> Result<T, LearnError> {
    let text = std::fs::read_to_string(path).map_err(|e| weights_error(path, e.to_string()))?;
    serde_json::from_str(&text)
        .map_err(|e| weights_error(path, format!("not {what} (truncated?): {e}")))
}

/// Checks a model file's format and version against the expected ones, then its
/// weights (`shape`: why they do not fit, if they do not).
pub(crate) fn check_model_file(
    path: &Path,
    (format, version): (&str, u32),
    (expected, expected_version): (&str, u32),
    shape: Result<(), String>,
) -> Result<(), LearnError> {
    if format != expected || version != expected_version {
        return Err(weights_error(
            path,
            format!(
                "format {format} version {version}, expected {expected} version {expected_version}"
            ),
        ));
    }
    shape.map_err(|reason| weights_error(path, reason))
}

fn weights_error(path: &Path, reason: String) -> LearnError {
    LearnError::Weights {
        path: path.display().to_string(),
        reason,
    }
}

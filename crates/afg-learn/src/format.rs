//! The format of a run directory's files: its version, written into every file, and
//! how a reader tells a file of an older format (which `afg migrate` brings up to date)
//! from a malformed one.

/// The current format of a run directory's files.
pub const RUN_FORMAT_VERSION: u32 = 2;

/// What a reader says of a file in an older format.
pub(crate) fn older_format_hint() -> String {
    format!(
        "written in an older format; run `afg migrate DIR` once to bring the run directory to format {RUN_FORMAT_VERSION}"
    )
}

/// Whether the JSON text is a file of an older format than [`RUN_FORMAT_VERSION`]: an
/// object that records no `version` (format 1 files other than weights headers
/// recorded none) or a lower one. Asked before the file is read as the current format,
/// so that an older file is named as such rather than as malformed; text that is not a
/// JSON object (a truncated file) is not older, and its reader reports it.
pub(crate) fn is_older(text: &str) -> bool {
    #[derive(serde::Deserialize)]
    struct Versioned {
        version: Option<u64>,
    }
    serde_json::from_str::<Versioned>(text)
        .is_ok_and(|v| v.version.is_none_or(|v| v < u64::from(RUN_FORMAT_VERSION)))
}

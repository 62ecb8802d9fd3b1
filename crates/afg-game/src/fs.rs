//! Durable file writes: a file is replaced whole or not at all, even across a crash or
//! a full disk.

use std::fs;
use std::io::Write;
use std::path::Path;

use crate::GameError;

/// Writes `bytes` to `path` atomically and durably: to a new temporary file beside it
/// (an unpredictable name, opened with `create_new`, so no existing file or symlink is
/// followed), flushed and synced, renamed over the target, and the directory synced,
/// so that neither a crash nor a full disk ever leaves a truncated file in its place.
///
/// # Errors
/// [`GameError::Io`] if any step fails; the target is then untouched.
///
/// # Examples
/// ```
/// let path = std::env::temp_dir().join(format!("afg-doc-atomic-{}", std::process::id()));
/// afg_game::fs::write_atomic(&path, b"one")?;
/// afg_game::fs::write_atomic(&path, b"two")?;
/// assert_eq!(std::fs::read(&path)?, b"two");
/// # std::fs::remove_file(&path)?;
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), GameError> {
    write_atomic_with(path, |f| f.write_all(bytes))
}

/// [`write_atomic`], creating the file's folder (and its parents) first: for outputs
/// such as figures that a user names anywhere.
///
/// # Errors
/// [`GameError::Io`] if the folder cannot be made or the file written.
///
/// # Examples
/// ```
/// let path = std::env::temp_dir().join(format!("afg-doc-dirs-{}/a/figure.svg", std::process::id()));
/// afg_game::fs::write_atomic_making_dirs(&path, b"<svg/>")?;
/// assert_eq!(std::fs::read(&path)?, b"<svg/>");
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn write_atomic_making_dirs(path: &Path, bytes: &[u8]) -> Result<(), GameError> {
    if let Some(parent) = path.parent().filter(|p| !p.as_os_str().is_empty()) {
        fs::create_dir_all(parent).map_err(|source| GameError::Io {
            path: parent.display().to_string(),
            source,
        })?;
    }
    write_atomic(path, bytes)
}

/// [`write_atomic`] with the contents written by `write` into the temporary file (for
/// writers that stream, such as a model recorder).
///
/// # Errors
/// As [`write_atomic`], and `write`'s error.
pub fn write_atomic_with(
    path: &Path,
    write: impl FnOnce(&mut fs::File) -> std::io::Result<()>,
) -> Result<(), GameError> {
    use std::hash::{BuildHasher, Hasher};
    let io_err = |source| GameError::Io {
        path: path.display().to_string(),
        source,
    };
    let dir = path
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let name = path
        .file_name()
        .ok_or_else(|| io_err(std::io::Error::other("not a file path")))?;
    let (tmp, mut file) = loop {
        // A fresh random key per try (std's hasher seeds are random per process).
        let key = std::collections::hash_map::RandomState::new()
            .build_hasher()
            .finish();
        let tmp = dir.join(format!(".{}.{key:016x}.tmp", name.to_string_lossy()));
        match fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&tmp)
        {
            Ok(f) => break (tmp, f),
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => continue,
            Err(e) => return Err(io_err(e)),
        }
    };
    let result = (|| {
        write(&mut file)?;
        file.flush()?;
        file.sync_all()?;
        drop(file);
        fs::rename(&tmp, path)?;
        sync_dir(dir)
    })();
    if result.is_err() {
        let _ = fs::remove_file(&tmp);
    }
    result.map_err(io_err)
}

/// Syncs a directory, so that a rename in it survives a crash (a no-op where
/// directories cannot be opened, as on Windows).
pub fn sync_dir(dir: &Path) -> std::io::Result<()> {
    #[cfg(unix)]
    fs::File::open(dir)?.sync_all()?;
    #[cfg(not(unix))]
    let _ = dir;
    Ok(())
}

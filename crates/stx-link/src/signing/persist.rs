//! Signing state that must survive a restart, and signing as a process starts it.
//!
//! MAVLink 2 signing refuses a timestamp it has seen, so after a restart (even with the wall
//! clock set back) a sender must continue above every timestamp that ever left it. The
//! high-water mark is kept in a small file, written atomically before frames signed under it
//! are sent (the I/O adapter calls [`store_signing_timestamp`] when
//! [`SansIo::signing_timestamp_mark`] moves), and read back by [`start_signing`].

use std::io;
use std::path::{Path, PathBuf};
use std::time::Duration;

use crate::sansio::SansIo;
use crate::signing::{SigningConfig, SigningKey};

/// Where stx keeps state that must survive a restart (signing timestamps), looked up in the
/// environment `env` (e.g. `|k| std::env::var_os(k)`): `$STATE_DIRECTORY` (systemd's
/// `StateDirectory=`), else `$XDG_STATE_HOME/stx`, else `$HOME/.local/state/stx`; `None` when
/// none is set.
pub fn default_state_dir(env: impl Fn(&str) -> Option<std::ffi::OsString>) -> Option<PathBuf> {
    let set = |k: &str| env(k).filter(|v| !v.is_empty()).map(PathBuf::from);
    set("STATE_DIRECTORY")
        // systemd may list several directories, separated by ':'.
        .map(|p| {
            let text = p.to_string_lossy().into_owned();
            PathBuf::from(text.split(':').next().unwrap_or_default())
        })
        .or_else(|| set("XDG_STATE_HOME").map(|p| p.join("stx")))
        .or_else(|| set("HOME").map(|p| p.join(".local/state/stx")))
}

/// Writes `endpoint`'s signing timestamp high-water mark to `path` (when both signing and a
/// file are set): what an adapter does once before the I/O adapter, so that a file that cannot be
/// written stops the start instead of weakening the guarantee later.
pub fn persist_signing_mark<E: SansIo>(endpoint: &E, path: Option<&Path>) -> io::Result<()> {
    match (path, endpoint.signing_timestamp_mark()) {
        (Some(path), Some(mark)) => store_signing_timestamp(path, mark).map_err(|e| {
            io::Error::new(
                e.kind(),
                format!("signing timestamp file {}: {e}", path.display()),
            )
        }),
        _ => Ok(()),
    }
}

/// Reads a persisted signing timestamp; `Ok(None)` if the file does not exist.
pub fn load_signing_timestamp(path: &Path) -> io::Result<Option<u64>> {
    match std::fs::read_to_string(path) {
        Ok(s) => s
            .trim()
            .parse::<u64>()
            .map(Some)
            .map_err(|e| io::Error::new(io::ErrorKind::InvalidData, e)),
        Err(e) if e.kind() == io::ErrorKind::NotFound => Ok(None),
        Err(e) => Err(e),
    }
}

/// Writes a signing timestamp atomically (temporary file, fsync, rename), creating the
/// directory if needed.
pub fn store_signing_timestamp(path: &Path, value: u64) -> io::Result<()> {
    use std::io::Write;
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)?;
    }
    let tmp = path.with_extension("tmp");
    let mut f = std::fs::File::create(&tmp)?;
    writeln!(f, "{value}")?;
    f.sync_all()?;
    std::fs::rename(&tmp, path)
}

/// Signing as a station or a drone starts it: `key`, the wall clock `unix_now` (time since the
/// Unix epoch, read by the caller so tests can set it), and the high-water mark its last run
/// left in `timestamp_file`, if any (a missing file is a first run). The error names the file.
pub fn start_signing(
    key: SigningKey,
    unix_now: Duration,
    timestamp_file: Option<&Path>,
) -> io::Result<SigningConfig> {
    let persisted = match timestamp_file {
        Some(path) => load_signing_timestamp(path).map_err(|e| {
            io::Error::new(
                e.kind(),
                format!("signing timestamp file {}: {e}", path.display()),
            )
        })?,
        None => None,
    };
    Ok(SigningConfig::new(key, 0, unix_now).with_persisted_timestamp(persisted))
}

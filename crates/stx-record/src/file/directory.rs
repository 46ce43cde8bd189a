//! Recording files in a directory: where they go by default, what they are named (the run's
//! start and the file's number, so a directory sorts by time and a name says its run), and
//! how a file is created without ever overwriting another run's.

use std::fs::{File, OpenOptions};
use std::io::{self, Write};
use std::path::{Path, PathBuf};
use std::time::SystemTime;

use super::{Storage, StorageFile};

/// Name of the recordings directory inside the station's state directory.
pub const RECORDINGS_DIR_NAME: &str = "recordings";

/// Where recordings go by default: `recordings/` in the station's state directory (found
/// like the signing timestamp's: `stx_link::signing::persist::default_state_dir`).
pub fn recordings_dir(state_dir: &Path) -> PathBuf {
    state_dir.join(RECORDINGS_DIR_NAME)
}

/// Recording files in a directory (created when the first file is).
#[derive(Debug, Clone)]
pub struct Directory {
    dir: PathBuf,
    run_stamp: String,
}

impl Directory {
    /// Files in `dir` for a run started at `run_started` (wall clock, names the files).
    pub fn new(dir: impl Into<PathBuf>, run_started: SystemTime) -> Self {
        let t = time::OffsetDateTime::from(run_started);
        Self {
            dir: dir.into(),
            run_stamp: format!(
                "{:04}{:02}{:02}T{:02}{:02}{:02}Z",
                t.year(),
                u8::from(t.month()),
                t.day(),
                t.hour(),
                t.minute(),
                t.second()
            ),
        }
    }

    /// The name of file `part` (`stx-20261105T143012Z-001.mcap`).
    pub fn file_name(&self, part: u32) -> String {
        format!("stx-{}-{part:03}.mcap", self.run_stamp)
    }
}

/// When the run that wrote the file `name` started, as its name says (the names
/// [`Directory::file_name`] gives), Unix milliseconds; `None` for any other name. A file
/// just begun holds no message yet that could say so.
pub fn run_started_ms_from_name(name: &str) -> Option<u64> {
    let stamp = name.strip_prefix("stx-")?.get(..16)?;
    let digits = |range: std::ops::Range<usize>| stamp.get(range)?.parse::<u32>().ok();
    if stamp.as_bytes().get(8) != Some(&b'T') || stamp.as_bytes().get(15) != Some(&b'Z') {
        return None;
    }
    let month = time::Month::try_from(u8::try_from(digits(4..6)?).ok()?).ok()?;
    let date = time::Date::from_calendar_date(
        i32::try_from(digits(0..4)?).ok()?,
        month,
        u8::try_from(digits(6..8)?).ok()?,
    )
    .ok()?;
    let at = date
        .with_hms(
            u8::try_from(digits(9..11)?).ok()?,
            u8::try_from(digits(11..13)?).ok()?,
            u8::try_from(digits(13..15)?).ok()?,
        )
        .ok()?
        .assume_utc();
    u64::try_from(at.unix_timestamp()).ok().map(|s| s * 1000)
}

impl StorageFile for File {
    fn write_all(&mut self, data: &[u8]) -> io::Result<()> {
        Write::write_all(self, data)
    }

    fn truncate(&mut self, len: u64) -> io::Result<()> {
        self.set_len(len)
    }

    fn sync(&mut self) -> io::Result<()> {
        self.sync_data()
    }
}

impl Storage for Directory {
    fn create(&mut self, part: u32) -> io::Result<(PathBuf, Box<dyn StorageFile>)> {
        std::fs::create_dir_all(&self.dir)?;
        let base = self.file_name(part);
        // Two runs started within the same second: never overwrite, add a counter.
        for attempt in 0..100 {
            let name = if attempt == 0 {
                base.clone()
            } else {
                base.replace(".mcap", &format!("-{attempt}.mcap"))
            };
            let path = self.dir.join(name);
            match OpenOptions::new().write(true).create_new(true).open(&path) {
                Ok(file) => return Ok((path, Box::new(file))),
                Err(e) if e.kind() == io::ErrorKind::AlreadyExists => continue,
                Err(e) => return Err(e),
            }
        }
        Err(io::Error::new(
            io::ErrorKind::AlreadyExists,
            format!("{base}: 100 files of that name exist"),
        ))
    }

    fn remove(&mut self, path: &Path) -> io::Result<()> {
        std::fs::remove_file(path)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Duration;

    #[test]
    fn a_file_name_says_when_its_run_started() {
        let started = SystemTime::UNIX_EPOCH + Duration::from_secs(1_795_000_212);
        let name = Directory::new("/tmp", started).file_name(2);
        assert_eq!(run_started_ms_from_name(&name), Some(1_795_000_212_000));
        let counted = name.replace(".mcap", "-1.mcap");
        assert_eq!(run_started_ms_from_name(&counted), Some(1_795_000_212_000));
        for other in [
            "flight.mcap",
            "stx-2026.mcap",
            "stx-20261399T000000Z-001.mcap",
        ] {
            assert_eq!(run_started_ms_from_name(other), None, "{other}");
        }
    }
}

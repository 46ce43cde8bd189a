//! The SondeHub queue's files: `journal.jsonl` (one point a line, appended) and `mark` (the
//! highest sequence number that needs no sending), as [`crate::sondehub::queue`] decides.
//! Rewrites go through a temporary file and a rename, so a crash leaves the old file or the
//! new one; an append cut by a crash is a line the queue skips when it reads the journal back.
//! No `fsync`: the queue survives the station's restart or crash; a power cut may lose the
//! last seconds the system had not written.

use std::path::{Path, PathBuf};

use tokio::io::AsyncWriteExt;

use crate::sondehub::Persist;

const JOURNAL: &str = "journal.jsonl";
const MARK: &str = "mark";

/// The queue's directory.
pub(super) struct Store {
    dir: PathBuf,
}

/// What the directory held at start: the journal's text and the mark.
pub(super) struct Found {
    pub(super) journal: String,
    pub(super) mark: u64,
}

impl Store {
    /// Opens (creating) `dir` and reads what it holds.
    pub(super) async fn open(dir: &Path) -> std::io::Result<(Self, Found)> {
        tokio::fs::create_dir_all(dir).await?;
        let journal = match tokio::fs::read(dir.join(JOURNAL)).await {
            Ok(bytes) => String::from_utf8_lossy(&bytes).into_owned(),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => String::new(),
            Err(e) => return Err(e),
        };
        if !journal.is_empty() && !journal.ends_with('\n') {
            // A line cut by a crash: ended here, so the next point starts a line of its own.
            let mut file = tokio::fs::OpenOptions::new()
                .append(true)
                .open(dir.join(JOURNAL))
                .await?;
            file.write_all(b"\n").await?;
        }
        let mark = match tokio::fs::read_to_string(dir.join(MARK)).await {
            Ok(text) => text.trim().parse().unwrap_or(0),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => 0,
            Err(e) => return Err(e),
        };
        Ok((
            Self {
                dir: dir.to_path_buf(),
            },
            Found { journal, mark },
        ))
    }

    /// Does what `persist` says: append, move the mark, rewrite the journal.
    pub(super) async fn apply(&self, persist: Persist) -> std::io::Result<()> {
        if !persist.append.is_empty() {
            let mut text = persist.append.join("\n");
            text.push('\n');
            let mut file = tokio::fs::OpenOptions::new()
                .create(true)
                .append(true)
                .open(self.dir.join(JOURNAL))
                .await?;
            file.write_all(text.as_bytes()).await?;
            file.flush().await?;
        }
        if let Some(mark) = persist.mark {
            self.replace(MARK, format!("{mark}\n")).await?;
        }
        if let Some(lines) = persist.rewrite {
            let mut text = lines.join("\n");
            if !text.is_empty() {
                text.push('\n');
            }
            self.replace(JOURNAL, text).await?;
        }
        Ok(())
    }

    async fn replace(&self, name: &str, text: String) -> std::io::Result<()> {
        let tmp = self.dir.join(format!("{name}.tmp"));
        tokio::fs::write(&tmp, text).await?;
        tokio::fs::rename(&tmp, self.dir.join(name)).await
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sondehub::{Queue, Sample};

    #[tokio::test]
    async fn a_line_cut_by_a_crash_is_skipped_and_what_follows_is_read_back() {
        let dir = std::env::temp_dir().join(format!("stx-sondehub-store-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let (store, found) = Store::open(&dir).await.expect("opens");
        assert!(found.journal.is_empty() && found.mark == 0);
        let mut q = Queue::new(10);
        for i in 0..3 {
            store.apply(q.push(Sample::bare(i))).await.expect("appends");
        }
        store.apply(q.done_through(1)).await.expect("marks");
        // The station died in the middle of the next append.
        std::fs::OpenOptions::new()
            .append(true)
            .open(dir.join(JOURNAL))
            .and_then(|mut f| std::io::Write::write_all(&mut f, b"{\"seq\":4,\"fi"))
            .expect("a cut line");
        let (store, found) = Store::open(&dir).await.expect("reopens");
        let (mut q, restored) = Queue::restore(10, found.journal.lines(), found.mark);
        assert_eq!((restored.points, restored.unreadable), (2, 1));
        store
            .apply(q.push(Sample::bare(9)))
            .await
            .expect("appends after the cut");
        let (_, found) = Store::open(&dir).await.expect("opens again");
        let (q, restored) = Queue::restore(10, found.journal.lines(), found.mark);
        assert_eq!((restored.points, restored.unreadable), (3, 1));
        let fixes: Vec<u64> = q.head(5).map(|x| x.sample.fix_ms).collect();
        assert_eq!(fixes, vec![1, 2, 9]);
        let _ = std::fs::remove_dir_all(&dir);
    }
}

//! The points waiting for the server, bounded, and what of them must be on disk so that a
//! station restarted without internet loses nothing.
//!
//! On disk (written by the daemon's store) is a journal, one JSON line per point with its
//! sequence number, and a mark: the highest sequence number that needs no sending any more
//! (sent, refused by the server, or dropped as the oldest when the queue was full). A point
//! is appended when it is made; the mark moves when the server answers; the journal is
//! rewritten with only the points still waiting when most of its lines are past the mark.
//! Reading both back gives the queue as it was. Everything here decides; nothing reads or
//! writes.

use std::collections::VecDeque;

use serde::{Deserialize, Serialize};

use super::point::Sample;

/// One journal line: a point and its place in the queue.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Queued {
    /// Its sequence number (increasing, never reused, across restarts).
    pub seq: u64,
    /// The point.
    #[serde(flatten)]
    pub sample: Sample,
}

/// What the store must do after a change.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Persist {
    /// Lines to append to the journal.
    pub append: Vec<String>,
    /// The new mark, if it moved.
    pub mark: Option<u64>,
    /// Replace the journal by these lines (a compaction), after appending nothing.
    pub rewrite: Option<Vec<String>>,
}

/// What was read back at start.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Restored {
    /// Points still waiting.
    pub points: usize,
    /// Lines that could not be read (a line cut by a crash), skipped.
    pub unreadable: usize,
    /// Waiting points dropped because there were more than the queue holds.
    pub dropped: usize,
}

/// The bounded queue of points waiting for the server.
#[derive(Debug)]
pub struct Queue {
    waiting: VecDeque<Queued>,
    max: usize,
    next_seq: u64,
    mark: u64,
    /// Lines the journal holds, waiting or not.
    journal_lines: usize,
    dropped: u64,
}

/// The journal is rewritten once this many of its lines (at least) are past the mark.
const COMPACT_AFTER: usize = 64;

impl Queue {
    /// An empty queue holding at most `max` points.
    pub fn new(max: usize) -> Self {
        Self {
            waiting: VecDeque::new(),
            max: max.max(1),
            next_seq: 1,
            mark: 0,
            journal_lines: 0,
            dropped: 0,
        }
    }

    /// The queue the journal's `lines` and the `mark` describe (the newest `max` points past
    /// the mark, in order).
    pub fn restore<'a>(
        max: usize,
        lines: impl IntoIterator<Item = &'a str>,
        mark: u64,
    ) -> (Self, Restored) {
        let mut queue = Self::new(max);
        queue.mark = mark;
        let mut restored = Restored::default();
        let mut highest = mark;
        for line in lines {
            if line.trim().is_empty() {
                continue;
            }
            queue.journal_lines += 1;
            let Ok(q) = serde_json::from_str::<Queued>(line) else {
                restored.unreadable += 1;
                continue;
            };
            highest = highest.max(q.seq);
            if q.seq > mark {
                queue.waiting.push_back(q);
            }
        }
        let mut found: Vec<Queued> = queue.waiting.drain(..).collect();
        found.sort_by_key(|q| q.seq);
        found.dedup_by_key(|q| q.seq);
        queue.waiting = found.into();
        while queue.waiting.len() > queue.max {
            queue.waiting.pop_front();
            restored.dropped += 1;
        }
        if let Some(first) = queue.waiting.front() {
            queue.mark = queue.mark.max(first.seq - 1);
        }
        queue.next_seq = highest + 1;
        queue.dropped = restored.dropped as u64;
        restored.points = queue.waiting.len();
        (queue, restored)
    }

    /// Queues `sample`; when full, the oldest point goes (counted in [`Queue::dropped`]).
    pub fn push(&mut self, sample: Sample) -> Persist {
        let queued = Queued {
            seq: self.next_seq,
            sample,
        };
        self.next_seq += 1;
        let mut persist = Persist::default();
        if let Ok(line) = serde_json::to_string(&queued) {
            persist.append.push(line);
            self.journal_lines += 1;
        }
        self.waiting.push_back(queued);
        while self.waiting.len() > self.max {
            if let Some(oldest) = self.waiting.pop_front() {
                self.dropped += 1;
                self.mark = oldest.seq;
                persist.mark = Some(oldest.seq);
            }
        }
        persist.rewrite = self.compaction();
        persist
    }

    /// The oldest `n` points waiting, in order.
    pub fn head(&self, n: usize) -> impl Iterator<Item = &Queued> {
        self.waiting.iter().take(n)
    }

    /// The points through `seq` need no sending any more (the server answered for them).
    pub fn done_through(&mut self, seq: u64) -> Persist {
        let mut persist = Persist::default();
        if seq <= self.mark {
            return persist;
        }
        while self.waiting.front().is_some_and(|q| q.seq <= seq) {
            self.waiting.pop_front();
        }
        self.mark = seq;
        persist.mark = Some(seq);
        persist.rewrite = self.compaction();
        persist
    }

    /// The journal's lines if it is time to rewrite it: when nothing waits (an empty file) or
    /// when more of its lines are past the mark than wait and at least [`COMPACT_AFTER`].
    fn compaction(&mut self) -> Option<Vec<String>> {
        let dead = self.journal_lines.saturating_sub(self.waiting.len());
        let due = (self.waiting.is_empty() && self.journal_lines > 0)
            || (dead >= COMPACT_AFTER && dead > self.waiting.len());
        if !due {
            return None;
        }
        let lines: Vec<String> = self
            .waiting
            .iter()
            .filter_map(|q| serde_json::to_string(q).ok())
            .collect();
        self.journal_lines = lines.len();
        Some(lines)
    }

    /// Points waiting.
    pub fn len(&self) -> usize {
        self.waiting.len()
    }

    /// Nothing waits.
    pub fn is_empty(&self) -> bool {
        self.waiting.is_empty()
    }

    /// Points dropped as the oldest of a full queue since the start.
    pub fn dropped(&self) -> u64 {
        self.dropped
    }

    /// Lines the journal holds now (for tests of the store).
    pub fn journal_lines(&self) -> usize {
        self.journal_lines
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample(fix_ms: u64) -> Sample {
        Sample::bare(fix_ms)
    }

    /// A journal as the store keeps it: what `persist` says, applied to `file` and `mark`.
    fn apply(file: &mut Vec<String>, mark: &mut u64, persist: Persist) {
        file.extend(persist.append);
        if let Some(m) = persist.mark {
            *mark = m;
        }
        if let Some(lines) = persist.rewrite {
            *file = lines;
        }
    }

    #[test]
    fn a_restart_finds_what_waited_and_nothing_sent() {
        let (mut file, mut mark) = (Vec::new(), 0);
        let mut q = Queue::new(100);
        for i in 0..5 {
            let p = q.push(sample(i));
            apply(&mut file, &mut mark, p);
        }
        let p = q.done_through(2);
        apply(&mut file, &mut mark, p);
        // A crash cut the last line in half.
        file.push("{\"seq\":6,\"fix".into());
        let (back, restored) = Queue::restore(100, file.iter().map(String::as_str), mark);
        assert_eq!(
            restored,
            Restored {
                points: 3,
                unreadable: 1,
                dropped: 0
            }
        );
        let fixes: Vec<u64> = back.head(10).map(|q| q.sample.fix_ms).collect();
        assert_eq!(fixes, vec![2, 3, 4]);
        // Numbers go on after the highest seen, never reused.
        let mut back = back;
        let p = back.push(sample(9));
        assert!(p.append[0].starts_with("{\"seq\":6,"), "{:?}", p.append);
    }

    #[test]
    fn a_full_queue_drops_its_oldest_and_says_so_on_disk() {
        let (mut file, mut mark) = (Vec::new(), 0);
        let mut q = Queue::new(3);
        for i in 0..5 {
            let p = q.push(sample(i));
            apply(&mut file, &mut mark, p);
        }
        assert_eq!((q.len(), q.dropped(), mark), (3, 2, 2));
        let (back, restored) = Queue::restore(3, file.iter().map(String::as_str), mark);
        assert_eq!((restored.points, restored.dropped), (3, 0));
        assert_eq!(back.head(1).next().map(|q| q.sample.fix_ms), Some(2));
        // Restored into a smaller queue: the newest stay.
        let (small, restored) = Queue::restore(2, file.iter().map(String::as_str), mark);
        assert_eq!((restored.dropped, small.dropped()), (1, 1));
        assert_eq!(small.head(1).next().map(|q| q.sample.fix_ms), Some(3));
    }

    #[test]
    fn the_journal_stays_small_while_the_server_keeps_up_and_while_it_is_away() {
        let (mut file, mut mark) = (Vec::new(), 0);
        let mut q = Queue::new(100);
        for i in 0..1000 {
            let p = q.push(sample(i));
            apply(&mut file, &mut mark, p);
            let seq = q.head(1).next().map(|x| x.seq).unwrap_or(0);
            let p = q.done_through(seq);
            apply(&mut file, &mut mark, p);
            assert!(file.is_empty(), "sent at once: nothing on disk");
        }
        // Away: the queue fills and drops; the journal never holds much more than the queue.
        for i in 0..10_000 {
            let p = q.push(sample(i));
            apply(&mut file, &mut mark, p);
            assert!(file.len() <= 2 * 100 + COMPACT_AFTER, "{}", file.len());
            assert_eq!(q.journal_lines(), file.len());
        }
        let (back, _) = Queue::restore(100, file.iter().map(String::as_str), mark);
        let fixes: Vec<u64> = back.head(1000).map(|q| q.sample.fix_ms).collect();
        assert_eq!(fixes, (9900..10_000).collect::<Vec<_>>());
    }

    #[test]
    fn an_old_answer_moves_nothing() {
        let mut q = Queue::new(10);
        for i in 0..3 {
            q.push(sample(i));
        }
        q.done_through(2);
        assert_eq!(q.done_through(1), Persist::default());
        assert_eq!(q.len(), 1);
    }
}

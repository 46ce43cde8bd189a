//! Reporting I/O failures without flooding: every failure is counted in
//! [`IoStats`](stx_link::sansio::IoStats), but a
//! link without a peer fails every frame, so each kind is reported (a `tracing` warning and an
//! [`IoEvent`]) the first time at once, then at most once per [`IO_ERROR_REPORT_INTERVAL`]
//! with the count since the last report.

use std::io;

use stx_link::sansio::IoEvent;
use tokio::time::Instant;

use super::{IO_ERROR_REPORT_INTERVAL, Transport};

/// Rate limit of the reports of one kind of I/O failure (every failure is counted
/// elsewhere): the first at once, then at most one per [`IO_ERROR_REPORT_INTERVAL`] carrying
/// how many failed since the previous report.
#[derive(Debug, Default)]
pub(super) struct ErrorReports {
    last_report: Option<Instant>,
    unreported: u64,
    pub(super) last_error: String,
}

/// Which way an I/O operation went.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Dir {
    Recv,
    Send,
}

impl ErrorReports {
    /// A failure at `now`: `Some(failures since the last report)` when it is to be reported.
    pub(super) fn failed(&mut self, now: Instant) -> Option<u64> {
        self.unreported += 1;
        self.due(now)
    }

    /// A success at `now`: reports the failures not yet reported, once the interval allows.
    pub(super) fn succeeded(&mut self, now: Instant) -> Option<u64> {
        if self.unreported == 0 {
            return None;
        }
        self.due(now)
    }

    fn due(&mut self, now: Instant) -> Option<u64> {
        let due = self
            .last_report
            .is_none_or(|t| now.duration_since(t) >= IO_ERROR_REPORT_INTERVAL);
        due.then(|| {
            self.last_report = Some(now);
            std::mem::take(&mut self.unreported)
        })
    }
}

impl Transport {
    pub(super) fn recv_error(&mut self, e: &io::Error) {
        self.stats.recv_errors += 1;
        self.failed(Dir::Recv, e);
    }

    pub(super) fn send_error(&mut self, e: &io::Error) {
        self.stats.send_errors += 1;
        self.failed(Dir::Send, e);
    }

    fn reports(&mut self, dir: Dir) -> &mut ErrorReports {
        match dir {
            Dir::Recv => &mut self.recv_reports,
            Dir::Send => &mut self.send_reports,
        }
    }

    fn failed(&mut self, dir: Dir, e: &io::Error) {
        let reports = self.reports(dir);
        reports.last_error = e.to_string();
        if let Some(n) = reports.failed(Instant::now()) {
            self.report(dir, n);
        }
    }

    pub(super) fn succeeded(&mut self, dir: Dir) {
        if let Some(n) = self.reports(dir).succeeded(Instant::now()) {
            self.report(dir, n);
        }
    }

    /// One report of `since_last` failures of `dir` (log line and event).
    fn report(&mut self, dir: Dir, since_last: u64) {
        let error = self.reports(dir).last_error.clone();
        let (what, total) = match dir {
            Dir::Recv => ("receive", self.stats.recv_errors),
            Dir::Send => ("send", self.stats.send_errors),
        };
        tracing::warn!(
            address = %self.address,
            %error,
            since_last_report = since_last,
            total,
            "{what} failed (reported at most every {} s)",
            IO_ERROR_REPORT_INTERVAL.as_secs()
        );
        self.events.push_back(match dir {
            Dir::Recv => IoEvent::RecvError {
                error,
                count: total,
            },
            Dir::Send => IoEvent::SendError {
                error,
                count: total,
            },
        });
    }
}

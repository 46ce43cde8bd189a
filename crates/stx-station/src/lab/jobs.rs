//! The Lab's job runner, without threads or clocks: one job at a time, its progress, an
//! operator's cancel, a time cap, and the last outcome kept for every page (viewers included)
//! until the next job ends. The adapter runs the work on its own thread and reports here;
//! times are the caller's (the mission clock), so the rules are tested with plain numbers.

use schemars::JsonSchema;
use serde::Serialize;

use super::LabResult;

/// A job is already running: the Lab runs one at a time.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("the Lab is running job {id} ({kind}); cancel it or wait")]
pub struct LabBusy {
    /// The running job.
    pub id: u64,
    /// Its kind.
    pub kind: &'static str,
}

/// Why a job should stop before its end.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StopReason {
    /// An operator cancelled it.
    Cancelled,
    /// It ran past the Lab's time cap.
    TimedOut,
}

#[derive(Debug, Clone)]
struct Job {
    id: u64,
    kind: &'static str,
    by: String,
    started_s: f64,
    done: u64,
    total: u64,
    cancelled: bool,
}

/// The running job, as `GET /api/lab` shows it.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct LabJobView {
    /// Job number (1, 2, … since the station started).
    pub id: u64,
    /// `scenario`, `monte_carlo`, `stability`, `tune`, `compare` or `identify`.
    pub kind: String,
    /// Who started it (token name).
    pub started_by: String,
    /// Time since it started, s.
    pub elapsed_s: f64,
    /// Steps done (runs of a batch, iterations of a tuning).
    pub done: u64,
    /// Steps in all (0 when the job cannot tell).
    pub total: u64,
    /// A cancel was asked; the job stops at its next step.
    pub cancelling: bool,
}

/// How the last job ended, with its result.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct LabOutcomeView {
    /// Job number.
    pub id: u64,
    /// Its kind.
    pub kind: String,
    /// Who started it.
    pub started_by: String,
    /// `done`, `cancelled` (a batch keeps the runs it flew), `timed_out` or `failed`.
    pub outcome: String,
    /// Why it failed or stopped.
    pub reason: Option<String>,
    /// How long it ran, s.
    pub elapsed_s: f64,
    /// The result (partial when cancelled or timed out; none when failed).
    pub result: Option<LabResult>,
}

/// `GET /api/lab`: the Lab's state for every page.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct LabStatusBody {
    /// The station runs Lab jobs (only `stx serve` does; a replay does not).
    pub available: bool,
    /// A job's longest run, s.
    pub time_cap_s: f64,
    /// The running job.
    pub job: Option<LabJobView>,
    /// The last job's outcome.
    pub last: Option<LabOutcomeView>,
    /// The station flies a simulated drone that `POST /api/lab/rehearse` restarts with a
    /// vehicle (`stx serve --sim`).
    pub rehearse: bool,
    /// The rehearsal the Lab last started, if any.
    pub rehearsal: Option<super::bodies::LabRehearsalBody>,
}

/// The runner's state.
#[derive(Debug, Clone)]
pub struct LabJobs {
    time_cap_s: f64,
    next_id: u64,
    running: Option<Job>,
    last: Option<LabOutcomeView>,
}

impl LabJobs {
    /// No job yet; each job may run `time_cap_s` seconds.
    pub fn new(time_cap_s: f64) -> Self {
        Self {
            time_cap_s,
            next_id: 1,
            running: None,
            last: None,
        }
    }

    /// Starts a job of `kind` for `by` at `now_s`, or says which job runs.
    pub fn start(&mut self, kind: &'static str, by: &str, now_s: f64) -> Result<u64, LabBusy> {
        if let Some(j) = &self.running {
            return Err(LabBusy {
                id: j.id,
                kind: j.kind,
            });
        }
        let id = self.next_id;
        self.next_id += 1;
        self.running = Some(Job {
            id,
            kind,
            by: by.to_string(),
            started_s: now_s,
            done: 0,
            total: 0,
            cancelled: false,
        });
        Ok(id)
    }

    fn job_mut(&mut self, id: u64) -> Option<&mut Job> {
        self.running.as_mut().filter(|j| j.id == id)
    }

    /// Job `id` has done `done` of `total` steps (a stale job's report is ignored).
    pub fn progress(&mut self, id: u64, done: usize, total: usize) {
        if let Some(j) = self.job_mut(id) {
            j.done = done as u64;
            j.total = total as u64;
        }
    }

    /// Asks the running job to stop; false when none runs.
    pub fn cancel(&mut self) -> bool {
        match self.running.as_mut() {
            Some(j) => {
                j.cancelled = true;
                true
            }
            None => false,
        }
    }

    /// Whether job `id` should stop at `now_s`, and why (a job no longer running stops).
    pub fn stop_reason(&self, id: u64, now_s: f64) -> Option<StopReason> {
        match self.running.as_ref().filter(|j| j.id == id) {
            None => Some(StopReason::Cancelled),
            Some(j) if j.cancelled => Some(StopReason::Cancelled),
            Some(j) if now_s - j.started_s > self.time_cap_s => Some(StopReason::TimedOut),
            Some(_) => None,
        }
    }

    /// Job `id` ended at `now_s` with `result`; the outcome replaces the last one. A job
    /// cancelled or past its cap keeps what it returned, marked so.
    pub fn finish(&mut self, id: u64, result: Result<LabResult, String>, now_s: f64) {
        let Some(job) = self.running.take_if(|j| j.id == id) else {
            return;
        };
        let elapsed_s = now_s - job.started_s;
        let stopped = if job.cancelled {
            Some(("cancelled", "cancelled by an operator".to_string()))
        } else if elapsed_s > self.time_cap_s {
            Some((
                "timed_out",
                format!("stopped at the Lab's time cap of {} s", self.time_cap_s),
            ))
        } else {
            None
        };
        let (outcome, reason, result) = match (result, stopped) {
            (Err(e), Some((o, r))) => (o, Some(format!("{r}: {e}")), None),
            (Err(e), None) => ("failed", Some(e), None),
            (Ok(r), Some((o, why))) => (o, Some(why), Some(r)),
            (Ok(r), None) => ("done", None, Some(r)),
        };
        self.last = Some(LabOutcomeView {
            id,
            kind: job.kind.to_string(),
            started_by: job.by,
            outcome: outcome.to_string(),
            reason,
            elapsed_s,
            result,
        });
    }

    /// The state for `GET /api/lab` at `now_s`.
    pub fn status(&self, now_s: f64) -> LabStatusBody {
        LabStatusBody {
            available: true,
            time_cap_s: self.time_cap_s,
            job: self.running.as_ref().map(|j| LabJobView {
                id: j.id,
                kind: j.kind.to_string(),
                started_by: j.by.clone(),
                elapsed_s: now_s - j.started_s,
                done: j.done,
                total: j.total,
                cancelling: j.cancelled,
            }),
            last: self.last.clone(),
            rehearse: false,
            rehearsal: None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lab::{MonteCarloSummary, ScenarioSeries};

    fn batch(flown: u64) -> Result<LabResult, String> {
        Ok(LabResult::MonteCarlo(MonteCarloSummary {
            runs_asked: 10,
            runs_flown: flown,
            ..Default::default()
        }))
    }

    #[test]
    fn one_job_at_a_time_and_the_next_after_it_ends() {
        let mut lab = LabJobs::new(60.0);
        let a = lab.start("scenario", "op", 0.0).expect("idle");
        assert_eq!(
            lab.start("monte_carlo", "op", 1.0),
            Err(LabBusy {
                id: a,
                kind: "scenario"
            })
        );
        lab.finish(a, Ok(LabResult::Scenario(ScenarioSeries::default())), 2.0);
        let s = lab.status(3.0);
        assert!(s.job.is_none());
        let last = s.last.expect("kept");
        assert_eq!((last.id, last.outcome.as_str()), (a, "done"));
        assert_eq!(last.elapsed_s, 2.0);
        let b = lab.start("monte_carlo", "op", 3.0).expect("idle again");
        assert_eq!(b, a + 1);
    }

    #[test]
    fn progress_shows_and_a_stale_job_cannot_report() {
        let mut lab = LabJobs::new(60.0);
        let a = lab.start("monte_carlo", "op", 0.0).expect("idle");
        lab.progress(a, 3, 10);
        lab.progress(a + 7, 9, 10);
        let j = lab.status(5.0).job.expect("running");
        assert_eq!((j.done, j.total, j.elapsed_s), (3, 10, 5.0));
        lab.finish(a + 7, batch(10), 6.0);
        assert!(lab.status(6.0).job.is_some(), "a stale finish ends nothing");
    }

    #[test]
    fn a_cancel_stops_the_job_and_keeps_its_partial_result() {
        let mut lab = LabJobs::new(60.0);
        assert!(!lab.cancel(), "nothing to cancel");
        let a = lab.start("monte_carlo", "op", 0.0).expect("idle");
        assert_eq!(lab.stop_reason(a, 1.0), None);
        assert!(lab.cancel());
        assert!(lab.status(1.0).job.expect("running").cancelling);
        assert_eq!(lab.stop_reason(a, 1.0), Some(StopReason::Cancelled));
        lab.finish(a, batch(4), 2.0);
        let last = lab.status(2.0).last.expect("kept");
        assert_eq!(last.outcome, "cancelled");
        match last.result {
            Some(LabResult::MonteCarlo(m)) => assert_eq!(m.runs_flown, 4),
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn the_time_cap_stops_a_job_and_names_the_cap() {
        let mut lab = LabJobs::new(30.0);
        let a = lab.start("tune", "op", 100.0).expect("idle");
        assert_eq!(lab.stop_reason(a, 130.0), None);
        assert_eq!(lab.stop_reason(a, 130.5), Some(StopReason::TimedOut));
        lab.finish(a, Err("stopped".into()), 131.0);
        let last = lab.status(131.0).last.expect("kept");
        assert_eq!(last.outcome, "timed_out");
        assert!(last.reason.expect("why").contains("30 s"));
        assert!(last.result.is_none());
    }

    #[test]
    fn a_failure_keeps_its_reason() {
        let mut lab = LabJobs::new(30.0);
        let a = lab.start("stability", "op", 0.0).expect("idle");
        lab.finish(a, Err("no trim at 90000 m".into()), 1.0);
        let last = lab.status(1.0).last.expect("kept");
        assert_eq!(last.outcome, "failed");
        assert_eq!(last.reason.as_deref(), Some("no trim at 90000 m"));
    }
}

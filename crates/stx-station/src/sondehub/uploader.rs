//! What to send SondeHub and when: batches of the queue every period (at once while a
//! backlog drains), the station's position at start and every 6 h, a chase car's at most
//! every 10 s; one request at a time; tries that fail (no answer, 5xx, any status but 2xx and
//! 400) wait 5 s, then twice as long each time up to `retry_max_s`, and are tried again with
//! the same points. A 202's errors and warnings are kept and logged; points it refused, or a
//! batch a 400 refused, are not sent again (the same bytes would be refused again).
//!
//! Pure: the daemon (`daemon::sondehub`) gives it points, the clock (`now`, the station's
//! monotonic seconds, for waits; `wall_ms` for the points' ages) and the server's answers,
//! and sends what [`Uploader::poll`] returns.

use serde::Deserialize;

use super::point::{ListenerBody, Sample, TelemetryPoint};
use super::queue::{Persist, Queue, Restored};
use super::settings::SondehubConfig;
use super::view::{ChaseCarView, SondehubNote, SondehubView};

/// Points in one upload at most (a backlog goes in several, one after the other).
pub const BATCH_MAX: usize = 200;
/// How often the station's position is sent again (SondeHub shows a station for ~12 h).
pub const STATION_EVERY_S: f64 = 6.0 * 3600.0;
/// The least time between two chase car uploads.
pub const CHASE_EVERY_S: f64 = 10.0;
/// The first wait after a failed try (or `retry_max_s`, if shorter).
pub const RETRY_FIRST_S: f64 = 5.0;
/// Errors and warnings kept for the pages.
const NOTES_KEPT: usize = 10;
/// A 202's errors logged one by one at most; the rest are counted.
const LOGGED_PER_ANSWER: usize = 5;

/// A request for the daemon to send.
#[derive(Debug, Clone, PartialEq)]
pub enum Request {
    /// `PUT /amateur/telemetry` with this JSON array (the daemon gzips it).
    Telemetry {
        /// The body, uncompressed.
        json: Vec<u8>,
        /// Points in it.
        points: usize,
    },
    /// `PUT /amateur/listeners` with this JSON object.
    Listener {
        /// The body.
        json: Vec<u8>,
        /// A chase car (else the station).
        mobile: bool,
    },
}

impl Request {
    /// The path under the API's address.
    pub fn path(&self) -> &'static str {
        match self {
            Request::Telemetry { .. } => "/amateur/telemetry",
            Request::Listener { .. } => "/amateur/listeners",
        }
    }
}

/// How a request ended.
#[derive(Debug, Clone, PartialEq)]
pub enum Answer {
    /// The server answered.
    Status {
        /// HTTP status.
        code: u16,
        /// The answer's body (a 202's JSON).
        body: String,
    },
    /// No answer: refused, unreachable, timed out.
    Failed(String),
}

/// How loud a log line is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Level {
    /// Normal operation.
    Info,
    /// Something lost or failing.
    Warn,
}

/// What the daemon must do after an answer: store and log.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Outcome {
    /// For the queue's store.
    pub persist: Persist,
    /// Lines for the log.
    pub log: Vec<(Level, String)>,
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum InFlight {
    Telemetry {
        through: u64,
        points: usize,
        historical: u64,
    },
    Station,
    Chase,
}

#[derive(Debug, Clone, PartialEq)]
struct ChaseCar {
    position: [f64; 3],
    pending: bool,
    last_try_s: Option<f64>,
    uploaded_wall_ms: Option<u64>,
}

#[derive(Debug, Deserialize)]
struct Accepted {
    #[serde(default)]
    errors: Vec<Problem>,
    #[serde(default)]
    warnings: Vec<Problem>,
}

#[derive(Debug, Deserialize)]
struct Problem {
    #[serde(default, alias = "warning_message")]
    error_message: Option<String>,
    #[serde(default)]
    payload: Option<serde_json::Value>,
}

impl Problem {
    fn text(&self) -> String {
        let what = self.error_message.as_deref().unwrap_or("(no message)");
        let at = self
            .payload
            .as_ref()
            .and_then(|p| p.get("datetime"))
            .and_then(|d| d.as_str());
        match at {
            Some(at) => format!("{what} (point of {at})"),
            None => what.to_string(),
        }
    }
}

/// The upload's state.
#[derive(Debug)]
pub struct Uploader {
    config: SondehubConfig,
    queue: Queue,
    in_flight: Option<InFlight>,
    failures: u32,
    retry_at: Option<f64>,
    telemetry_at: f64,
    station_at: Option<f64>,
    chase: Option<ChaseCar>,
    /// Warnings in the last 202.
    last_warnings: usize,
    view: SondehubView,
}

impl Uploader {
    /// The upload of `config` with `queue` (as restored, `restored`; `on_disk`: it has a
    /// store), starting at `now`.
    pub fn new(
        config: SondehubConfig,
        queue: Queue,
        restored: Restored,
        on_disk: bool,
        now: f64,
    ) -> Self {
        let view = SondehubView {
            url: config.base_url().to_string(),
            uploader_callsign: config.uploader_callsign.clone(),
            payload_callsign: config.payload_callsign.clone(),
            period_s: config.period_s,
            made: 0,
            sent: 0,
            historical: 0,
            refused: 0,
            queued: queue.len() as u64,
            queue_max: config.queue_max_points as u64,
            dropped: queue.dropped(),
            restored: restored.points as u64,
            on_disk,
            last_upload_wall_ms: None,
            last_result: None,
            failing: false,
            retry_wall_ms: None,
            errors: Vec::new(),
            warnings: Vec::new(),
            station_uploaded_wall_ms: None,
            chase_car: None,
        };
        Self {
            station_at: config.station_position.map(|_| now),
            config,
            queue,
            in_flight: None,
            failures: 0,
            retry_at: None,
            telemetry_at: now,
            chase: None,
            last_warnings: 0,
            view,
        }
    }

    /// Queues a new point.
    pub fn add(&mut self, sample: Sample) -> Persist {
        self.view.made += 1;
        self.queue.push(sample)
    }

    /// A recovery phone is at `position` (`[lat, lon, alt]`): the chase car's next upload.
    pub fn chase_car(&mut self, position: [f64; 3]) {
        let car = self.chase.get_or_insert(ChaseCar {
            position,
            pending: true,
            last_try_s: None,
            uploaded_wall_ms: None,
        });
        car.position = position;
        car.pending = true;
    }

    /// What to send now, if anything (nothing while a request is out).
    pub fn poll(&mut self, now: f64, wall_ms: u64) -> Option<Request> {
        if self.in_flight.is_some() || self.retry_at.is_some_and(|t| now < t) {
            return None;
        }
        if self.station_at.is_some_and(|t| now >= t)
            && let Some(body) = ListenerBody::station(&self.config)
        {
            self.in_flight = Some(InFlight::Station);
            return Some(listener(&body));
        }
        if let Some(car) = &mut self.chase
            && car.pending
            && car.last_try_s.is_none_or(|t| now >= t + CHASE_EVERY_S)
        {
            car.last_try_s = Some(now);
            self.in_flight = Some(InFlight::Chase);
            return Some(listener(&ListenerBody::chase_car(
                &self.config,
                car.position,
            )));
        }
        if self.queue.is_empty() || now < self.telemetry_at {
            return None;
        }
        let old_ms = (self.config.historical_after_s * 1000.0) as u64;
        let mut points: Vec<TelemetryPoint> = Vec::new();
        let mut through = 0;
        let mut historical = 0;
        for q in self.queue.head(BATCH_MAX) {
            let mut p = q.sample.point.clone();
            p.historical = wall_ms.saturating_sub(q.sample.fix_ms) > old_ms;
            historical += u64::from(p.historical);
            through = q.seq;
            points.push(p);
        }
        let json = serde_json::to_vec(&points).ok()?;
        self.in_flight = Some(InFlight::Telemetry {
            through,
            points: points.len(),
            historical,
        });
        Some(Request::Telemetry {
            json,
            points: points.len(),
        })
    }

    /// When [`Uploader::poll`] may next have something (`None`: only after an answer, a
    /// point or a chase car).
    pub fn next_wake(&self) -> Option<f64> {
        if self.in_flight.is_some() {
            return None;
        }
        let chase = self
            .chase
            .as_ref()
            .filter(|c| c.pending)
            .map(|c| c.last_try_s.map_or(0.0, |t| t + CHASE_EVERY_S));
        let telemetry = (!self.queue.is_empty()).then_some(self.telemetry_at);
        let due = [self.station_at, chase, telemetry]
            .into_iter()
            .flatten()
            .reduce(f64::min)?;
        Some(self.retry_at.map_or(due, |r| r.max(due)))
    }

    /// The answer to the request out, at `now` (`wall_ms`).
    pub fn answered(&mut self, now: f64, wall_ms: u64, answer: Answer) -> Outcome {
        let mut out = Outcome::default();
        let Some(sent) = self.in_flight.take() else {
            return out;
        };
        let (code, body) = match &answer {
            Answer::Status { code, body } => (Some(*code), body.as_str()),
            Answer::Failed(_) => (None, ""),
        };
        let what = match sent {
            InFlight::Telemetry { points, .. } => plural(points, "point"),
            InFlight::Station => "the station's position".into(),
            InFlight::Chase => "the chase car's position".into(),
        };
        let taken = code.is_some_and(|c| (200..300).contains(&c));
        let refused = code == Some(400);
        self.view.last_result = Some(match &answer {
            Answer::Status { code, .. } if taken => format!("{code}: {what} taken"),
            Answer::Status { code, body } => format!("{code}: {}", first_line(body)),
            Answer::Failed(why) => format!("no answer: {why}"),
        });
        if !taken && !refused {
            self.failed(now, wall_ms, &what, &mut out);
            return out;
        }
        if self.view.failing {
            out.log
                .push((Level::Info, "SondeHub: the server answers again".into()));
        }
        self.failures = 0;
        self.retry_at = None;
        self.view.failing = false;
        self.view.retry_wall_ms = None;
        if refused {
            let text = format!("HTTP 400 for {what}: {}", first_line(body));
            out.log
                .push((Level::Warn, format!("SondeHub refused {text}")));
            self.note_error(wall_ms, text);
        }
        match sent {
            InFlight::Telemetry {
                through,
                points,
                historical,
            } => {
                out.persist = self.queue.done_through(through);
                if refused {
                    self.view.refused += points as u64;
                } else {
                    let errors = self.accepted(wall_ms, code, body, &mut out);
                    let errors = errors.min(points);
                    self.view.refused += errors as u64;
                    self.view.sent += (points - errors) as u64;
                    self.view.historical += historical;
                    self.view.last_upload_wall_ms = Some(wall_ms);
                    if code == Some(202) {
                        self.view.last_result = Some(format!(
                            "202: {} of {points} points taken, {errors} refused, {}",
                            points - errors,
                            plural(self.last_warnings, "warning")
                        ));
                    }
                }
                // A full batch is a backlog draining: the next at once.
                self.telemetry_at = if points >= BATCH_MAX {
                    now
                } else {
                    now + self.config.period_s
                };
            }
            InFlight::Station => {
                self.station_at = Some(now + STATION_EVERY_S);
                if taken {
                    self.view.station_uploaded_wall_ms = Some(wall_ms);
                }
            }
            InFlight::Chase => {
                if let Some(car) = &mut self.chase {
                    car.pending = false;
                    if taken {
                        car.uploaded_wall_ms = Some(wall_ms);
                    }
                }
            }
        }
        out
    }

    /// A 202's errors and warnings noted and logged; how many points it refused.
    fn accepted(
        &mut self,
        wall_ms: u64,
        code: Option<u16>,
        body: &str,
        out: &mut Outcome,
    ) -> usize {
        self.last_warnings = 0;
        if code != Some(202) {
            return 0;
        }
        let Ok(accepted) = serde_json::from_str::<Accepted>(body) else {
            let text = format!("202 without its JSON: {}", first_line(body));
            out.log.push((Level::Warn, format!("SondeHub: {text}")));
            self.note_warning(wall_ms, text);
            return 0;
        };
        for (i, e) in accepted.errors.iter().enumerate() {
            if i < LOGGED_PER_ANSWER {
                out.log.push((
                    Level::Warn,
                    format!("SondeHub refused a point: {}", e.text()),
                ));
            }
            self.note_error(wall_ms, e.text());
        }
        for (i, w) in accepted.warnings.iter().enumerate() {
            if i < LOGGED_PER_ANSWER {
                out.log
                    .push((Level::Warn, format!("SondeHub warns: {}", w.text())));
            }
            self.note_warning(wall_ms, w.text());
        }
        self.last_warnings = accepted.warnings.len();
        let more = accepted.errors.len() + accepted.warnings.len();
        if more > 2 * LOGGED_PER_ANSWER {
            out.log.push((
                Level::Warn,
                format!(
                    "SondeHub: {} errors and {} warnings in one answer (the first logged)",
                    accepted.errors.len(),
                    accepted.warnings.len()
                ),
            ));
        }
        accepted.errors.len()
    }

    fn failed(&mut self, now: f64, wall_ms: u64, what: &str, out: &mut Outcome) {
        self.failures = self.failures.saturating_add(1);
        let first = RETRY_FIRST_S.min(self.config.retry_max_s);
        let wait =
            (first * 2f64.powi(self.failures.min(30) as i32 - 1)).min(self.config.retry_max_s);
        self.retry_at = Some(now + wait);
        let result = self.view.last_result.clone().unwrap_or_default();
        let text = format!("{what} not sent ({result}); tried again in {wait:.0} s");
        if !self.view.failing {
            out.log.push((
                Level::Warn,
                format!(
                    "SondeHub: {text} (points wait in the queue; logged once until it answers)"
                ),
            ));
        }
        self.view.failing = true;
        self.view.retry_wall_ms = Some(wall_ms + (wait * 1000.0) as u64);
        self.note_error(wall_ms, text);
    }

    fn note_error(&mut self, wall_ms: u64, text: String) {
        push_note(&mut self.view.errors, wall_ms, text);
    }

    fn note_warning(&mut self, wall_ms: u64, text: String) {
        push_note(&mut self.view.warnings, wall_ms, text);
    }

    /// The upload as the pages show it.
    pub fn view(&self) -> SondehubView {
        let mut v = self.view.clone();
        v.queued = self.queue.len() as u64;
        v.dropped = self.queue.dropped();
        v.chase_car = self.chase.as_ref().map(|c| ChaseCarView {
            callsign: self.config.chase_callsign(),
            position: c.position,
            uploaded_wall_ms: c.uploaded_wall_ms,
        });
        v
    }
}

fn listener(body: &ListenerBody) -> Request {
    Request::Listener {
        json: serde_json::to_vec(body).unwrap_or_default(),
        mobile: body.mobile,
    }
}

/// "1 point", "2 points".
fn plural(n: usize, what: &str) -> String {
    if n == 1 {
        format!("1 {what}")
    } else {
        format!("{n} {what}s")
    }
}

fn push_note(notes: &mut Vec<SondehubNote>, wall_ms: u64, text: String) {
    notes.push(SondehubNote { wall_ms, text });
    if notes.len() > NOTES_KEPT {
        notes.remove(0);
    }
}

/// The first line of an answer's body, cut to 200 characters: enough to say what it was.
fn first_line(body: &str) -> String {
    body.lines()
        .next()
        .unwrap_or("")
        .chars()
        .take(200)
        .collect()
}

#[cfg(test)]
#[path = "uploader_tests.rs"]
mod tests;

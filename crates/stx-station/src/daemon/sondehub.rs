//! `[sondehub]` on the network: a sampler task makes a point of each new GPS fix every
//! `period_s` ([`crate::sondehub::Sampler`]) and hands it over a bounded channel with
//! `try_send`; the uploader task queues it (on disk, `sondehub_store`), sends what
//! [`crate::sondehub::Uploader`] says is due over HTTP (`reqwest`, rustls; telemetry gzipped
//! with `flate2`), each request in a task of its own, and reports to the pages through
//! [`SondehubShare`]. Neither task touches the link or the core's loop beyond reading the
//! state as the chase broadcast does: a slow or absent server delays nothing else.

use std::io::Write;
use std::sync::Arc;
use std::time::{Duration, SystemTime, UNIX_EPOCH};

use tokio::sync::{mpsc, watch};

use super::sondehub_store::Store;
use crate::http::{Shared, SondehubShare};
use crate::sondehub::point::{SOFTWARE_NAME, SOFTWARE_VERSION};
use crate::sondehub::{
    Answer, Level, Outcome, Persist, Queue, Request, Restored, Sample, Sampler, SondehubConfig,
    Uploader,
};

/// Points between the sampler and the uploader at most (minutes of points at 2–30 s).
const HANDOVER: usize = 64;

/// The upload, prepared before the station's tasks start: its queue read back from disk.
pub(super) struct Prepared {
    config: SondehubConfig,
    uploader: Uploader,
    store: Option<Store>,
    chase_car: watch::Receiver<Option<[f64; 3]>>,
}

fn wall_ms() -> u64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map(|d| d.as_millis() as u64)
        .unwrap_or(0)
}

/// Reads the queue `config` names and builds the pages' side; `now`: the station's clock.
pub(super) async fn prepare(config: SondehubConfig, now: f64) -> (SondehubShare, Prepared) {
    let max = config.queue_max_points;
    let (queue, restored, store) = match &config.queue_dir {
        None => {
            tracing::warn!(
                "SondeHub: no queue directory (no state directory): points wait in memory only"
            );
            (Queue::new(max), Restored::default(), None)
        }
        Some(dir) => match Store::open(dir).await {
            Ok((store, found)) => {
                let (queue, restored) = Queue::restore(max, found.journal.lines(), found.mark);
                if restored.points > 0 || restored.unreadable > 0 {
                    tracing::info!(
                        dir = %dir.display(),
                        waiting = restored.points,
                        unreadable = restored.unreadable,
                        dropped = restored.dropped,
                        "SondeHub: points from before the restart wait to be sent"
                    );
                }
                (queue, restored, Some(store))
            }
            Err(e) => {
                tracing::error!(dir = %dir.display(), error = %e, "SondeHub: queue directory unusable: points wait in memory only");
                (Queue::new(max), Restored::default(), None)
            }
        },
    };
    let uploader = Uploader::new(config.clone(), queue, restored, store.is_some(), now);
    let (chase_tx, chase_rx) = watch::channel(None);
    let share = SondehubShare {
        view: std::sync::Mutex::new(uploader.view()),
        chase_car: chase_tx,
    };
    let prepared = Prepared {
        config,
        uploader,
        store,
        chase_car: chase_rx,
    };
    (share, prepared)
}

/// Samples and uploads until `stop`.
pub(super) async fn run(p: Prepared, shared: Arc<Shared>, stop: watch::Receiver<bool>) {
    let (points_tx, points_rx) = mpsc::channel(HANDOVER);
    tokio::spawn(sample(
        p.config.clone(),
        shared.clone(),
        points_tx,
        stop.clone(),
    ));
    let client = match reqwest::Client::builder()
        .user_agent(format!("{SOFTWARE_NAME}-{SOFTWARE_VERSION}"))
        .timeout(Duration::from_secs_f64(p.config.timeout_s))
        .build()
    {
        Ok(c) => c,
        Err(e) => {
            tracing::error!(error = %e, "SondeHub: no HTTP client: nothing is uploaded");
            return;
        }
    };
    tracing::info!(url = %p.config.base_url(), payload = %p.config.payload_callsign, "SondeHub upload on");
    upload(p, shared, client, points_rx, stop).await;
}

/// Every `period_s`, the newest fix as a point, handed to the uploader without waiting.
async fn sample(
    config: SondehubConfig,
    shared: Arc<Shared>,
    points: mpsc::Sender<Sample>,
    mut stop: watch::Receiver<bool>,
) {
    let mut sampler = Sampler::default();
    let mut every = tokio::time::interval(Duration::from_secs_f64(config.period_s));
    every.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Skip);
    let mut lost = 0u64;
    loop {
        tokio::select! {
            _ = every.tick() => {}
            _ = stop.changed() => break,
        }
        let now = shared.now_s();
        let sample = {
            let state = shared.core().state_msg_now(now);
            sampler.sample(&config, state.wall_ms, state.vehicle.as_ref())
        };
        let Some(sample) = sample else { continue };
        if points.try_send(sample).is_err() {
            lost += 1;
            tracing::warn!(
                lost,
                "SondeHub: the uploader fell behind; a point was not queued"
            );
        }
    }
}

async fn upload(
    mut p: Prepared,
    shared: Arc<Shared>,
    client: reqwest::Client,
    mut points: mpsc::Receiver<Sample>,
    mut stop: watch::Receiver<bool>,
) {
    let (answers_tx, mut answers) = mpsc::channel::<Answer>(1);
    let base = p.config.base_url().to_string();
    let mut store_failing = false;
    loop {
        if let Some(request) = p.uploader.poll(shared.now_s(), wall_ms()) {
            tokio::spawn(send(
                client.clone(),
                base.clone(),
                request,
                answers_tx.clone(),
            ));
        }
        publish(&shared, &p.uploader);
        let wait = p
            .uploader
            .next_wake()
            .map_or(3600.0, |t| (t - shared.now_s()).max(0.0));
        let event = tokio::select! {
            Some(sample) = points.recv() => Event::Point(Box::new(sample)),
            Some(answer) = answers.recv() => Event::Answer(answer),
            Ok(()) = p.chase_car.changed() => Event::ChaseCar,
            _ = tokio::time::sleep(Duration::from_secs_f64(wait.min(3600.0))) => Event::Wake,
            _ = stop.changed() => break,
        };
        let persist = match event {
            Event::Point(sample) => p.uploader.add(*sample),
            Event::Answer(answer) => {
                let Outcome { persist, log } =
                    p.uploader.answered(shared.now_s(), wall_ms(), answer);
                for (level, line) in log {
                    match level {
                        Level::Info => tracing::info!("{line}"),
                        Level::Warn => tracing::warn!("{line}"),
                    }
                }
                persist
            }
            Event::ChaseCar => {
                if let Some(position) = *p.chase_car.borrow_and_update() {
                    p.uploader.chase_car(position);
                }
                Persist::default()
            }
            Event::Wake => Persist::default(),
        };
        if let Some(store) = &p.store {
            match store.apply(persist).await {
                Ok(()) => store_failing = false,
                Err(e) if !store_failing => {
                    store_failing = true;
                    tracing::error!(error = %e, "SondeHub: the queue's files cannot be written: a restart now would lose what waits");
                }
                Err(_) => {}
            }
        }
    }
}

/// What woke the uploader.
enum Event {
    Point(Box<Sample>),
    Answer(Answer),
    ChaseCar,
    Wake,
}

fn publish(shared: &Shared, uploader: &Uploader) {
    if let Some(share) = &shared.sondehub
        && let Ok(mut view) = share.view.lock()
    {
        *view = uploader.view();
    }
}

/// Sends `request` and hands back how it ended.
async fn send(
    client: reqwest::Client,
    base: String,
    request: Request,
    answers: mpsc::Sender<Answer>,
) {
    let url = format!("{base}{}", request.path());
    let date = httpdate::fmt_http_date(SystemTime::now());
    let builder = client
        .put(&url)
        .header(reqwest::header::CONTENT_TYPE, "application/json")
        .header(reqwest::header::DATE, date);
    let builder = match request {
        Request::Telemetry { json, .. } => match gzip(&json) {
            Ok(body) => builder
                .header(reqwest::header::CONTENT_ENCODING, "gzip")
                .body(body),
            Err(_) => builder.body(json),
        },
        Request::Listener { json, .. } => builder.body(json),
    };
    let answer = match builder.send().await {
        Ok(response) => {
            let code = response.status().as_u16();
            match response.text().await {
                Ok(body) => Answer::Status { code, body },
                Err(e) => Answer::Failed(format!("answer {code} cut short: {e}")),
            }
        }
        Err(e) if e.is_timeout() => Answer::Failed("timed out".into()),
        Err(e) => Answer::Failed(describe(&e)),
    };
    let _ = answers.send(answer).await;
}

/// A client error with its causes ("error sending request: … : Connection refused").
fn describe(e: &dyn std::error::Error) -> String {
    let mut text = e.to_string();
    let mut cause = e.source();
    while let Some(c) = cause {
        text.push_str(": ");
        text.push_str(&c.to_string());
        cause = c.source();
    }
    text
}

fn gzip(json: &[u8]) -> std::io::Result<Vec<u8>> {
    let mut encoder = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
    encoder.write_all(json)?;
    encoder.finish()
}

//! SondeHub-Amateur: the payload's track on the balloon community's public map, uploaded as
//! its API (projecthorus/sondehub-infra, `swagger.yaml`) takes it: `PUT /amateur/telemetry`
//! with a gzip-compressed JSON array of points, the station's position and a recovery
//! phone's (as a chase car, `mobile: true`) with `PUT /amateur/listeners`.
//!
//! Opt-in (`[sondehub]`, [`SondehubConfig`]). Points wait in a bounded queue kept on disk
//! ([`queue`]), so a field without internet loses nothing: they go when the server answers
//! again, the oldest as `historical` when they are older than the server's window.
//!
//! Pure: [`Sampler`] makes points from the station's state, [`Uploader`] decides what to
//! send and when and reads the answers; the daemon (`daemon::sondehub`) owns the HTTP client,
//! the files and the timers, in a task of its own off the telemetry's path.

pub mod point;
pub mod queue;
pub mod settings;
pub mod uploader;
pub mod view;

pub use point::{ListenerBody, Sample, Sampler, TelemetryPoint, utc_datetime};
pub use queue::{Persist, Queue, Restored};
pub use settings::{SondehubConfig, StationPosition};
pub use uploader::{Answer, Level, Outcome, Request, Uploader};
pub use view::{ChaseCarBody, ChaseCarView, SondehubNote, SondehubView};

//! Replaying a recording through the station (`stx replay`): the recorded link bytes go
//! through a station core of the replay's own on the recording's clock, so its estimator,
//! guidance replica and predictor run again on them ([`ReplayMode::Rerun`], e.g. to try new
//! gains on an old flight), or the recorded `state` and events go to the pages as the station
//! showed them then ([`ReplayMode::Recorded`]). Pages see `state.replay` (REPLAY, the
//! timeline), may pause, seek and change the speed (`POST /api/replay`), and cannot command:
//! nothing is listening. After a seek the pages are shown the flight as it was at the new
//! position (the station rebuilt there, the track and plots up to it), paused or not.
//!
//! - [`clock`]: where the replay is (pure, on the caller's clock), held at a seek until the
//!   station is rebuilt there;
//! - [`control`]: the clock shared between the HTTP handlers and the feeder, woken on change;
//! - [`feeder`]: reads the recording, from its start up to the position at once after every
//!   seek, then paced, and hands each message to a [`feeder::ReplaySink`];
//! - [`rerun`]: the link bytes through a ground endpoint and a station core on the
//!   recording's clock, the drone's recorded plan adopted by [`plan_listener`];
//! - [`recorded`]: what a replay of the recorded messages has shown up to its position.

pub mod clock;
pub mod control;
pub mod feeder;
pub mod plan_listener;
pub mod recorded;
pub mod rerun;

pub use clock::{MAX_SPEED, MIN_SPEED, ReplayClock, ReplayError};
pub use control::ReplayControl;
pub use recorded::RecordedTimeline;
pub use rerun::Rerun;

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// What a replay shows.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum ReplayMode {
    /// The recorded link bytes through this station's estimator, guidance and predictor.
    Rerun,
    /// The station's `state` and events as they were recorded.
    Recorded,
}

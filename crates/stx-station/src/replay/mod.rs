//! Replaying a recording through the station (`stx replay`): the recorded link bytes go back
//! into a station's link as they came, so its estimator, guidance replica and predictor run
//! again on them ([`ReplayMode::Rerun`], e.g. to try new gains on an old flight), or the
//! recorded `state` and events go to the pages as the station showed them then
//! ([`ReplayMode::Recorded`]). Pages see `state.replay` (REPLAY, the timeline), may pause,
//! seek and change the speed (`POST /api/replay`), and cannot command: nothing is listening.
//!
//! - [`clock`]: where the replay is (pure, on the caller's clock);
//! - [`control`]: the clock shared between the HTTP handlers and the feeder, woken on change;
//! - [`feeder`]: reads the recording from the position through its index and hands each
//!   message to a [`feeder::ReplaySink`] when it is due.

pub mod clock;
pub mod control;
pub mod feeder;

pub use clock::{MAX_SPEED, MIN_SPEED, ReplayClock, ReplayError};
pub use control::ReplayControl;

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

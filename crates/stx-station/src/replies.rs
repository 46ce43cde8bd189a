//! The API's replies around the station's state (`API.md`): the WebSocket's `hello`,
//! `history`, `lagged` and `pong`, and the bodies of the REST lists and of a command's `202`.
//! The state, events, command results and parameters themselves are in [`crate::messages`].
//! Also the recordings list of `GET /api/recordings` and the answer that opens a replay.

use schemars::JsonSchema;
use serde::Serialize;

use crate::config::Role;
use crate::messages::{EventMsg, Session, StateMsg, TrackPoint};
use crate::recording::summary::RecordingSummary;

/// The WebSocket's first message.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct HelloMsg {
    /// Always `hello`.
    #[serde(rename = "type")]
    #[schemars(extend("const" = "hello"))]
    pub kind: &'static str,
    /// As `GET /api/session` answers it.
    pub session: Session,
    /// The caller's role (as in `session`).
    pub role: Role,
    /// The caller's name (as in `session`).
    pub name: String,
}

/// Sent once after `hello` and the first `state`: what happened before the page connected;
/// in a replay also to every page after each seek: what happened before the new position.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct HistoryMsg {
    /// Always `history`.
    #[serde(rename = "type")]
    #[schemars(extend("const" = "history"))]
    pub kind: &'static str,
    /// The track at 1 s.
    pub track: Vec<TrackPoint>,
    /// The last 500 events, oldest first.
    pub events: Vec<EventMsg>,
    /// The last 5 minutes of states at 1 Hz, for the plots.
    pub states: Vec<StateMsg>,
    /// In a replay, the seek it belongs to (`ReplayView.epoch`): after each seek every page
    /// gets the history at the new position, which replaces its track, plots and event log;
    /// `null` on a live station.
    pub replay_epoch: Option<u64>,
}

/// The page fell more than the backlog behind: it missed events, command results or
/// parameter tables, and should re-read them.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct LaggedMsg {
    /// Always `lagged`.
    #[serde(rename = "type")]
    #[schemars(extend("const" = "lagged"))]
    pub kind: &'static str,
    /// Messages missed this time.
    pub missed: u64,
    /// Messages missed since the page connected.
    pub missed_total: u64,
    /// Mission clock, s.
    pub time_s: f64,
    /// Where to re-read the event log: always `/api/events`.
    #[schemars(extend("const" = "/api/events"))]
    pub refetch: &'static str,
}

/// The answer to the page's `ping`.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct PongMsg {
    /// Always `pong`.
    #[serde(rename = "type")]
    #[schemars(extend("const" = "pong"))]
    pub kind: &'static str,
}

/// One connected WebSocket page and what it was sent or missed.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct ClientView {
    /// The page's number, from 1 in order of connection.
    pub id: u64,
    /// The token's name.
    pub name: String,
    /// The token's role.
    pub role: Option<Role>,
    /// Mission time it connected, s.
    pub connected_s: f64,
    /// `state` messages sent.
    pub states_sent: u64,
    /// `state` messages skipped because the page was behind (a newer one was sent instead).
    pub states_coalesced: u64,
    /// Events, command results and parameter tables sent.
    pub messages_sent: u64,
    /// Events, command results and parameter tables missed by falling more than the backlog
    /// behind.
    pub messages_missed: u64,
    /// Events, command results and tables queued for it and not yet sent; past the backlog
    /// (4096) it gets `lagged`.
    pub messages_behind: u64,
    /// Times it fell that far behind.
    pub lag_episodes: u64,
    /// When the socket is a public relay's (`stx relay`): the pages it serves, as it last said.
    pub relay_viewers: Option<u32>,
}

/// `GET /api/clients`.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct ClientsBody {
    /// The connected pages.
    pub clients: Vec<ClientView>,
}

/// `GET /api/events`.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct EventsBody {
    /// The event log since `since_s`, oldest first.
    pub events: Vec<EventMsg>,
}

/// `GET /api/track`.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct TrackBody {
    /// The track, a point at most every `every_s`.
    pub points: Vec<TrackPoint>,
}

/// The `202` of a command: it is on its way; the outcome follows as `command_result`.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct CommandAccepted {
    /// The request, as `command_result` and `GET /api/commands/{id}` name it.
    pub request_id: String,
    /// Always `sent`.
    #[schemars(extend("const" = "sent"))]
    pub status: &'static str,
}

/// The recordings, newest first, and the files that could not be read.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
pub struct RecordingsBody {
    /// The recordings directory (`null` when the station has none).
    pub directory: Option<String>,
    /// Every readable recording, newest first.
    pub recordings: Vec<RecordingSummary>,
    /// Files of the directory that are not readable recordings, with why.
    pub unreadable: Vec<UnreadableRecording>,
}

/// A file of the recordings directory that could not be summarised.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
pub struct UnreadableRecording {
    /// File name.
    pub name: String,
    /// Why.
    pub reason: String,
}

/// A replay station the daemon started for a page.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
pub struct ReplayOpened {
    /// The recording.
    pub name: String,
    /// Port of the replay's dashboard, on the host the page used.
    pub port: u16,
    /// `https` with `[tls]`, else `http`.
    pub scheme: &'static str,
}

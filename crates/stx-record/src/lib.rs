//! stx-record: every flight kept, as MCAP files that replay in the station and open in
//! Foxglove and other MCAP tools.
//!
//! How the parts fit:
//! - What is recorded. Every channel is JSON with a JSON Schema ([`channel`]): Foxglove's
//!   well-known types where one fits ([`foxglove`]: positions with covariance on a map,
//!   events in a log panel, attitude as a frame transform), the raw MAVLink frames in both
//!   directions with their radio ([`frame`]), and the station's own types, whose schemas the
//!   station supplies. Each file starts with a metadata record ([`info`]: station version,
//!   vehicle, mission, the names of token holders — by construction never a token or key).
//! - Writing, sans-io. [`RecorderCore`] ([`writer`]) takes messages and `now` and hands out
//!   the bytes of MCAP files, one whole chunk at a time, and says when a file starts and
//!   ends: chunks close at a size or after at most a second open (so a killed process loses
//!   about a second), files rotate at a size or duration.
//! - Writing, to disk. [`Recorder`] ([`file`](mod@file)) runs a core on its own thread fed by a
//!   bounded queue that never blocks the caller; what it could not write is counted and
//!   reported ([`status`]). A disk that refuses the recording is tried again after waits
//!   that double ([`backoff`]), keeping what was written and leaving no empty files. Files go
//!   to [`file::recordings_dir`] of the station's state directory unless the station says
//!   otherwise.
//! - Reading. [`Recording`] ([`read`]) lists channels, counts, time range and metadata from
//!   the file's summary (or, for a file cut before its summary, from one scan of it —
//!   `read::scan`) and iterates messages in log-time order from any time through the chunk
//!   indexes. [`recover()`] ([`recover`](mod@recover)) writes a clean, finished copy of a cut file.
//!   Both walk cut files with the private `records` module.
//! - Export. [`export`]: one CSV per channel with units, and the track as KML or GPX.
//!
//! No tokio: the core is plain data; the file adapter uses a thread and a std channel.

pub mod backoff;
pub mod channel;
pub mod export;
pub mod file;
pub mod foxglove;
pub mod frame;
pub mod info;
pub mod read;
mod records;
pub mod recover;
pub mod status;
pub mod writer;

pub use channel::{ChannelError, ChannelId, ChannelSpec};
pub use file::{Directory, Recorder, RecorderConfig, RecorderHandle, Storage, StorageFile};
pub use frame::{Direction, MavlinkFrame};
pub use info::{Named, RecordingInfo};
pub use read::{ChannelInfo, IndexSource, ReadError, RecordedMessage, Recording};
pub use recover::{RecoverError, RecoverReport, recover, recover_file};
pub use status::{Failing, IssueKind, RecorderIssue, RecorderStatus, Resumed};
pub use writer::{Compression, CoreOptions, CoreStats, Output, RecorderCore, WriteError};

//! A flight log read from a file: a station recording (MCAP) or a flight-log CSV
//! (`stx_analysis::flight_log::csv`). stx-analysis builds logs from what it is handed and
//! opens no file; this opens one, for the Lab's jobs on a recording ([`crate::recording`]) and
//! for `stx compare` and `stx identify`, so a flight reads the same in the dashboard and on the
//! command line.

use std::path::Path;

use stx_analysis::flight_log::csv::from_csv;
use stx_analysis::flight_log::recording::LogBuilder;
use stx_analysis::flight_log::{FlightLog, FlightLogError};
use stx_record::{ReadError, Recording};
use thiserror::Error;

/// Why a flight file could not be read; each names the file, and its source says why.
#[derive(Debug, Error)]
pub enum FlightFileError {
    /// The CSV file could not be read.
    #[error("reading {path}")]
    Read {
        path: String,
        #[source]
        source: std::io::Error,
    },
    /// The CSV text is not a flight log.
    #[error("flight log {path}")]
    Csv {
        path: String,
        #[source]
        source: FlightLogError,
    },
    /// The recording could not be opened or read.
    #[error("recording {path}")]
    Recording {
        path: String,
        #[source]
        source: ReadError,
    },
    /// The recording holds no flight log (a message it cannot read, or too little).
    #[error("recording {path}")]
    RecordingLog {
        path: String,
        #[source]
        source: FlightLogError,
    },
}

/// The flight log of a recording or a CSV file (a `.csv` name is a CSV). The error names the
/// file; whatever goes wrong is the file's fault, which the command line reports as bad input.
pub fn read_log(path: &Path) -> Result<FlightLog, FlightFileError> {
    let name = || path.display().to_string();
    let is_csv = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("csv"));
    if is_csv {
        let text = std::fs::read_to_string(path).map_err(|source| FlightFileError::Read {
            path: name(),
            source,
        })?;
        return from_csv(&text).map_err(|source| FlightFileError::Csv {
            path: name(),
            source,
        });
    }
    let read = |source| FlightFileError::Recording {
        path: name(),
        source,
    };
    let log = |source| FlightFileError::RecordingLog {
        path: name(),
        source,
    };
    let mut recording = Recording::open(path).map_err(read)?;
    let mut builder = LogBuilder::default();
    for message in recording.messages().map_err(read)? {
        let message = message.map_err(read)?;
        builder
            .add(&message.topic, message.log_time, &message.data)
            .map_err(log)?;
    }
    builder.finish().map_err(log)
}

/// `error` and its sources, joined by ": " (as the command line prints an error chain), for the
/// Lab's refusal text.
pub fn chain(error: &dyn std::error::Error) -> String {
    let mut text = error.to_string();
    let mut source = error.source();
    while let Some(e) = source {
        text.push_str(": ");
        text.push_str(&e.to_string());
        source = e.source();
    }
    text
}

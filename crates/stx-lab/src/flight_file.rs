//! A flight log read from a file: a station recording (MCAP) or a flight-log CSV
//! (`stx_analysis::flight_log::csv`). stx-analysis builds logs from what it is handed and
//! opens no file; this opens one, for the Lab's jobs on a recording ([`crate::recording`]) and
//! for `stx compare` and `stx identify`, so a flight reads the same in the dashboard and on the
//! command line.

use std::path::Path;

use anyhow::Context;
use stx_analysis::flight_log::recording::LogBuilder;
use stx_analysis::flight_log::{FlightLog, csv::from_csv};
use stx_record::Recording;

/// The flight log of a recording or a CSV file (a `.csv` name is a CSV). The error names the
/// file; whatever goes wrong is the file's fault, which the command line reports as bad input.
pub fn read_log(path: &Path) -> anyhow::Result<FlightLog> {
    let is_csv = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("csv"));
    if is_csv {
        let text =
            std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
        return from_csv(&text).with_context(|| format!("flight log {}", path.display()));
    }
    let bad = |e: anyhow::Error| e.context(format!("recording {}", path.display()));
    let mut recording = Recording::open(path).map_err(|e| bad(e.into()))?;
    let mut builder = LogBuilder::default();
    for message in recording.messages().map_err(|e| bad(e.into()))? {
        let message = message.map_err(|e| bad(e.into()))?;
        builder
            .add(&message.topic, message.log_time, &message.data)
            .map_err(|e| bad(e.into()))?;
    }
    builder.finish().map_err(|e| bad(e.into()))
}

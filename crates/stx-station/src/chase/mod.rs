//! Chase cars: the "Horus UDP" `PAYLOAD_SUMMARY` datagrams that chasemapper (the chase cars'
//! map) and the Horus tools listen for on the local network (UDP broadcast, port 55672), so a
//! chase laptop shows the payload and where stx predicts it lands. The format is the one
//! horusdemodlib's `horusudp.send_payload_summary` sends (a JSON object: `type`, `callsign`,
//! `latitude`, `longitude`, `altitude` m, `speed` km/h, `heading` °, `time` "HH:MM:SS" UTC,
//! `comment`, `temp`, `sats`, `batt_voltage`, −1 for what is not known).
//!
//! The predicted landing travels as a second payload (`landing_callsign`): the Horus format
//! has no landing field, and a second marker is what a chase map shows without changes.
//!
//! Pure: [`summaries`] turns the station's state into the datagrams' contents; the daemon
//! (`daemon::chase`) sends them every `period_s`.

pub mod settings;
mod summary;

pub use settings::ChaseConfig;
pub use summary::{PayloadSummary, summaries, utc_hms};

//! `[[forward]]`: read-only MAVLink outputs, so QGroundControl or MAVProxy can watch the drone
//! beside the station. Each forward is an address (the link's forms: `udpout:` sends to a
//! watcher listening, `udpin:` answers the watcher that sent last, `tcpin:` serves one watcher
//! at a time) and mavlink-router's per-direction filters ([`stx_link::forward`]). What the
//! drone sends goes out unchanged, as the link accepted it; by default nothing a watcher sends
//! reaches the drone.
//!
//! The sockets live in the daemon (`daemon::forward`); here are the settings, their checks and
//! what the pages are shown (with the chase cars' broadcast, [`crate::chase`]: `GET
//! /api/sharing`).

use serde::{Deserialize, Serialize};
use stx_link::forward::{ForwardCounts, MessageFilter};

/// One `[[forward]]` table.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ForwardConfig {
    /// Shown on the pages and in the log.
    pub name: String,
    /// Where the watcher is: `udpout:HOST:PORT` (the watcher listens, e.g. MAVProxy's
    /// `--master=udpin:…`), `udpin:ADDR:PORT` or `tcpin:ADDR:PORT` (the watcher connects).
    pub address: String,
    /// What goes to the watcher (message ids, source systems and components to allow or
    /// block; no allow list: all). Default: everything the link accepted.
    #[serde(default)]
    pub out: MessageFilter,
    /// What of the watcher's may reach the drone. Default: nothing; only message ids in
    /// `allow_msg_id` ever do (e.g. `[0]` for its heartbeats).
    #[serde(default, rename = "in")]
    pub into_link: MessageFilter,
}

impl ForwardConfig {
    /// The first problem with `forwards` as `(field, rule)`, if any.
    pub fn invalid(forwards: &[ForwardConfig]) -> Option<(String, String)> {
        for (i, f) in forwards.iter().enumerate() {
            if f.name.trim().is_empty() {
                return Some((format!("forward[{i}].name"), "must not be empty".into()));
            }
            if forwards[..i].iter().any(|g| g.name == f.name) {
                return Some((
                    format!("forward[{i}].name"),
                    format!("`{}` is used twice", f.name),
                ));
            }
            use stx_link::address::Address;
            match f.address.parse::<Address>() {
                Err(e) => return Some((format!("forward[{i}].address"), e.to_string())),
                Ok(Address::TcpClient(_) | Address::Serial { .. }) => {
                    return Some((
                        format!("forward[{i}].address"),
                        "udpout:, udpin: or tcpin: (a watcher on the network, not a radio)".into(),
                    ));
                }
                Ok(_) => {}
            }
        }
        None
    }
}

/// A forward as the pages show it: where it goes, what it may send the drone, and its counts.
#[derive(Debug, Clone, PartialEq, Serialize, schemars::JsonSchema)]
pub struct ForwardView {
    /// The forward's name.
    pub name: String,
    /// Its address.
    pub address: String,
    /// Message ids of the watcher's that may reach the drone; empty: none (read-only).
    pub may_send_to_drone: Vec<u32>,
    /// Frames sent to the watcher.
    pub out_passed: u64,
    /// Frames its out filter kept from the watcher.
    pub out_filtered: u64,
    /// Frames lost because the forward fell behind the link (never the link's loss).
    pub out_dropped: u64,
    /// Frames of the watcher passed on to the drone.
    pub in_passed: u64,
    /// Frames of the watcher kept from the drone.
    pub in_refused: u64,
}

impl ForwardView {
    /// The view of `config` with `counts` and `dropped` so far.
    pub fn new(config: &ForwardConfig, counts: ForwardCounts, dropped: u64) -> Self {
        Self {
            name: config.name.clone(),
            address: config.address.clone(),
            may_send_to_drone: config.into_link.allow_msg_id.clone().unwrap_or_default(),
            out_passed: counts.out_passed,
            out_filtered: counts.out_filtered,
            out_dropped: dropped,
            in_passed: counts.in_passed,
            in_refused: counts.in_refused,
        }
    }
}

/// The chase cars' broadcast as the pages show it.
#[derive(Debug, Clone, PartialEq, Serialize, schemars::JsonSchema)]
pub struct ChaseView {
    /// The payload's callsign.
    pub callsign: String,
    /// The predicted landing's callsign.
    pub landing_callsign: String,
    /// Where the datagrams go, address:port.
    pub to: String,
    /// Time between two summaries, s.
    pub period_s: f64,
    /// Datagrams sent so far.
    pub sent: u64,
    /// When the last one was sent, Unix ms; `null` before the first (no GPS fix yet).
    pub last_sent_wall_ms: Option<u64>,
    /// Why the last send failed, while sends fail.
    pub error: Option<String>,
}

/// `GET /api/sharing`: what the station shares beyond its pages: the forwards, in the order
/// of the configuration, the chase cars' broadcast and the SondeHub upload.
#[derive(Debug, Clone, PartialEq, Serialize, schemars::JsonSchema)]
pub struct SharingBody {
    /// The forwards; empty when the configuration has none.
    pub forwards: Vec<ForwardView>,
    /// The chase broadcast; `null` when it is off.
    pub chase: Option<ChaseView>,
    /// The SondeHub-Amateur upload; `null` when it is off.
    pub sondehub: Option<crate::sondehub::SondehubView>,
    /// The public relays (`stx relay`) connected to the station, in order of connection.
    pub relays: Vec<RelayShare>,
}

/// A public relay on one of the station's WebSockets and the audience it reports.
#[derive(Debug, Clone, PartialEq, Serialize, schemars::JsonSchema)]
pub struct RelayShare {
    /// The socket's number, as `GET /api/clients` has it.
    pub id: u64,
    /// The name of the token the relay connected with.
    pub name: String,
    /// Mission time it connected, s.
    pub connected_s: f64,
    /// Public pages served through it, its own and those of the relays below it.
    pub viewers: u32,
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Vec<ForwardConfig> {
        #[derive(Deserialize)]
        struct T {
            forward: Vec<ForwardConfig>,
        }
        toml::from_str::<T>(text).expect("parses").forward
    }

    #[test]
    fn a_forward_reads_as_mavlink_router_writes_it_and_is_read_only_by_default() {
        let f = parse(
            "[[forward]]\nname = \"qgc\"\naddress = \"udpout:127.0.0.1:14550\"\n\
             [forward.out]\nblock_msg_id = [22]\n",
        );
        assert_eq!(f[0].out.block_msg_id, vec![22]);
        assert_eq!(f[0].into_link, MessageFilter::default());
        assert_eq!(ForwardConfig::invalid(&f), None);
        assert!(
            ForwardView::new(&f[0], ForwardCounts::default(), 0)
                .may_send_to_drone
                .is_empty()
        );
    }

    #[test]
    fn bad_forwards_name_the_field() {
        let f = parse(
            "[[forward]]\nname = \"a\"\naddress = \"udpout:127.0.0.1:1\"\n\
             [[forward]]\nname = \"a\"\naddress = \"udpout:127.0.0.1:2\"\n",
        );
        assert_eq!(
            ForwardConfig::invalid(&f).map(|e| e.0).as_deref(),
            Some("forward[1].name")
        );
        let f = parse("[[forward]]\nname = \"a\"\naddress = \"serial:/dev/ttyUSB0:57600\"\n");
        assert_eq!(
            ForwardConfig::invalid(&f).map(|e| e.0).as_deref(),
            Some("forward[0].address")
        );
        let f = parse("[[forward]]\nname = \"a\"\naddress = \"nonsense\"\n");
        assert_eq!(
            ForwardConfig::invalid(&f).map(|e| e.0).as_deref(),
            Some("forward[0].address")
        );
    }
}

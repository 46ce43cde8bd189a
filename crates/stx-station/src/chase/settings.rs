//! `[chase]` in the station's configuration, checked.

use serde::{Deserialize, Serialize};

/// `[chase]`: the broadcast for chase cars; off unless configured.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ChaseConfig {
    /// The payload's callsign on the chase maps.
    pub callsign: String,
    /// The predicted landing's callsign (default: the payload's with `_LANDING`).
    #[serde(default)]
    pub landing_callsign: Option<String>,
    /// Where the datagrams go: the network's broadcast address (default `255.255.255.255`),
    /// or one chase laptop's address.
    #[serde(default = "default_address")]
    pub address: std::net::IpAddr,
    /// UDP port chasemapper listens on (Horus UDP's 55672 by default).
    #[serde(default = "default_port")]
    pub port: u16,
    /// Time between two summaries, s (1–60).
    #[serde(default = "default_period_s")]
    pub period_s: f64,
}

fn default_address() -> std::net::IpAddr {
    std::net::Ipv4Addr::BROADCAST.into()
}

fn default_port() -> u16 {
    55672
}

fn default_period_s() -> f64 {
    2.0
}

impl ChaseConfig {
    /// The first problem as `(field, rule)`, if any.
    pub fn invalid(&self) -> Option<(&'static str, &'static str)> {
        let callsign_ok =
            |c: &str| !c.is_empty() && c.len() <= 32 && c.chars().all(|ch| ch.is_ascii_graphic());
        if !callsign_ok(&self.callsign) {
            return Some((
                "chase.callsign",
                "1–32 printable ASCII characters, no spaces",
            ));
        }
        if self
            .landing_callsign
            .as_deref()
            .is_some_and(|c| !callsign_ok(c))
        {
            return Some((
                "chase.landing_callsign",
                "1–32 printable ASCII characters, no spaces",
            ));
        }
        if !(1.0..=60.0).contains(&self.period_s) {
            return Some(("chase.period_s", "between 1 and 60 s"));
        }
        if self.port == 0 {
            return Some(("chase.port", "a port, 1–65535"));
        }
        None
    }

    /// The predicted landing's callsign.
    pub fn landing_callsign(&self) -> String {
        self.landing_callsign
            .clone()
            .unwrap_or_else(|| format!("{}_LANDING", self.callsign))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_bad_chase_table_names_its_field() {
        let parse = |t: &str| toml::from_str::<ChaseConfig>(t).expect("parses");
        let ok = parse("callsign = \"STRAPLEX1\"");
        assert_eq!((ok.port, ok.period_s, ok.invalid()), (55672, 2.0, None));
        assert_eq!(ok.landing_callsign(), "STRAPLEX1_LANDING");
        assert_eq!(
            parse("callsign = \"A B\"").invalid().map(|e| e.0),
            Some("chase.callsign")
        );
        assert_eq!(
            parse("callsign = \"A\"\nperiod_s = 0.1")
                .invalid()
                .map(|e| e.0),
            Some("chase.period_s")
        );
        assert!(toml::from_str::<ChaseConfig>("callsign = \"A\"\nperiod = 2").is_err());
    }
}

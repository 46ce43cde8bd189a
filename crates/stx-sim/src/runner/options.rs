//! What [`super::Flight`] flies, and how: the mission, where the station is, the speed, the
//! drone's link settings and signing, how long it stays on the air after landing, and where
//! the simulated ground anemometer sends its wind.

use std::fmt;
use std::net::SocketAddr;
use std::path::PathBuf;
use std::str::FromStr;
use std::time::Duration;

use stx_link::endpoint::LinkConfig;
use stx_link::signing::SigningKey;

use crate::drone::MissionConfig;

/// How fast mission time runs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Speed {
    /// This many times real time.
    Times(f64),
    /// As fast as the computer goes.
    Max,
}

impl FromStr for Speed {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        if s == "max" {
            return Ok(Self::Max);
        }
        match s.parse::<f64>() {
            Ok(v) if v > 0.0 && v.is_finite() => Ok(Self::Times(v)),
            _ => Err(format!(
                "{s:?} is not a speed: a number > 0 (times real time) or `max`"
            )),
        }
    }
}

impl fmt::Display for Speed {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Times(v) => write!(f, "{v}x"),
            Self::Max => write!(f, "max"),
        }
    }
}

/// MAVLink 2 signing of the drone's link: with it, unsigned traffic is refused.
#[derive(Debug, Clone)]
pub struct Signing {
    /// The shared key (its `Debug` prints no byte of it).
    pub key: SigningKey,
    /// Where the timestamp's high-water mark is kept across restarts: read at the start,
    /// written before the first signed frame and ahead of every later one, so a restart with
    /// the clock set back still signs above every timestamp already used.
    pub timestamp_file: PathBuf,
    /// The wall-clock reading the signing clock starts from (time since the Unix epoch);
    /// `None` reads the system clock. Tests set it to rehearse a clock set back.
    pub clock_unix: Option<Duration>,
}

/// What to fly, and how.
#[derive(Debug, Clone)]
pub struct FlyOptions {
    /// Where the station is, as an stx-link address: `udpout:127.0.0.1:14550` (the station's
    /// `udpin`), `udpin:…`, `tcp:…`, `tcpin:…`, `serial:PATH:BAUD`.
    pub connect: String,
    /// The mission, with any command-line changes already applied
    /// ([`crate::drone::MissionOverrides`]).
    pub mission: MissionConfig,
    /// Mission time per real time.
    pub speed: Speed,
    /// The drone's link settings (system id, heartbeat period); its `signing` is replaced by
    /// [`Self::signing`]'s.
    pub link: LinkConfig,
    /// Signing, if the link is signed.
    pub signing: Option<Signing>,
    /// How long to keep answering on the ground after landing, real time; `None`: until the
    /// shutdown future resolves (what a station running the drone beside it wants).
    pub linger: Option<Duration>,
    /// The vehicle the drone truly flies (a vehicle file, e.g. one the Lab identified); the
    /// shipped STRAPLEX vehicle by default. The onboard guidance keeps the mission's own polar
    /// and gains whatever it is.
    pub vehicle: stx_dynamics::vehicle::Vehicle,
    /// Fly a vehicle and sensors drawn from this dispersion set (with the mission's seed)
    /// around [`Self::vehicle`] instead of it and the mission's sensors; the servos stay
    /// perfect.
    pub dispersions: Option<crate::dispersions::Dispersions>,
    /// Send the simulated world's ground anemometer (a 10-m mast by the mission's target, in
    /// the wind the drone truly flies: [`crate::anemometer`]) to this UDP address, one NMEA
    /// MWV sentence a datagram every report; `None`: no anemometer.
    pub anemometer_to: Option<SocketAddr>,
}

impl FlyOptions {
    /// `mission` towards `connect` in real time, system id 1, no signing, the shipped vehicle,
    /// no ground anemometer, stopping as soon as it has landed.
    pub fn new(connect: &str, mission: MissionConfig) -> Self {
        Self {
            connect: connect.to_string(),
            mission,
            speed: Speed::Times(1.0),
            link: LinkConfig::vehicle(),
            signing: None,
            linger: Some(Duration::ZERO),
            vehicle: stx_dynamics::vehicle::Vehicle::straplex(),
            dispersions: None,
            anemometer_to: None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn speeds_parse_and_print_and_nonsense_is_refused() {
        assert_eq!("max".parse::<Speed>(), Ok(Speed::Max));
        assert_eq!("2.5".parse::<Speed>(), Ok(Speed::Times(2.5)));
        for bad in ["0", "-1", "inf", "NaN", "fast"] {
            assert!(bad.parse::<Speed>().is_err(), "{bad}");
        }
        assert_eq!(Speed::Times(10.0).to_string(), "10x");
        assert_eq!(Speed::Max.to_string(), "max");
    }
}

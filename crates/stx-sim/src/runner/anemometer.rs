//! The simulated world's ground anemometer on the air ([`FlyOptions::anemometer_to`]): one
//! [`Anemometer`] by the mission's target, in the wind the drone truly flies, moved on to each
//! step's mission time; each report goes as one UDP datagram holding its NMEA 0183 MWV
//! sentence, as a serial-to-UDP gateway by a real mast forwards it to the station.
//!
//! A failed send is counted and logged once, and never stops the flight: the anemometer is
//! the station's aid, and a station not listening yet must not end the drone's run.
//!
//! [`FlyOptions::anemometer_to`]: super::FlyOptions::anemometer_to

use std::io;
use std::net::{Ipv4Addr, Ipv6Addr, SocketAddr};
use std::sync::Arc;

use serde::Serialize;
use stx_types::wind::WindField;
use tokio::net::UdpSocket;

use crate::anemometer::{Anemometer, AnemometerConfig, mwv_sentence};
use crate::drone::Drone;

/// What the ground anemometer sent, for the flight's report.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub struct AnemometerCounters {
    /// Reports the instrument made.
    pub reports: u64,
    /// Of them, handed to the socket.
    pub sent: u64,
    /// Of them, refused by the socket (only the first is logged).
    pub send_errors: u64,
}

/// The instrument, the wind it stands in and the socket it sends from.
pub(super) struct AnemometerLink {
    anemometer: Anemometer,
    /// The drone's true wind: the instrument measures the world, not any forecast.
    wind: Arc<dyn WindField>,
    socket: UdpSocket,
    to: SocketAddr,
    counters: AnemometerCounters,
}

impl AnemometerLink {
    /// An instrument (default settings, errors drawn from the mission's seed) by the target of
    /// `drone`'s mission, at the launch site when the mission has none, in the drone's true
    /// wind, sending to `to` from an ephemeral socket of `to`'s address family.
    pub(super) async fn open(to: SocketAddr, drone: &Drone) -> io::Result<Self> {
        let any: SocketAddr = if to.is_ipv4() {
            (Ipv4Addr::UNSPECIFIED, 0).into()
        } else {
            (Ipv6Addr::UNSPECIFIED, 0).into()
        };
        let socket = UdpSocket::bind(any).await?;
        let mission = drone.config();
        let target = mission.target_ned_m().map(|t| [t.x, t.y]);
        let config = AnemometerConfig::default().beside(target.unwrap_or([0.0, 0.0]));
        tracing::info!(
            %to,
            mast_ne_m = ?config.offset_ne_m,
            by = if target.is_some() { "the target" } else { "the launch site (no target)" },
            "ground anemometer sending NMEA MWV"
        );
        Ok(Self {
            anemometer: Anemometer::new(config, mission.seed),
            wind: Arc::clone(&drone.physics().environment().wind),
            socket,
            to,
            counters: AnemometerCounters::default(),
        })
    }

    /// Moves the instrument on to mission time `time_s` and sends the report it makes, if any.
    pub(super) async fn step(&mut self, time_s: f64) {
        let Some(report) = self.anemometer.step(time_s, &*self.wind) else {
            return;
        };
        self.counters.reports += 1;
        let sentence = mwv_sentence(&report);
        match self.socket.send_to(sentence.as_bytes(), self.to).await {
            Ok(_) => self.counters.sent += 1,
            Err(error) => {
                if self.counters.send_errors == 0 {
                    tracing::warn!(
                        to = %self.to,
                        %error,
                        "ground anemometer: MWV not sent (later failures are only counted)"
                    );
                }
                self.counters.send_errors += 1;
            }
        }
    }

    /// What it sent so far.
    pub(super) fn counters(&self) -> AnemometerCounters {
        self.counters
    }
}

//! Where the drone is and how it flies: GNSS fixes ([`GpsRaw`], GPS_RAW_INT), the onboard
//! estimate ([`GlobalPosition`], GLOBAL_POSITION_INT), attitude ([`Attitude`], ATTITUDE),
//! pitot air data ([`AirData`], SCALED_PRESSURE) and the HUD summary ([`Hud`], VFR_HUD).

use mavlink::dialects::common as mc;
use mavlink::dialects::common::MavMessage;
use serde::{Deserialize, Serialize};

use super::units::{
    acc_to_mm, c_to_cdeg, cdeg_to_course, course_to_cdeg, deg_to_e7, e7_to_deg, m_to_mm, mm_to_acc,
    mm_to_m, mps_to_cms_i16,
};

/// GNSS fix type (GPS_FIX_TYPE).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
#[serde(rename_all = "snake_case")]
pub enum GpsFix {
    NoGps,
    NoFix,
    Fix2d,
    Fix3d,
    Dgps,
    RtkFloat,
    RtkFixed,
    Static,
    Ppp,
}

impl GpsFix {
    pub(super) fn to_mav(self) -> mc::GpsFixType {
        use mc::GpsFixType as G;
        match self {
            Self::NoGps => G::GPS_FIX_TYPE_NO_GPS,
            Self::NoFix => G::GPS_FIX_TYPE_NO_FIX,
            Self::Fix2d => G::GPS_FIX_TYPE_2D_FIX,
            Self::Fix3d => G::GPS_FIX_TYPE_3D_FIX,
            Self::Dgps => G::GPS_FIX_TYPE_DGPS,
            Self::RtkFloat => G::GPS_FIX_TYPE_RTK_FLOAT,
            Self::RtkFixed => G::GPS_FIX_TYPE_RTK_FIXED,
            Self::Static => G::GPS_FIX_TYPE_STATIC,
            Self::Ppp => G::GPS_FIX_TYPE_PPP,
        }
    }
    pub(super) fn from_mav(g: mc::GpsFixType) -> Self {
        use mc::GpsFixType as G;
        match g {
            G::GPS_FIX_TYPE_NO_GPS => Self::NoGps,
            G::GPS_FIX_TYPE_NO_FIX => Self::NoFix,
            G::GPS_FIX_TYPE_2D_FIX => Self::Fix2d,
            G::GPS_FIX_TYPE_3D_FIX => Self::Fix3d,
            G::GPS_FIX_TYPE_DGPS => Self::Dgps,
            G::GPS_FIX_TYPE_RTK_FLOAT => Self::RtkFloat,
            G::GPS_FIX_TYPE_RTK_FIXED => Self::RtkFixed,
            G::GPS_FIX_TYPE_STATIC => Self::Static,
            G::GPS_FIX_TYPE_PPP => Self::Ppp,
        }
    }
}

/// Raw GNSS receiver output (GPS_RAW_INT).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
pub struct GpsRaw {
    /// Receiver timestamp, µs (Unix epoch or since boot).
    pub time_usec: u64,
    /// Fix type.
    pub fix: GpsFix,
    /// Latitude, degrees WGS84 (wire: degE7).
    pub lat_deg: f64,
    /// Longitude, degrees WGS84 (wire: degE7).
    pub lon_deg: f64,
    /// Altitude above mean sea level, m (wire: mm).
    pub alt_msl_m: f64,
    /// Ground speed, m/s (wire: cm/s, 0…655.34), `None` if unknown.
    pub ground_speed_mps: Option<f64>,
    /// Course over ground, degrees 0…360 (wire: cdeg), `None` if unknown.
    pub course_deg: Option<f64>,
    /// Satellites visible, `None` if unknown (wire 255).
    pub satellites: Option<u8>,
    /// Horizontal position uncertainty, m (wire: mm; 0 = unknown, so a known value is at
    /// least 1 mm).
    pub h_acc_m: Option<f64>,
    /// Vertical position uncertainty, m (wire: mm; as `h_acc_m`).
    pub v_acc_m: Option<f64>,
}

impl GpsRaw {
    /// The GPS_RAW_INT carrying it.
    pub(super) fn to_mavlink(self) -> MavMessage {
        MavMessage::GPS_RAW_INT(mc::GPS_RAW_INT_DATA {
            time_usec: self.time_usec,
            lat: deg_to_e7(self.lat_deg),
            lon: deg_to_e7(self.lon_deg),
            alt: m_to_mm(self.alt_msl_m),
            eph: u16::MAX,
            epv: u16::MAX,
            vel: match self.ground_speed_mps {
                Some(v) if v.is_finite() => (v * 100.0).round().clamp(0.0, 65534.0) as u16,
                _ => u16::MAX,
            },
            cog: course_to_cdeg(self.course_deg),
            fix_type: self.fix.to_mav(),
            satellites_visible: self.satellites.map_or(u8::MAX, |s| s.min(254)),
            alt_ellipsoid: 0,
            h_acc: acc_to_mm(self.h_acc_m),
            v_acc: acc_to_mm(self.v_acc_m),
            vel_acc: 0,
            hdg_acc: 0,
            yaw: 0,
        })
    }

    /// What a GPS_RAW_INT carries.
    pub(super) fn from_mavlink(g: &mc::GPS_RAW_INT_DATA) -> Self {
        GpsRaw {
            time_usec: g.time_usec,
            fix: GpsFix::from_mav(g.fix_type),
            lat_deg: e7_to_deg(g.lat),
            lon_deg: e7_to_deg(g.lon),
            alt_msl_m: mm_to_m(g.alt),
            ground_speed_mps: if g.vel == u16::MAX {
                None
            } else {
                Some(f64::from(g.vel) / 100.0)
            },
            course_deg: cdeg_to_course(g.cog),
            satellites: if g.satellites_visible == u8::MAX {
                None
            } else {
                Some(g.satellites_visible)
            },
            h_acc_m: mm_to_acc(g.h_acc),
            v_acc_m: mm_to_acc(g.v_acc),
        }
    }
}

/// Onboard position and velocity estimate (GLOBAL_POSITION_INT).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
pub struct GlobalPosition {
    /// Time since boot, ms.
    pub time_boot_ms: u32,
    /// Latitude, degrees (wire: degE7).
    pub lat_deg: f64,
    /// Longitude, degrees (wire: degE7).
    pub lon_deg: f64,
    /// Altitude above mean sea level, m (wire: mm).
    pub alt_msl_m: f64,
    /// Altitude above the home / launch point, m (wire: mm).
    pub alt_rel_m: f64,
    /// Velocity north, m/s (wire: cm/s, ±327.67).
    pub v_north_mps: f64,
    /// Velocity east, m/s (wire: cm/s).
    pub v_east_mps: f64,
    /// Velocity down, m/s (wire: cm/s).
    pub v_down_mps: f64,
    /// Heading, degrees 0…360 (wire: cdeg), `None` if unknown.
    pub heading_deg: Option<f64>,
}

impl GlobalPosition {
    /// The GLOBAL_POSITION_INT carrying it.
    pub(super) fn to_mavlink(self) -> MavMessage {
        MavMessage::GLOBAL_POSITION_INT(mc::GLOBAL_POSITION_INT_DATA {
            time_boot_ms: self.time_boot_ms,
            lat: deg_to_e7(self.lat_deg),
            lon: deg_to_e7(self.lon_deg),
            alt: m_to_mm(self.alt_msl_m),
            relative_alt: m_to_mm(self.alt_rel_m),
            vx: mps_to_cms_i16(self.v_north_mps),
            vy: mps_to_cms_i16(self.v_east_mps),
            vz: mps_to_cms_i16(self.v_down_mps),
            hdg: course_to_cdeg(self.heading_deg),
        })
    }

    /// What a GLOBAL_POSITION_INT carries.
    pub(super) fn from_mavlink(p: &mc::GLOBAL_POSITION_INT_DATA) -> Self {
        GlobalPosition {
            time_boot_ms: p.time_boot_ms,
            lat_deg: e7_to_deg(p.lat),
            lon_deg: e7_to_deg(p.lon),
            alt_msl_m: mm_to_m(p.alt),
            alt_rel_m: mm_to_m(p.relative_alt),
            v_north_mps: f64::from(p.vx) / 100.0,
            v_east_mps: f64::from(p.vy) / 100.0,
            v_down_mps: f64::from(p.vz) / 100.0,
            heading_deg: cdeg_to_course(p.hdg),
        }
    }
}

/// Attitude from the AHRS (ATTITUDE).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
pub struct Attitude {
    /// Time since boot, ms.
    pub time_boot_ms: u32,
    /// Roll, rad (wire f32).
    pub roll_rad: f64,
    /// Pitch, rad.
    pub pitch_rad: f64,
    /// Yaw, rad.
    pub yaw_rad: f64,
    /// Body roll rate, rad/s.
    pub roll_rate_radps: f64,
    /// Body pitch rate, rad/s.
    pub pitch_rate_radps: f64,
    /// Body yaw rate, rad/s.
    pub yaw_rate_radps: f64,
}

impl Attitude {
    /// The ATTITUDE carrying it.
    pub(super) fn to_mavlink(self) -> MavMessage {
        MavMessage::ATTITUDE(mc::ATTITUDE_DATA {
            time_boot_ms: self.time_boot_ms,
            roll: self.roll_rad as f32,
            pitch: self.pitch_rad as f32,
            yaw: self.yaw_rad as f32,
            rollspeed: self.roll_rate_radps as f32,
            pitchspeed: self.pitch_rate_radps as f32,
            yawspeed: self.yaw_rate_radps as f32,
        })
    }

    /// What a ATTITUDE carries.
    pub(super) fn from_mavlink(a: &mc::ATTITUDE_DATA) -> Self {
        Attitude {
            time_boot_ms: a.time_boot_ms,
            roll_rad: f64::from(a.roll),
            pitch_rad: f64::from(a.pitch),
            yaw_rad: f64::from(a.yaw),
            roll_rate_radps: f64::from(a.rollspeed),
            pitch_rate_radps: f64::from(a.pitchspeed),
            yaw_rate_radps: f64::from(a.yawspeed),
        }
    }
}

/// Pitot air data (SCALED_PRESSURE).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
pub struct AirData {
    /// Time since boot, ms.
    pub time_boot_ms: u32,
    /// Static (absolute) pressure, Pa (wire: hPa f32).
    pub abs_pressure_pa: f64,
    /// Pitot differential pressure, Pa (wire: hPa f32).
    pub diff_pressure_pa: f64,
    /// Temperature of the absolute-pressure sensor, °C (wire: cdegC).
    pub temperature_c: f64,
    /// Temperature of the differential-pressure sensor, °C (wire: cdegC, 0 = unknown, so a
    /// known 0.00 °C is sent as 0.01 °C as MAVLink asks).
    pub diff_temperature_c: Option<f64>,
}

impl AirData {
    /// The SCALED_PRESSURE carrying it.
    pub(super) fn to_mavlink(self) -> MavMessage {
        MavMessage::SCALED_PRESSURE(mc::SCALED_PRESSURE_DATA {
            time_boot_ms: self.time_boot_ms,
            press_abs: (self.abs_pressure_pa / 100.0) as f32,
            press_diff: (self.diff_pressure_pa / 100.0) as f32,
            temperature: c_to_cdeg(self.temperature_c),
            temperature_press_diff: match self.diff_temperature_c {
                Some(c) => match c_to_cdeg(c) {
                    0 => 1,
                    v => v,
                },
                None => 0,
            },
        })
    }

    /// What a SCALED_PRESSURE carries.
    pub(super) fn from_mavlink(d: &mc::SCALED_PRESSURE_DATA) -> Self {
        AirData {
            time_boot_ms: d.time_boot_ms,
            abs_pressure_pa: f64::from(d.press_abs) * 100.0,
            diff_pressure_pa: f64::from(d.press_diff) * 100.0,
            temperature_c: f64::from(d.temperature) / 100.0,
            diff_temperature_c: if d.temperature_press_diff == 0 {
                None
            } else {
                Some(f64::from(d.temperature_press_diff) / 100.0)
            },
        }
    }
}

/// Head-up display summary (VFR_HUD).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
pub struct Hud {
    /// Airspeed, m/s.
    pub airspeed_mps: f64,
    /// Ground speed, m/s.
    pub groundspeed_mps: f64,
    /// Heading, whole degrees 0…359 on the wire.
    pub heading_deg: f64,
    /// Climb rate, m/s (negative while descending).
    pub climb_mps: f64,
    /// Altitude MSL, m.
    pub alt_msl_m: f64,
}

impl Hud {
    /// The VFR_HUD carrying it.
    pub(super) fn to_mavlink(self) -> MavMessage {
        MavMessage::VFR_HUD(mc::VFR_HUD_DATA {
            airspeed: self.airspeed_mps as f32,
            groundspeed: self.groundspeed_mps as f32,
            alt: self.alt_msl_m as f32,
            climb: self.climb_mps as f32,
            heading: if self.heading_deg.is_finite() {
                (self.heading_deg.round() as i64).rem_euclid(360) as i16
            } else {
                0
            },
            throttle: 0,
        })
    }

    /// What a VFR_HUD carries.
    pub(super) fn from_mavlink(h: &mc::VFR_HUD_DATA) -> Self {
        Hud {
            airspeed_mps: f64::from(h.airspeed),
            groundspeed_mps: f64::from(h.groundspeed),
            heading_deg: f64::from(h.heading),
            climb_mps: f64::from(h.climb),
            alt_msl_m: f64::from(h.alt),
        }
    }
}

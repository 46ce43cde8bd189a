//! stx's telemetry as plain Rust values in SI units, and their exact mapping to MAVLink
//! common-dialect messages.
//!
//! The rest of stx (estimator display, dashboard, recorder) works with these types and never
//! with MAVLink's scaled integers (degE7, mm, cdeg, cdegC, hPa, cA, …). The mapping is
//! two-way: [`Telemetry::to_mavlink`] on the drone, [`Telemetry::from_mavlink`] on the
//! station; a value survives the round trip within the wire's quantisation, and a value read
//! from the wire survives the reverse trip exactly.
//!
//! | stx type | MAVLink message | notes |
//! |---|---|---|
//! | [`VehicleStatus`] | HEARTBEAT | `custom_mode = mode \| stage << 8 \| phase << 16` (codes from `stx_gnc::mission`), `base_mode = CUSTOM_MODE_ENABLED`, `type = MAV_TYPE_PARAFOIL` (exists in the dialect, 28), autopilot `GENERIC` |
//! | [`GpsRaw`] | GPS_RAW_INT | extensions carry h_acc / v_acc; `UINT16_MAX` / `255` / `0` = unknown |
//! | [`GlobalPosition`] | GLOBAL_POSITION_INT | onboard estimate; NED velocity in cm/s |
//! | [`Attitude`] | ATTITUDE | rad, rad/s |
//! | [`AirData`] | SCALED_PRESSURE | pitot: wire hPa ↔ Pa, cdegC ↔ °C |
//! | [`Hud`] | VFR_HUD | heading is whole degrees on the wire; throttle always 0 (no motor) |
//! | [`Actuators`] | SERVO_OUTPUT_RAW | servo1 main-line differential −1…+1 ↔ 1000…2000 µs (1500 neutral); servo2 right brake, servo3 left brake 0…1 ↔ 1000…2000 µs |
//! | [`SystemStatus`] | SYS_STATUS | battery voltage/current/remaining, load, comm drop rate, sensor bitmaps |
//! | [`BatteryStatus`] | BATTERY_STATUS | total voltage in cell 0, other cells `UINT16_MAX` (MAVLink's rule for an unknown cell split) |
//! | [`StatusText`] | STATUSTEXT | one chunk of ≤ 50 bytes; [`split_status_text`] and [`StatusTextAssembler`] handle longer text with `id`/`chunk_seq` |
//! | [`Wind`] | WIND_COV | NED m/s, 1-σ variability (the wire's `var_*` fields are standard deviations in m/s), altitude MSL |
//! | [`GuidanceStatus`] | NAV_CONTROLLER_OUTPUT | bearing to target, cross-track error, distance to target (m, saturates at 65 535), altitude error |
//! | [`PredictedLanding`] | POSITION_TARGET_GLOBAL_INT | see below |
//!
//! ## Why POSITION_TARGET_GLOBAL_INT for the predicted landing point
//! The common dialect has no message for a predicted touchdown point. We need one message
//! (so the point is atomic and `to_mavlink` stays one-to-one) with integer latitude and
//! longitude (degE7, 1 cm) and an MSL altitude:
//! - HOME_POSITION would move the home / return point in every generic ground station: unsafe.
//! - NAMED_VALUE_FLOAT triples carry f32 latitude/longitude (about 1.7 m steps at 180° of
//!   longitude) and need three messages re-assembled, which can arrive torn.
//! - LANDING_TARGET describes a sensor's view of a target relative to the vehicle.
//!
//! POSITION_TARGET_GLOBAL_INT carries degE7 latitude/longitude and an altitude in
//! `MAV_FRAME_GLOBAL` (MSL). We send it with every velocity, acceleration, yaw and yaw-rate
//! field marked ignored in `type_mask` (only the position is meaningful). For an unpowered
//! parafoil the "position target" generic tools show is where the vehicle is going to be
//! at the end of its descent, which is what the predicted landing point is. A frame other than
//! `MAV_FRAME_GLOBAL`, or a type mask with any position bit ignored, is not read as a
//! predicted landing point.

use mavlink::dialects::common as mc;
use mavlink::dialects::common::MavMessage;
use serde::{Deserialize, Serialize};
use stx_gnc::mission::{FlightMode, FlightStage, GuidancePhase};

fn deg_to_e7(deg: f64) -> i32 {
    (deg * 1e7).round() as i32
}
fn e7_to_deg(v: i32) -> f64 {
    f64::from(v) / 1e7
}
fn m_to_mm(m: f64) -> i32 {
    (m * 1000.0).round() as i32
}
fn mm_to_m(v: i32) -> f64 {
    f64::from(v) / 1000.0
}
fn nan_to_none(v: f32) -> Option<f64> {
    if v.is_nan() { None } else { Some(f64::from(v)) }
}
fn none_to_nan(v: Option<f64>) -> f32 {
    v.map_or(f32::NAN, |x| x as f32)
}
/// Degrees to centidegrees in 0..36000 (wrapping), `u16::MAX` for unknown.
fn course_to_cdeg(deg: Option<f64>) -> u16 {
    match deg {
        Some(d) if d.is_finite() => ((d * 100.0).round() as i64).rem_euclid(36000) as u16,
        _ => u16::MAX,
    }
}
fn cdeg_to_course(v: u16) -> Option<f64> {
    if v == u16::MAX {
        None
    } else {
        Some(f64::from(v) / 100.0)
    }
}

/// Onboard system state (HEARTBEAT `system_status`, MAV_STATE).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SystemState {
    Uninit,
    Boot,
    Calibrating,
    Standby,
    Active,
    Critical,
    Emergency,
    Poweroff,
    FlightTermination,
}

impl SystemState {
    fn to_mav(self) -> mc::MavState {
        use mc::MavState as S;
        match self {
            Self::Uninit => S::MAV_STATE_UNINIT,
            Self::Boot => S::MAV_STATE_BOOT,
            Self::Calibrating => S::MAV_STATE_CALIBRATING,
            Self::Standby => S::MAV_STATE_STANDBY,
            Self::Active => S::MAV_STATE_ACTIVE,
            Self::Critical => S::MAV_STATE_CRITICAL,
            Self::Emergency => S::MAV_STATE_EMERGENCY,
            Self::Poweroff => S::MAV_STATE_POWEROFF,
            Self::FlightTermination => S::MAV_STATE_FLIGHT_TERMINATION,
        }
    }
    fn from_mav(s: mc::MavState) -> Self {
        use mc::MavState as S;
        match s {
            S::MAV_STATE_UNINIT => Self::Uninit,
            S::MAV_STATE_BOOT => Self::Boot,
            S::MAV_STATE_CALIBRATING => Self::Calibrating,
            S::MAV_STATE_STANDBY => Self::Standby,
            S::MAV_STATE_ACTIVE => Self::Active,
            S::MAV_STATE_CRITICAL => Self::Critical,
            S::MAV_STATE_EMERGENCY => Self::Emergency,
            S::MAV_STATE_POWEROFF => Self::Poweroff,
            S::MAV_STATE_FLIGHT_TERMINATION => Self::FlightTermination,
        }
    }
}

/// Mode, flight stage and guidance phase of the drone (HEARTBEAT).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct VehicleStatus {
    /// Control mode the operator selected.
    pub mode: FlightMode,
    /// Where in the mission the vehicle is.
    pub stage: FlightStage,
    /// Where spiral-landing guidance is.
    pub phase: GuidancePhase,
    /// Onboard system state.
    pub state: SystemState,
}

impl VehicleStatus {
    /// `custom_mode` value: `mode | stage << 8 | phase << 16`.
    pub fn custom_mode(&self) -> u32 {
        u32::from(self.mode.code())
            | u32::from(self.stage.code()) << 8
            | u32::from(self.phase.code()) << 16
    }

    /// Unpacks a `custom_mode`; `None` if any code is unknown or the top byte is not zero.
    pub fn unpack_custom_mode(
        custom_mode: u32,
    ) -> Option<(FlightMode, FlightStage, GuidancePhase)> {
        let [mode, stage, phase, top] = custom_mode.to_le_bytes();
        if top != 0 {
            return None;
        }
        Some((
            FlightMode::from_code(mode)?,
            FlightStage::from_code(stage)?,
            GuidancePhase::from_code(phase)?,
        ))
    }
}

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
    fn to_mav(self) -> mc::GpsFixType {
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
    fn from_mav(g: mc::GpsFixType) -> Self {
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

fn acc_to_mm(v: Option<f64>) -> u32 {
    match v {
        Some(m) if m.is_finite() => ((m * 1000.0).round() as u32).max(1),
        _ => 0,
    }
}
fn mm_to_acc(v: u32) -> Option<f64> {
    if v == 0 {
        None
    } else {
        Some(f64::from(v) / 1000.0)
    }
}

/// Onboard position and velocity estimate (GLOBAL_POSITION_INT).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
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

fn mps_to_cms_i16(v: f64) -> i16 {
    (v * 100.0).round() as i16
}

/// Attitude from the AHRS (ATTITUDE).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
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

/// Pitot air data (SCALED_PRESSURE).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
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

fn c_to_cdeg(c: f64) -> i16 {
    (c * 100.0).round() as i16
}

/// Head-up display summary (VFR_HUD).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
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

/// The three actuators (SERVO_OUTPUT_RAW).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Actuators {
    /// Time, µs (wraps after ~71 min, as on the wire).
    pub time_usec: u32,
    /// Main-line differential, −1 (full left) … +1 (full right); servo1, 1500 µs neutral.
    pub main_line: f64,
    /// Right brake deflection 0 (up) … 1 (full); servo2, 1000…2000 µs.
    pub brake_right: f64,
    /// Left brake deflection 0 … 1; servo3, 1000…2000 µs.
    pub brake_left: f64,
}

/// Normalised −1…1 to 1000…2000 µs, 1500 neutral.
pub fn signed_to_pwm_us(v: f64) -> u16 {
    let v = if v.is_nan() { 0.0 } else { v.clamp(-1.0, 1.0) };
    (1500.0 + 500.0 * v).round() as u16
}
/// 1000…2000 µs to −1…1 (clamped).
pub fn pwm_us_to_signed(us: u16) -> f64 {
    ((f64::from(us) - 1500.0) / 500.0).clamp(-1.0, 1.0)
}
/// Normalised 0…1 to 1000…2000 µs.
pub fn unit_to_pwm_us(v: f64) -> u16 {
    let v = if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) };
    (1000.0 + 1000.0 * v).round() as u16
}
/// 1000…2000 µs to 0…1 (clamped).
pub fn pwm_us_to_unit(us: u16) -> f64 {
    ((f64::from(us) - 1000.0) / 1000.0).clamp(0.0, 1.0)
}

/// Onboard system health and main battery (SYS_STATUS).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SystemStatus {
    /// Battery voltage, V (wire: mV; `None` = UINT16_MAX).
    pub battery_voltage_v: Option<f64>,
    /// Battery current, A (wire: cA; `None` = −1).
    pub battery_current_a: Option<f64>,
    /// Remaining battery, % 0…100 (`None` = −1).
    pub battery_remaining_pct: Option<u8>,
    /// Main-loop load, % (wire: d%).
    pub load_pct: f64,
    /// Communication drop rate, % (wire: c%).
    pub comm_drop_rate_pct: f64,
    /// Communication errors.
    pub comm_errors: u16,
    /// MAV_SYS_STATUS_SENSOR bitmap: present.
    pub sensors_present: u32,
    /// MAV_SYS_STATUS_SENSOR bitmap: enabled.
    pub sensors_enabled: u32,
    /// MAV_SYS_STATUS_SENSOR bitmap: healthy.
    pub sensors_health: u32,
}

fn volts_to_mv(v: Option<f64>) -> u16 {
    match v {
        Some(v) if v.is_finite() => ((v * 1000.0).round().clamp(0.0, 65534.0)) as u16,
        _ => u16::MAX,
    }
}
fn mv_to_volts(v: u16) -> Option<f64> {
    if v == u16::MAX {
        None
    } else {
        Some(f64::from(v) / 1000.0)
    }
}
fn amps_to_ca(a: Option<f64>) -> i16 {
    match a {
        Some(a) if a.is_finite() => {
            let ca = (a * 100.0).round() as i16;
            // −1 means "not measured"; a measured −0.01 A is sent as −0.02 A.
            if ca == -1 { -2 } else { ca }
        }
        _ => -1,
    }
}
fn ca_to_amps(v: i16) -> Option<f64> {
    if v == -1 {
        None
    } else {
        Some(f64::from(v) / 100.0)
    }
}
fn pct_to_i8(p: Option<u8>) -> i8 {
    p.map_or(-1, |p| p.min(100) as i8)
}
fn i8_to_pct(v: i8) -> Option<u8> {
    u8::try_from(v).ok().map(|v| v.min(100))
}

/// One battery (BATTERY_STATUS).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct BatteryStatus {
    /// Battery id.
    pub id: u8,
    /// Total voltage, V (wire: mV in cell 0, ≤ 65.534 V).
    pub voltage_v: Option<f64>,
    /// Current, A (wire: cA, −1 = unknown).
    pub current_a: Option<f64>,
    /// Charge consumed, mAh (−1 = unknown).
    pub consumed_mah: Option<i32>,
    /// Remaining, % (−1 = unknown).
    pub remaining_pct: Option<u8>,
    /// Temperature, °C (wire: cdegC, INT16_MAX = unknown).
    pub temperature_c: Option<f64>,
}

/// MAVLink severity (MAV_SEVERITY, RFC 5424).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Severity {
    Emergency,
    Alert,
    Critical,
    Error,
    Warning,
    Notice,
    Info,
    Debug,
}

impl Severity {
    fn to_mav(self) -> mc::MavSeverity {
        use mc::MavSeverity as S;
        match self {
            Self::Emergency => S::MAV_SEVERITY_EMERGENCY,
            Self::Alert => S::MAV_SEVERITY_ALERT,
            Self::Critical => S::MAV_SEVERITY_CRITICAL,
            Self::Error => S::MAV_SEVERITY_ERROR,
            Self::Warning => S::MAV_SEVERITY_WARNING,
            Self::Notice => S::MAV_SEVERITY_NOTICE,
            Self::Info => S::MAV_SEVERITY_INFO,
            Self::Debug => S::MAV_SEVERITY_DEBUG,
        }
    }
    fn from_mav(s: mc::MavSeverity) -> Self {
        use mc::MavSeverity as S;
        match s {
            S::MAV_SEVERITY_EMERGENCY => Self::Emergency,
            S::MAV_SEVERITY_ALERT => Self::Alert,
            S::MAV_SEVERITY_CRITICAL => Self::Critical,
            S::MAV_SEVERITY_ERROR => Self::Error,
            S::MAV_SEVERITY_WARNING => Self::Warning,
            S::MAV_SEVERITY_NOTICE => Self::Notice,
            S::MAV_SEVERITY_INFO => Self::Info,
            S::MAV_SEVERITY_DEBUG => Self::Debug,
        }
    }
}

/// Longest text in one STATUSTEXT, bytes.
pub const STATUSTEXT_LEN: usize = 50;

/// One STATUSTEXT chunk. Text is kept as bytes because a long text is split at byte
/// boundaries (a shorter chunk would mean "last chunk" to the receiver), which may cut a UTF-8
/// character in two; [`StatusTextAssembler`] joins the bytes before decoding them.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct StatusText {
    /// Severity.
    pub severity: Severity,
    /// Up to 50 bytes of UTF-8 text (without the terminating NUL).
    pub text: Vec<u8>,
    /// Id shared by the chunks of one long text; 0 for a single-chunk text.
    pub id: u16,
    /// Index of this chunk, from 0.
    pub chunk_seq: u8,
}

impl StatusText {
    /// A single-chunk text (truncated to 50 bytes at a character boundary).
    pub fn single(severity: Severity, text: &str) -> Self {
        let mut end = text.len().min(STATUSTEXT_LEN);
        while !text.is_char_boundary(end) {
            end -= 1;
        }
        Self {
            severity,
            text: text.as_bytes().get(..end).unwrap_or(&[]).to_vec(),
            id: 0,
            chunk_seq: 0,
        }
    }

    /// The chunk's text, with invalid UTF-8 replaced.
    pub fn text_lossy(&self) -> String {
        String::from_utf8_lossy(&self.text).into_owned()
    }
}

/// Splits `text` into STATUSTEXT chunks. Text of at most 50 bytes gives one chunk with id 0;
/// longer text gives chunks of 50 bytes with the given non-zero `id` and `chunk_seq` 0, 1, …,
/// the last shorter than 50 bytes (an empty one is added when the length is a multiple of 50,
/// since a NUL in the text marks the last chunk). At most 256 chunks (12 800 bytes); longer
/// text is cut.
pub fn split_status_text(severity: Severity, text: &str, id: u16) -> Vec<StatusText> {
    let bytes = text.as_bytes();
    if bytes.len() <= STATUSTEXT_LEN {
        return vec![StatusText {
            severity,
            text: bytes.to_vec(),
            id: 0,
            chunk_seq: 0,
        }];
    }
    let id = id.max(1);
    let mut chunks: Vec<StatusText> = bytes
        .chunks(STATUSTEXT_LEN)
        .take(256)
        .enumerate()
        .map(|(i, c)| StatusText {
            severity,
            text: c.to_vec(),
            id,
            chunk_seq: i as u8,
        })
        .collect();
    if chunks
        .last()
        .is_some_and(|c| c.text.len() == STATUSTEXT_LEN)
        && chunks.len() < 256
    {
        let seq = chunks.len() as u8;
        chunks.push(StatusText {
            severity,
            text: Vec::new(),
            id,
            chunk_seq: seq,
        });
    }
    chunks
}

/// A text being re-assembled: ((system id, component id, text id), severity, bytes so far,
/// next expected `chunk_seq`).
type PendingText = ((u8, u8, u16), Severity, Vec<u8>, u8);

/// Re-assembles chunked STATUSTEXTs per (sender, id). Incomplete texts are dropped when a new
/// text with the same id starts or when more than [`StatusTextAssembler::MAX_PENDING`] are
/// pending; both cases are counted in `dropped`.
#[derive(Debug, Default)]
pub struct StatusTextAssembler {
    pending: Vec<PendingText>,
    /// Incomplete texts dropped.
    pub dropped: u64,
}

impl StatusTextAssembler {
    /// Most incomplete texts kept at once.
    pub const MAX_PENDING: usize = 16;

    /// Feeds one chunk from `(system_id, component_id)`; returns the whole text when complete.
    pub fn push(
        &mut self,
        system_id: u8,
        component_id: u8,
        chunk: &StatusText,
    ) -> Option<(Severity, String)> {
        if chunk.id == 0 {
            return Some((chunk.severity, chunk.text_lossy()));
        }
        let key = (system_id, component_id, chunk.id);
        let last = chunk.text.len() < STATUSTEXT_LEN;
        let idx = self.pending.iter().position(|p| p.0 == key);
        match (idx, chunk.chunk_seq) {
            (Some(i), seq) if seq != 0 => {
                let entry = self.pending.get_mut(i)?;
                if entry.3 != seq {
                    self.pending.remove(i);
                    self.dropped += 1;
                    return None;
                }
                entry.2.extend_from_slice(&chunk.text);
                entry.3 = seq.wrapping_add(1);
                if last || seq == 255 {
                    let (_, sev, text, _) = self.pending.remove(i);
                    return Some((sev, String::from_utf8_lossy(&text).into_owned()));
                }
                None
            }
            (None, seq) if seq != 0 => {
                self.dropped += 1;
                None
            }
            (existing, _) => {
                if let Some(i) = existing {
                    self.pending.remove(i);
                    self.dropped += 1;
                }
                if last {
                    return Some((chunk.severity, chunk.text_lossy()));
                }
                if self.pending.len() >= Self::MAX_PENDING {
                    self.pending.remove(0);
                    self.dropped += 1;
                }
                self.pending
                    .push((key, chunk.severity, chunk.text.clone(), 1));
                None
            }
        }
    }
}

/// Onboard wind estimate (WIND_COV).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Wind {
    /// Time, µs.
    pub time_usec: u64,
    /// Wind towards north, m/s (NED), `None` if unknown.
    pub wind_north_mps: Option<f64>,
    /// Wind towards east, m/s.
    pub wind_east_mps: Option<f64>,
    /// Wind down, m/s.
    pub wind_down_mps: Option<f64>,
    /// Horizontal variability, 1-σ m/s (wire `var_horiz`).
    pub var_horiz_mps: Option<f64>,
    /// Vertical variability, 1-σ m/s (wire `var_vert`).
    pub var_vert_mps: Option<f64>,
    /// Altitude MSL of the estimate, m.
    pub alt_msl_m: Option<f64>,
    /// Horizontal speed accuracy, 1-σ m/s (0 = unknown).
    pub horiz_accuracy_mps: f64,
    /// Vertical speed accuracy, 1-σ m/s (0 = unknown).
    pub vert_accuracy_mps: f64,
}

/// Guidance state (NAV_CONTROLLER_OUTPUT).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct GuidanceStatus {
    /// Roll the controller asks for, degrees.
    pub desired_roll_deg: f64,
    /// Heading the controller asks for, whole degrees.
    pub desired_heading_deg: f64,
    /// Bearing from the vehicle to the target, whole degrees.
    pub bearing_to_target_deg: f64,
    /// Distance to the target, whole metres 0…65 535 (saturates).
    pub distance_to_target_m: f64,
    /// Altitude error (desired − actual), m.
    pub alt_error_m: f64,
    /// Cross-track error, m (positive right of the track).
    pub xtrack_error_m: f64,
}

/// The onboard prediction of the touchdown point (POSITION_TARGET_GLOBAL_INT; see the module
/// documentation).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PredictedLanding {
    /// Time since boot, ms.
    pub time_boot_ms: u32,
    /// Latitude, degrees (wire: degE7).
    pub lat_deg: f64,
    /// Longitude, degrees (wire: degE7).
    pub lon_deg: f64,
    /// Altitude MSL of the touchdown point, m (wire: f32).
    pub alt_msl_m: f64,
}

/// Type mask of the predicted-landing POSITION_TARGET_GLOBAL_INT: everything but position
/// ignored.
fn predicted_landing_mask() -> mc::PositionTargetTypemask {
    use mc::PositionTargetTypemask as M;
    M::POSITION_TARGET_TYPEMASK_VX_IGNORE
        | M::POSITION_TARGET_TYPEMASK_VY_IGNORE
        | M::POSITION_TARGET_TYPEMASK_VZ_IGNORE
        | M::POSITION_TARGET_TYPEMASK_AX_IGNORE
        | M::POSITION_TARGET_TYPEMASK_AY_IGNORE
        | M::POSITION_TARGET_TYPEMASK_AZ_IGNORE
        | M::POSITION_TARGET_TYPEMASK_YAW_IGNORE
        | M::POSITION_TARGET_TYPEMASK_YAW_RATE_IGNORE
}

/// Every telemetry item the drone sends.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Telemetry {
    Status(VehicleStatus),
    GpsRaw(GpsRaw),
    Position(GlobalPosition),
    Attitude(Attitude),
    AirData(AirData),
    Hud(Hud),
    Actuators(Actuators),
    System(SystemStatus),
    Battery(BatteryStatus),
    StatusText(StatusText),
    Wind(Wind),
    Guidance(GuidanceStatus),
    PredictedLanding(PredictedLanding),
}

impl Telemetry {
    /// Name of the MAVLink message this maps to.
    pub fn message_name(&self) -> &'static str {
        match self {
            Self::Status(_) => "HEARTBEAT",
            Self::GpsRaw(_) => "GPS_RAW_INT",
            Self::Position(_) => "GLOBAL_POSITION_INT",
            Self::Attitude(_) => "ATTITUDE",
            Self::AirData(_) => "SCALED_PRESSURE",
            Self::Hud(_) => "VFR_HUD",
            Self::Actuators(_) => "SERVO_OUTPUT_RAW",
            Self::System(_) => "SYS_STATUS",
            Self::Battery(_) => "BATTERY_STATUS",
            Self::StatusText(_) => "STATUSTEXT",
            Self::Wind(_) => "WIND_COV",
            Self::Guidance(_) => "NAV_CONTROLLER_OUTPUT",
            Self::PredictedLanding(_) => "POSITION_TARGET_GLOBAL_INT",
        }
    }

    /// The MAVLink message carrying this item.
    pub fn to_mavlink(&self) -> MavMessage {
        match self {
            Self::Status(s) => MavMessage::HEARTBEAT(mc::HEARTBEAT_DATA {
                custom_mode: s.custom_mode(),
                mavtype: mc::MavType::MAV_TYPE_PARAFOIL,
                autopilot: mc::MavAutopilot::MAV_AUTOPILOT_GENERIC,
                base_mode: mc::MavModeFlag::MAV_MODE_FLAG_CUSTOM_MODE_ENABLED,
                system_status: s.state.to_mav(),
                mavlink_version: 3,
            }),
            Self::GpsRaw(g) => MavMessage::GPS_RAW_INT(mc::GPS_RAW_INT_DATA {
                time_usec: g.time_usec,
                lat: deg_to_e7(g.lat_deg),
                lon: deg_to_e7(g.lon_deg),
                alt: m_to_mm(g.alt_msl_m),
                eph: u16::MAX,
                epv: u16::MAX,
                vel: match g.ground_speed_mps {
                    Some(v) if v.is_finite() => (v * 100.0).round().clamp(0.0, 65534.0) as u16,
                    _ => u16::MAX,
                },
                cog: course_to_cdeg(g.course_deg),
                fix_type: g.fix.to_mav(),
                satellites_visible: g.satellites.map_or(u8::MAX, |s| s.min(254)),
                alt_ellipsoid: 0,
                h_acc: acc_to_mm(g.h_acc_m),
                v_acc: acc_to_mm(g.v_acc_m),
                vel_acc: 0,
                hdg_acc: 0,
                yaw: 0,
            }),
            Self::Position(p) => MavMessage::GLOBAL_POSITION_INT(mc::GLOBAL_POSITION_INT_DATA {
                time_boot_ms: p.time_boot_ms,
                lat: deg_to_e7(p.lat_deg),
                lon: deg_to_e7(p.lon_deg),
                alt: m_to_mm(p.alt_msl_m),
                relative_alt: m_to_mm(p.alt_rel_m),
                vx: mps_to_cms_i16(p.v_north_mps),
                vy: mps_to_cms_i16(p.v_east_mps),
                vz: mps_to_cms_i16(p.v_down_mps),
                hdg: course_to_cdeg(p.heading_deg),
            }),
            Self::Attitude(a) => MavMessage::ATTITUDE(mc::ATTITUDE_DATA {
                time_boot_ms: a.time_boot_ms,
                roll: a.roll_rad as f32,
                pitch: a.pitch_rad as f32,
                yaw: a.yaw_rad as f32,
                rollspeed: a.roll_rate_radps as f32,
                pitchspeed: a.pitch_rate_radps as f32,
                yawspeed: a.yaw_rate_radps as f32,
            }),
            Self::AirData(d) => MavMessage::SCALED_PRESSURE(mc::SCALED_PRESSURE_DATA {
                time_boot_ms: d.time_boot_ms,
                press_abs: (d.abs_pressure_pa / 100.0) as f32,
                press_diff: (d.diff_pressure_pa / 100.0) as f32,
                temperature: c_to_cdeg(d.temperature_c),
                temperature_press_diff: match d.diff_temperature_c {
                    Some(c) => match c_to_cdeg(c) {
                        0 => 1,
                        v => v,
                    },
                    None => 0,
                },
            }),
            Self::Hud(h) => MavMessage::VFR_HUD(mc::VFR_HUD_DATA {
                airspeed: h.airspeed_mps as f32,
                groundspeed: h.groundspeed_mps as f32,
                alt: h.alt_msl_m as f32,
                climb: h.climb_mps as f32,
                heading: if h.heading_deg.is_finite() {
                    (h.heading_deg.round() as i64).rem_euclid(360) as i16
                } else {
                    0
                },
                throttle: 0,
            }),
            Self::Actuators(a) => MavMessage::SERVO_OUTPUT_RAW(mc::SERVO_OUTPUT_RAW_DATA {
                time_usec: a.time_usec,
                servo1_raw: signed_to_pwm_us(a.main_line),
                servo2_raw: unit_to_pwm_us(a.brake_right),
                servo3_raw: unit_to_pwm_us(a.brake_left),
                ..Default::default()
            }),
            Self::System(s) => MavMessage::SYS_STATUS(mc::SYS_STATUS_DATA {
                onboard_control_sensors_present: mc::MavSysStatusSensor::from_bits_retain(
                    s.sensors_present,
                ),
                onboard_control_sensors_enabled: mc::MavSysStatusSensor::from_bits_retain(
                    s.sensors_enabled,
                ),
                onboard_control_sensors_health: mc::MavSysStatusSensor::from_bits_retain(
                    s.sensors_health,
                ),
                load: (s.load_pct * 10.0).round().clamp(0.0, 65535.0) as u16,
                voltage_battery: volts_to_mv(s.battery_voltage_v),
                current_battery: amps_to_ca(s.battery_current_a),
                drop_rate_comm: (s.comm_drop_rate_pct * 100.0).round().clamp(0.0, 10000.0) as u16,
                errors_comm: s.comm_errors,
                errors_count1: 0,
                errors_count2: 0,
                errors_count3: 0,
                errors_count4: 0,
                battery_remaining: pct_to_i8(s.battery_remaining_pct),
                onboard_control_sensors_present_extended: mc::MavSysStatusSensorExtended::empty(),
                onboard_control_sensors_enabled_extended: mc::MavSysStatusSensorExtended::empty(),
                onboard_control_sensors_health_extended: mc::MavSysStatusSensorExtended::empty(),
            }),
            Self::Battery(b) => {
                let mut voltages = [u16::MAX; 10];
                voltages[0] = volts_to_mv(b.voltage_v);
                MavMessage::BATTERY_STATUS(mc::BATTERY_STATUS_DATA {
                    current_consumed: b.consumed_mah.map_or(-1, |c| c.max(0)),
                    energy_consumed: -1,
                    temperature: b
                        .temperature_c
                        .map_or(i16::MAX, |c| c_to_cdeg(c).min(i16::MAX - 1)),
                    voltages,
                    current_battery: amps_to_ca(b.current_a),
                    id: b.id,
                    battery_function: mc::MavBatteryFunction::MAV_BATTERY_FUNCTION_UNKNOWN,
                    mavtype: mc::MavBatteryType::MAV_BATTERY_TYPE_UNKNOWN,
                    battery_remaining: pct_to_i8(b.remaining_pct),
                    time_remaining: 0,
                    charge_state: mc::MavBatteryChargeState::MAV_BATTERY_CHARGE_STATE_UNDEFINED,
                    voltages_ext: [0; 4],
                    mode: mc::MavBatteryMode::MAV_BATTERY_MODE_UNKNOWN,
                    fault_bitmask: mc::MavBatteryFault::empty(),
                })
            }
            Self::StatusText(t) => {
                let mut text = [0_u8; STATUSTEXT_LEN];
                let n = t.text.len().min(STATUSTEXT_LEN);
                text[..n].copy_from_slice(t.text.get(..n).unwrap_or(&[]));
                MavMessage::STATUSTEXT(mc::STATUSTEXT_DATA {
                    severity: t.severity.to_mav(),
                    text: text.into(),
                    id: t.id,
                    chunk_seq: t.chunk_seq,
                })
            }
            Self::Wind(w) => MavMessage::WIND_COV(mc::WIND_COV_DATA {
                time_usec: w.time_usec,
                wind_x: none_to_nan(w.wind_north_mps),
                wind_y: none_to_nan(w.wind_east_mps),
                wind_z: none_to_nan(w.wind_down_mps),
                var_horiz: none_to_nan(w.var_horiz_mps),
                var_vert: none_to_nan(w.var_vert_mps),
                wind_alt: none_to_nan(w.alt_msl_m),
                horiz_accuracy: w.horiz_accuracy_mps as f32,
                vert_accuracy: w.vert_accuracy_mps as f32,
            }),
            Self::Guidance(g) => {
                MavMessage::NAV_CONTROLLER_OUTPUT(mc::NAV_CONTROLLER_OUTPUT_DATA {
                    nav_roll: g.desired_roll_deg as f32,
                    nav_pitch: 0.0,
                    alt_error: g.alt_error_m as f32,
                    aspd_error: 0.0,
                    xtrack_error: g.xtrack_error_m as f32,
                    nav_bearing: g.desired_heading_deg.round() as i16,
                    target_bearing: g.bearing_to_target_deg.round() as i16,
                    wp_dist: g.distance_to_target_m.round() as u16,
                })
            }
            Self::PredictedLanding(p) => {
                MavMessage::POSITION_TARGET_GLOBAL_INT(mc::POSITION_TARGET_GLOBAL_INT_DATA {
                    time_boot_ms: p.time_boot_ms,
                    lat_int: deg_to_e7(p.lat_deg),
                    lon_int: deg_to_e7(p.lon_deg),
                    alt: p.alt_msl_m as f32,
                    vx: 0.0,
                    vy: 0.0,
                    vz: 0.0,
                    afx: 0.0,
                    afy: 0.0,
                    afz: 0.0,
                    yaw: 0.0,
                    yaw_rate: 0.0,
                    type_mask: predicted_landing_mask(),
                    coordinate_frame: mc::MavFrame::MAV_FRAME_GLOBAL,
                })
            }
        }
    }

    /// The telemetry item a MAVLink message carries, `None` for messages that are not stx
    /// telemetry (including heartbeats of other vehicle types or with unknown stx codes).
    pub fn from_mavlink(msg: &MavMessage) -> Option<Telemetry> {
        Some(match msg {
            MavMessage::HEARTBEAT(h) => {
                if h.mavtype != mc::MavType::MAV_TYPE_PARAFOIL
                    || !h
                        .base_mode
                        .contains(mc::MavModeFlag::MAV_MODE_FLAG_CUSTOM_MODE_ENABLED)
                {
                    return None;
                }
                let (mode, stage, phase) = VehicleStatus::unpack_custom_mode(h.custom_mode)?;
                Self::Status(VehicleStatus {
                    mode,
                    stage,
                    phase,
                    state: SystemState::from_mav(h.system_status),
                })
            }
            MavMessage::GPS_RAW_INT(g) => Self::GpsRaw(GpsRaw {
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
            }),
            MavMessage::GLOBAL_POSITION_INT(p) => Self::Position(GlobalPosition {
                time_boot_ms: p.time_boot_ms,
                lat_deg: e7_to_deg(p.lat),
                lon_deg: e7_to_deg(p.lon),
                alt_msl_m: mm_to_m(p.alt),
                alt_rel_m: mm_to_m(p.relative_alt),
                v_north_mps: f64::from(p.vx) / 100.0,
                v_east_mps: f64::from(p.vy) / 100.0,
                v_down_mps: f64::from(p.vz) / 100.0,
                heading_deg: cdeg_to_course(p.hdg),
            }),
            MavMessage::ATTITUDE(a) => Self::Attitude(Attitude {
                time_boot_ms: a.time_boot_ms,
                roll_rad: f64::from(a.roll),
                pitch_rad: f64::from(a.pitch),
                yaw_rad: f64::from(a.yaw),
                roll_rate_radps: f64::from(a.rollspeed),
                pitch_rate_radps: f64::from(a.pitchspeed),
                yaw_rate_radps: f64::from(a.yawspeed),
            }),
            MavMessage::SCALED_PRESSURE(d) => Self::AirData(AirData {
                time_boot_ms: d.time_boot_ms,
                abs_pressure_pa: f64::from(d.press_abs) * 100.0,
                diff_pressure_pa: f64::from(d.press_diff) * 100.0,
                temperature_c: f64::from(d.temperature) / 100.0,
                diff_temperature_c: if d.temperature_press_diff == 0 {
                    None
                } else {
                    Some(f64::from(d.temperature_press_diff) / 100.0)
                },
            }),
            MavMessage::VFR_HUD(h) => Self::Hud(Hud {
                airspeed_mps: f64::from(h.airspeed),
                groundspeed_mps: f64::from(h.groundspeed),
                heading_deg: f64::from(h.heading),
                climb_mps: f64::from(h.climb),
                alt_msl_m: f64::from(h.alt),
            }),
            MavMessage::SERVO_OUTPUT_RAW(s) => Self::Actuators(Actuators {
                time_usec: s.time_usec,
                main_line: pwm_us_to_signed(s.servo1_raw),
                brake_right: pwm_us_to_unit(s.servo2_raw),
                brake_left: pwm_us_to_unit(s.servo3_raw),
            }),
            MavMessage::SYS_STATUS(s) => Self::System(SystemStatus {
                battery_voltage_v: mv_to_volts(s.voltage_battery),
                battery_current_a: ca_to_amps(s.current_battery),
                battery_remaining_pct: i8_to_pct(s.battery_remaining),
                load_pct: f64::from(s.load) / 10.0,
                comm_drop_rate_pct: f64::from(s.drop_rate_comm) / 100.0,
                comm_errors: s.errors_comm,
                sensors_present: s.onboard_control_sensors_present.bits(),
                sensors_enabled: s.onboard_control_sensors_enabled.bits(),
                sensors_health: s.onboard_control_sensors_health.bits(),
            }),
            MavMessage::BATTERY_STATUS(b) => Self::Battery(BatteryStatus {
                id: b.id,
                voltage_v: mv_to_volts(b.voltages[0]),
                current_a: ca_to_amps(b.current_battery),
                consumed_mah: if b.current_consumed < 0 {
                    None
                } else {
                    Some(b.current_consumed)
                },
                remaining_pct: i8_to_pct(b.battery_remaining),
                temperature_c: if b.temperature == i16::MAX {
                    None
                } else {
                    Some(f64::from(b.temperature) / 100.0)
                },
            }),
            MavMessage::STATUSTEXT(t) => {
                let raw: &[u8] = &t.text[..];
                let end = raw.iter().position(|&b| b == 0).unwrap_or(raw.len());
                Self::StatusText(StatusText {
                    severity: Severity::from_mav(t.severity),
                    text: raw.get(..end).unwrap_or(&[]).to_vec(),
                    id: t.id,
                    chunk_seq: t.chunk_seq,
                })
            }
            MavMessage::WIND_COV(w) => Self::Wind(Wind {
                time_usec: w.time_usec,
                wind_north_mps: nan_to_none(w.wind_x),
                wind_east_mps: nan_to_none(w.wind_y),
                wind_down_mps: nan_to_none(w.wind_z),
                var_horiz_mps: nan_to_none(w.var_horiz),
                var_vert_mps: nan_to_none(w.var_vert),
                alt_msl_m: nan_to_none(w.wind_alt),
                horiz_accuracy_mps: f64::from(w.horiz_accuracy),
                vert_accuracy_mps: f64::from(w.vert_accuracy),
            }),
            MavMessage::NAV_CONTROLLER_OUTPUT(n) => Self::Guidance(GuidanceStatus {
                desired_roll_deg: f64::from(n.nav_roll),
                desired_heading_deg: f64::from(n.nav_bearing),
                bearing_to_target_deg: f64::from(n.target_bearing),
                distance_to_target_m: f64::from(n.wp_dist),
                alt_error_m: f64::from(n.alt_error),
                xtrack_error_m: f64::from(n.xtrack_error),
            }),
            MavMessage::POSITION_TARGET_GLOBAL_INT(p) => {
                use mc::PositionTargetTypemask as M;
                let position_ignored = M::POSITION_TARGET_TYPEMASK_X_IGNORE
                    | M::POSITION_TARGET_TYPEMASK_Y_IGNORE
                    | M::POSITION_TARGET_TYPEMASK_Z_IGNORE;
                if p.coordinate_frame != mc::MavFrame::MAV_FRAME_GLOBAL
                    || p.type_mask.intersects(position_ignored)
                {
                    return None;
                }
                Self::PredictedLanding(PredictedLanding {
                    time_boot_ms: p.time_boot_ms,
                    lat_deg: e7_to_deg(p.lat_int),
                    lon_deg: e7_to_deg(p.lon_int),
                    alt_msl_m: f64::from(p.alt),
                })
            }
            _ => return None,
        })
    }
}

#[cfg(test)]
mod tests;

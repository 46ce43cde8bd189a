//! SI units to MAVLink's scaled integers and back (degE7, mm, cm/s, cdeg, cdegC, mV, cA, %),
//! with the wire's "unknown" values (`UINT16_MAX`, −1, 0, NaN) as `None`.

pub(super) fn deg_to_e7(deg: f64) -> i32 {
    (deg * 1e7).round() as i32
}
pub(super) fn e7_to_deg(v: i32) -> f64 {
    f64::from(v) / 1e7
}
pub(super) fn m_to_mm(m: f64) -> i32 {
    (m * 1000.0).round() as i32
}
pub(super) fn mm_to_m(v: i32) -> f64 {
    f64::from(v) / 1000.0
}
pub(super) fn nan_to_none(v: f32) -> Option<f64> {
    if v.is_nan() { None } else { Some(f64::from(v)) }
}
pub(super) fn none_to_nan(v: Option<f64>) -> f32 {
    v.map_or(f32::NAN, |x| x as f32)
}
/// Degrees to centidegrees in 0..36000 (wrapping), `u16::MAX` for unknown.
pub(super) fn course_to_cdeg(deg: Option<f64>) -> u16 {
    match deg {
        Some(d) if d.is_finite() => ((d * 100.0).round() as i64).rem_euclid(36000) as u16,
        _ => u16::MAX,
    }
}
pub(super) fn cdeg_to_course(v: u16) -> Option<f64> {
    if v == u16::MAX {
        None
    } else {
        Some(f64::from(v) / 100.0)
    }
}

pub(super) fn acc_to_mm(v: Option<f64>) -> u32 {
    match v {
        Some(m) if m.is_finite() => ((m * 1000.0).round() as u32).max(1),
        _ => 0,
    }
}
pub(super) fn mm_to_acc(v: u32) -> Option<f64> {
    if v == 0 {
        None
    } else {
        Some(f64::from(v) / 1000.0)
    }
}

pub(super) fn mps_to_cms_i16(v: f64) -> i16 {
    (v * 100.0).round() as i16
}

pub(super) fn c_to_cdeg(c: f64) -> i16 {
    (c * 100.0).round() as i16
}

pub(super) fn volts_to_mv(v: Option<f64>) -> u16 {
    match v {
        Some(v) if v.is_finite() => ((v * 1000.0).round().clamp(0.0, 65534.0)) as u16,
        _ => u16::MAX,
    }
}
pub(super) fn mv_to_volts(v: u16) -> Option<f64> {
    if v == u16::MAX {
        None
    } else {
        Some(f64::from(v) / 1000.0)
    }
}
pub(super) fn amps_to_ca(a: Option<f64>) -> i16 {
    match a {
        Some(a) if a.is_finite() => {
            let ca = (a * 100.0).round() as i16;
            // −1 means "not measured"; a measured −0.01 A is sent as −0.02 A.
            if ca == -1 { -2 } else { ca }
        }
        _ => -1,
    }
}
pub(super) fn ca_to_amps(v: i16) -> Option<f64> {
    if v == -1 {
        None
    } else {
        Some(f64::from(v) / 100.0)
    }
}
pub(super) fn pct_to_i8(p: Option<u8>) -> i8 {
    p.map_or(-1, |p| p.min(100) as i8)
}
pub(super) fn i8_to_pct(v: i8) -> Option<u8> {
    u8::try_from(v).ok().map(|v| v.min(100))
}

//! The catalog itself: every onboard parameter with its name, unit, range, group, meaning
//! and where its value lives in [`OnboardSettings`], in the order of the drone's table.

use super::{GpsLossAction, OnboardSettings, ParamDef, ParamGroup, ParamKind};

macro_rules! real {
    ($name:literal, $units:literal, $min:expr, $max:expr, $group:ident, $desc:literal, |$s:ident| $field:expr) => {
        ParamDef {
            name: $name,
            units: $units,
            min: $min,
            max: $max,
            kind: ParamKind::Real,
            group: ParamGroup::$group,
            description: $desc,
            get: |$s: &OnboardSettings| $field,
            set: |$s: &mut OnboardSettings, v: f64| $field = v,
        }
    };
}

/// One point of the planning polar's steady-glide table: the airspeed or the sink rate at the
/// table's `$k`-th brake setting (`GlidePerformance::brake_points`, 0, 0.2 … 1 as shipped).
macro_rules! polar_point {
    ($name:literal, $what:literal, $min:expr, $max:expr, $k:literal, |$s:ident| $table:expr) => {
        ParamDef {
            name: $name,
            units: "m/s",
            min: $min,
            max: $max,
            kind: ParamKind::Real,
            group: ParamGroup::Polar,
            description: concat!(
                $what,
                " at the table's brake setting ",
                stringify!($k),
                " (0, 0.2, 0.4, 0.6, 0.8, 1), at the polar's reference density"
            ),
            get: |$s: &OnboardSettings| $table[$k],
            set: |$s: &mut OnboardSettings, v: f64| $table[$k] = v,
        }
    };
}

/// Every onboard parameter, in the order of the drone's table.
pub const CATALOG: &[ParamDef] = &[
    real!(
        "GN_HK1",
        "m/rad",
        0.0,
        0.2,
        Gains,
        "HK1: main line per radian of heading, course or bearing error",
        |s| s.guidance.gains.hk1_m_per_rad
    ),
    real!(
        "GN_HK2",
        "m·s/rad",
        0.0,
        0.2,
        Gains,
        "HK2: main line per rad/s of heading rate (damping)",
        |s| s.guidance.gains.hk2_m_s_per_rad
    ),
    real!(
        "GN_HK3",
        "m/m",
        0.0,
        0.01,
        Gains,
        "HK3: main line per metre of cross-track error when following a localizer",
        |s| s.guidance.gains.hk3_m_per_m
    ),
    real!(
        "GN_CONV_DIST",
        "m",
        5.0,
        2000.0,
        Gains,
        "CD: convergence distance of the localizer and glide slope (approach while the error exceeds CD/5)",
        |s| s.guidance.gains.convergence_distance_m
    ),
    real!(
        "GN_VK1",
        "1",
        0.0,
        50.0,
        Gains,
        "VK1: brake per unit of glide-slope error (sink over ground speed)",
        |s| s.guidance.gains.vk1
    ),
    real!(
        "GN_VK2",
        "1/m",
        0.0,
        2.0,
        Gains,
        "VK2: brake per metre of altitude error when following the glide slope",
        |s| s.guidance.gains.vk2_per_m
    ),
    real!(
        "GN_BRAKE_TRIM",
        "1",
        0.0,
        1.0,
        Gains,
        "symmetric brake held when the vertical law is centred (0 released … 1 full)",
        |s| s.guidance.gains.brake_trim
    ),
    real!(
        "GN_LINE_MAX",
        "m",
        0.001,
        0.05,
        Gains,
        "largest main-line command of the control laws (the drone also bounds it by its servo travel)",
        |s| s.guidance.gains.main_line_limit_m
    ),
    real!(
        "SP_HALF_SIZE",
        "m",
        10.0,
        2000.0,
        Spiral,
        "half the side of the square spiral around the target",
        |s| s.guidance.spiral.half_size_m
    ),
    real!(
        "SP_MAX_FINAL",
        "m",
        20.0,
        5000.0,
        Spiral,
        "longest final approach the downwind leg may be extended to",
        |s| s.guidance.spiral.max_final_m
    ),
    real!(
        "SP_MIN_FINAL",
        "m",
        0.0,
        2000.0,
        Spiral,
        "shortest final approach (time to settle on the line)",
        |s| s.guidance.spiral.min_final_m
    ),
    real!(
        "SP_HANG_H",
        "m",
        0.0,
        50.0,
        Spiral,
        "height of the drone above the lowest hanging body",
        |s| s.guidance.spiral.hang_height_m
    ),
    real!(
        "SP_FLARE_H",
        "m",
        0.0,
        50.0,
        Spiral,
        "height of the lowest body above the ground at which the flare (full brakes) starts",
        |s| s.guidance.spiral.flare_height_m
    ),
    ParamDef {
        name: "SP_FLARE",
        units: "",
        min: 0.0,
        max: 1.0,
        kind: ParamKind::Flag,
        group: ParamGroup::Spiral,
        description: "1: flare at the flare height; 0: hold the final approach's brake to the ground",
        get: |s| if s.guidance.spiral.flare { 1.0 } else { 0.0 },
        set: |s, v| s.guidance.spiral.flare = v >= 0.5,
    },
    real!(
        "SP_TURN_RATE",
        "rad/s",
        0.0,
        1.5,
        Spiral,
        "turn rate planned for the corners of the pattern; 0: the rate the control gains turn at",
        |s| s.guidance.spiral.planned_turn_rate_rad_s
    ),
    real!(
        "SP_FINAL_MARGIN",
        "m",
        -100.0,
        300.0,
        Spiral,
        "height kept in hand above the planned glide when leaving the spiral",
        |s| s.guidance.spiral.final_margin_m
    ),
    real!(
        "SP_CALM_WIND",
        "m/s",
        0.0,
        5.0,
        Spiral,
        "below this wind the pattern's direction is held as it is",
        |s| s.guidance.spiral.calm_wind_mps
    ),
    real!(
        "SP_REACH_MARGIN",
        "1",
        0.1,
        2.0,
        Spiral,
        "share of the still-air reach counted on before the target is declared out of reach",
        |s| s.guidance.spiral.reach_margin
    ),
    real!(
        "SP_WIND_FILTER",
        "s",
        0.1,
        300.0,
        Spiral,
        "time constant of the wind filter that orients the pattern",
        |s| s.guidance.spiral.wind_filter_s
    ),
    real!(
        "SP_AIM_BEYOND",
        "m",
        -200.0,
        200.0,
        Spiral,
        "touchdown aimed this far beyond the target along the final",
        |s| s.guidance.spiral.aim_beyond_m
    ),
    real!(
        "SP_WIND_MARGIN",
        "m/s",
        0.0,
        10.0,
        Spiral,
        "headwind added to the measured wind when planning the final",
        |s| s.guidance.spiral.wind_margin_mps
    ),
    real!(
        "SP_WIND_MARG_FR",
        "1",
        0.0,
        2.0,
        Spiral,
        "headwind added as a share of the measured wind when planning the final",
        |s| s.guidance.spiral.wind_margin_fraction
    ),
    real!(
        "FS_GPS_LOSS_S",
        "s",
        0.5,
        120.0,
        Failsafe,
        "seconds without a GPS fix before the GPS-loss action (FS_GPS_ACTION) is taken",
        |s| s.failsafe.gps_loss_s
    ),
    ParamDef {
        name: "FS_GPS_ACTION",
        units: "",
        min: 0.0,
        max: 2.0,
        kind: ParamKind::Choice(&["continue", "into_wind", "uncontrolled"]),
        group: ParamGroup::Failsafe,
        description: "GPS loss under the parafoil: 0 keep flying the plan on dead reckoning, 1 turn into the wind and hold heading with a barometric flare, 2 servos neutral",
        get: |s| f64::from(s.failsafe.gps_loss_action.code()),
        set: |s, v| {
            if let Some(a) = GpsLossAction::from_code(v as u8) {
                s.failsafe.gps_loss_action = a;
            }
        },
    },
    real!(
        "MAN_TIMEOUT_S",
        "s",
        0.1,
        10.0,
        Failsafe,
        "sticks go stale after this long without MANUAL_CONTROL; manual mode then falls back to the autonomous mode",
        |s| s.failsafe.manual_timeout_s
    ),
    real!(
        "MIS_DEPLOY_M",
        "m",
        50.0,
        30000.0,
        Mission,
        "estimated height above the launch site at which the round chute is released and the parafoil deploys",
        |s| s.mission.deploy_height_m
    ),
    real!(
        "MIS_SETTLE_S",
        "s",
        0.0,
        120.0,
        Mission,
        "time the parafoil inflates and settles with neutral servos before guidance steers",
        |s| s.mission.settle_s
    ),
    real!(
        "MIS_CUTDOWN_M",
        "m",
        0.0,
        50000.0,
        Mission,
        "estimated altitude above sea level at which the drone cuts the balloon away itself; 0 = never",
        |s| s.mission.cutdown_altitude_msl_m
    ),
    real!(
        "MIS_BURST_M",
        "m",
        0.0,
        50000.0,
        Mission,
        "expected burst altitude above sea level, loaded before launch for the station's flight-path prediction; 0 = not loaded",
        |s| s.mission.expected_burst_msl_m
    ),
    real!(
        "MIS_ASCENT_MPS",
        "m/s",
        0.0,
        20.0,
        Mission,
        "expected mean ascent rate from launch to burst, loaded before launch for the station's flight-path prediction; 0 = not loaded",
        |s| s.mission.expected_ascent_rate_mps
    ),
    // The planning polar last: appended, so the drone's table keeps every older index.
    polar_point!("PL_AS_0", "steady true airspeed", 2.0, 25.0, 0, |s| s
        .guidance
        .performance
        .airspeed_mps),
    polar_point!("PL_AS_1", "steady true airspeed", 2.0, 25.0, 1, |s| s
        .guidance
        .performance
        .airspeed_mps),
    polar_point!("PL_AS_2", "steady true airspeed", 2.0, 25.0, 2, |s| s
        .guidance
        .performance
        .airspeed_mps),
    polar_point!("PL_AS_3", "steady true airspeed", 2.0, 25.0, 3, |s| s
        .guidance
        .performance
        .airspeed_mps),
    polar_point!("PL_AS_4", "steady true airspeed", 2.0, 25.0, 4, |s| s
        .guidance
        .performance
        .airspeed_mps),
    polar_point!("PL_AS_5", "steady true airspeed", 2.0, 25.0, 5, |s| s
        .guidance
        .performance
        .airspeed_mps),
    polar_point!("PL_SINK_0", "steady sink rate", 0.3, 15.0, 0, |s| s
        .guidance
        .performance
        .sink_rate_mps),
    polar_point!("PL_SINK_1", "steady sink rate", 0.3, 15.0, 1, |s| s
        .guidance
        .performance
        .sink_rate_mps),
    polar_point!("PL_SINK_2", "steady sink rate", 0.3, 15.0, 2, |s| s
        .guidance
        .performance
        .sink_rate_mps),
    polar_point!("PL_SINK_3", "steady sink rate", 0.3, 15.0, 3, |s| s
        .guidance
        .performance
        .sink_rate_mps),
    polar_point!("PL_SINK_4", "steady sink rate", 0.3, 15.0, 4, |s| s
        .guidance
        .performance
        .sink_rate_mps),
    polar_point!("PL_SINK_5", "steady sink rate", 0.3, 15.0, 5, |s| s
        .guidance
        .performance
        .sink_rate_mps),
    // The rest of the polar: a vehicle file trims only the straight glide, and `stx polar`
    // sends these as the shipped table has them; they are parameters so that what a flight
    // learned of the turn can be sent too.
    real!(
        "PL_RHO",
        "kg/m³",
        0.3,
        1.5,
        Polar,
        "air density the polar's airspeeds and sink rates are given at",
        |s| s.guidance.performance.reference_density_kg_per_m3
    ),
    real!(
        "PL_TURN_MAX",
        "rad/s",
        0.1,
        3.0,
        Polar,
        "steady turn rate with the main line fully over",
        |s| s.guidance.performance.max_turn_rate_rad_s
    ),
    real!(
        "PL_TURN_LINE",
        "m",
        0.001,
        0.1,
        Polar,
        "main-line command that gives tanh(1) ≈ 76 % of the maximum turn rate",
        |s| s.guidance.performance.turn_main_line_scale_m
    ),
    real!(
        "PL_TURN_TAU",
        "s",
        0.1,
        10.0,
        Polar,
        "time constant of the turn rate's response to the main line",
        |s| s.guidance.performance.turn_time_constant_s
    ),
    real!(
        "PL_TURN_SINK",
        "m/s per (rad/s)²",
        0.0,
        50.0,
        Polar,
        "extra sink in a steady turn per (rad/s)² of turn rate",
        |s| s.guidance.performance.turn_sink_mps_per_rad2_s2
    ),
];

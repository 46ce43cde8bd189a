use mavlink::dialects::common as mc;
use mavlink::dialects::common::MavMessage;
use mavlink::{MavlinkVersion, Message};
use proptest::prelude::*;
use serde_json::Value;
use stx_types::mission::{FlightMode, FlightStage, GuidancePhase};

use super::*;

/// Half a wire quantum for the fields that are scaled integers; `None` for f32 fields.
fn quantum(kind: &str, field: &str) -> Option<f64> {
    Some(match (kind, field) {
        (_, "lat_deg" | "lon_deg") => 0.5e-7,
        ("gps_raw" | "position", "alt_msl_m" | "alt_rel_m") => 0.5e-3,
        ("gps_raw", "h_acc_m" | "v_acc_m") => 1.0e-3,
        ("gps_raw", "ground_speed_mps" | "course_deg") => 0.5e-2,
        ("position", "heading_deg" | "v_north_mps" | "v_east_mps" | "v_down_mps") => 0.5e-2,
        ("air_data", "temperature_c" | "diff_temperature_c") => 0.5e-2,
        ("hud", "heading_deg") => 0.5,
        ("actuators", "main_line") => 1.0e-3,
        ("actuators", "brake_right" | "brake_left") => 0.5e-3,
        ("system", "battery_voltage_v") | ("battery", "voltage_v") => 0.5e-3,
        // −0.01 A is sent as −0.02 A (−1 cA means "not measured").
        ("system", "battery_current_a") | ("battery", "current_a") => 1.1e-2,
        ("system", "load_pct") => 0.05,
        ("system", "comm_drop_rate_pct") => 0.5e-2,
        ("battery", "temperature_c") => 0.5e-2,
        ("guidance", "desired_heading_deg" | "bearing_to_target_deg" | "distance_to_target_m") => {
            0.5
        }
        _ => return None,
    })
}

fn assert_close(kind: &str, field: &str, a: &Value, b: &Value) {
    match (a, b) {
        (Value::Object(x), Value::Object(y)) => {
            assert_eq!(x.len(), y.len(), "{kind}: field sets differ");
            for (k, va) in x {
                let vb = y.get(k).unwrap_or(&Value::Null);
                assert_close(kind, k, va, vb);
            }
        }
        (Value::Number(x), Value::Number(y)) => {
            let (x, y) = (
                x.as_f64().unwrap_or(f64::NAN),
                y.as_f64().unwrap_or(f64::NAN),
            );
            let tol = quantum(kind, field).unwrap_or(0.0).max(1.2e-7 * x.abs()) + 1e-12;
            assert!(
                (x - y).abs() <= tol,
                "{kind}.{field}: sent {x}, got {y} (tol {tol})"
            );
        }
        _ => assert_eq!(a, b, "{kind}.{field}"),
    }
}

fn check_round_trip(t: &Telemetry) {
    let wire = t.to_mavlink();
    let back = Telemetry::from_mavlink(&wire).unwrap_or_else(|| panic!("{t:?} not read back"));
    let (a, b) = (
        serde_json::to_value(t).unwrap(),
        serde_json::to_value(&back).unwrap(),
    );
    let kind = a
        .get("kind")
        .and_then(Value::as_str)
        .unwrap_or("")
        .to_string();
    assert_close(&kind, "", &a, &b);
    // What came from the wire goes back to the same wire bytes.
    let (mut p1, mut p2) = ([0_u8; 255], [0_u8; 255]);
    let n1 = wire.ser(MavlinkVersion::V2, &mut p1);
    let n2 = back.to_mavlink().ser(MavlinkVersion::V2, &mut p2);
    assert_eq!(p1[..n1], p2[..n2], "{kind}: wire not stable");
}

fn opt<T: std::fmt::Debug + Clone + 'static>(
    s: impl Strategy<Value = T> + 'static,
) -> BoxedStrategy<Option<T>> {
    prop_oneof![1 => Just(None), 4 => s.prop_map(Some)].boxed()
}

fn lat() -> impl Strategy<Value = f64> {
    -90.0..90.0_f64
}
fn lon() -> impl Strategy<Value = f64> {
    -180.0..180.0_f64
}

fn status() -> impl Strategy<Value = Telemetry> {
    (
        prop::sample::select(FlightMode::ALL.to_vec()),
        prop::sample::select(FlightStage::ALL.to_vec()),
        prop::sample::select(GuidancePhase::ALL.to_vec()),
        prop::sample::select(vec![
            SystemState::Standby,
            SystemState::Active,
            SystemState::FlightTermination,
        ]),
    )
        .prop_map(|(mode, stage, phase, state)| {
            Telemetry::Status(VehicleStatus {
                mode,
                stage,
                phase,
                state,
            })
        })
}

fn gps() -> impl Strategy<Value = Telemetry> {
    (
        any::<u64>(),
        prop::sample::select(vec![GpsFix::NoFix, GpsFix::Fix3d, GpsFix::RtkFixed]),
        lat(),
        lon(),
        -400.0..40_000.0_f64,
        opt(0.0..600.0_f64),
        opt(0.0..359.99_f64),
        opt(0_u8..60),
        (opt(0.001..100.0_f64), opt(0.001..100.0_f64)),
    )
        .prop_map(
            |(time_usec, fix, lat_deg, lon_deg, alt_msl_m, gs, course_deg, satellites, (h, v))| {
                Telemetry::GpsRaw(GpsRaw {
                    time_usec,
                    fix,
                    lat_deg,
                    lon_deg,
                    alt_msl_m,
                    ground_speed_mps: gs,
                    course_deg,
                    satellites,
                    h_acc_m: h,
                    v_acc_m: v,
                })
            },
        )
}

fn position() -> impl Strategy<Value = Telemetry> {
    (
        any::<u32>(),
        lat(),
        lon(),
        -400.0..40_000.0_f64,
        -400.0..40_000.0_f64,
        [-300.0..300.0_f64, -300.0..300.0, -300.0..300.0],
        opt(0.0..359.99_f64),
    )
        .prop_map(|(t, la, lo, alt, rel, v, hdg)| {
            Telemetry::Position(GlobalPosition {
                time_boot_ms: t,
                lat_deg: la,
                lon_deg: lo,
                alt_msl_m: alt,
                alt_rel_m: rel,
                v_north_mps: v[0],
                v_east_mps: v[1],
                v_down_mps: v[2],
                heading_deg: hdg,
            })
        })
}

fn f32ish(r: std::ops::Range<f64>) -> impl Strategy<Value = f64> {
    r
}

fn others() -> impl Strategy<Value = Telemetry> {
    prop_oneof![
        (
            any::<u32>(),
            [
                f32ish(-3.2..3.2),
                f32ish(-1.6..1.6),
                f32ish(-3.2..3.2),
                f32ish(-10.0..10.0),
                f32ish(-10.0..10.0),
                f32ish(-10.0..10.0)
            ]
        )
            .prop_map(|(t, a)| Telemetry::Attitude(Attitude {
                time_boot_ms: t,
                roll_rad: a[0],
                pitch_rad: a[1],
                yaw_rad: a[2],
                roll_rate_radps: a[3],
                pitch_rate_radps: a[4],
                yaw_rate_radps: a[5],
            })),
        (
            any::<u32>(),
            100.0..110_000.0_f64,
            -50.0..2_000.0_f64,
            -80.0..60.0_f64,
            opt(-80.0..60.0_f64)
        )
            .prop_map(|(t, p, dp, tc, td)| Telemetry::AirData(AirData {
                time_boot_ms: t,
                abs_pressure_pa: p,
                diff_pressure_pa: dp,
                temperature_c: tc,
                // 0.00 °C is sent as 0.01 °C (0 means unknown).
                diff_temperature_c: td.map(|c| if c.abs() < 0.005 { 0.01 } else { c }),
            })),
        (
            0.0..60.0_f64,
            0.0..80.0_f64,
            0.0..359.4_f64,
            -30.0..5.0_f64,
            -400.0..40_000.0_f64
        )
            .prop_map(|(a, g, h, c, alt)| {
                Telemetry::Hud(Hud {
                    airspeed_mps: a,
                    groundspeed_mps: g,
                    heading_deg: h,
                    climb_mps: c,
                    alt_msl_m: alt,
                })
            }),
        (any::<u32>(), -1.0..=1.0_f64, 0.0..=1.0_f64, 0.0..=1.0_f64).prop_map(|(t, m, r, l)| {
            Telemetry::Actuators(Actuators {
                time_usec: t,
                main_line: m,
                brake_right: r,
                brake_left: l,
            })
        }),
        (
            opt(0.0..65.0_f64),
            opt(-300.0..300.0_f64),
            opt(0_u8..=100),
            0.0..100.0_f64,
            0.0..100.0_f64,
            any::<u16>(),
            any::<[u32; 3]>()
        )
            .prop_map(
                |(v, c, r, load, drop, errs, s)| Telemetry::System(SystemStatus {
                    battery_voltage_v: v,
                    battery_current_a: c,
                    battery_remaining_pct: r,
                    load_pct: load,
                    comm_drop_rate_pct: drop,
                    comm_errors: errs,
                    sensors_present: s[0],
                    sensors_enabled: s[1],
                    sensors_health: s[2],
                })
            ),
        (
            any::<u8>(),
            opt(0.0..65.0_f64),
            opt(-300.0..300.0_f64),
            opt(0_i32..1_000_000),
            opt(0_u8..=100),
            opt(-60.0..120.0_f64)
        )
            .prop_map(|(id, v, c, mah, r, t)| Telemetry::Battery(BatteryStatus {
                id,
                voltage_v: v,
                current_a: c,
                consumed_mah: mah,
                remaining_pct: r,
                temperature_c: t,
            })),
        (
            "[a-zA-Z0-9 .:!-]{0,50}",
            prop::sample::select(vec![Severity::Info, Severity::Warning, Severity::Critical])
        )
            .prop_map(|(s, sev)| Telemetry::StatusText(StatusText::single(sev, &s))),
        (
            any::<u64>(),
            [
                opt(-60.0..60.0_f64),
                opt(-60.0..60.0_f64),
                opt(-10.0..10.0_f64),
                opt(0.0..10.0_f64),
                opt(0.0..5.0_f64),
                opt(0.0..40_000.0_f64)
            ],
            0.0..5.0_f64,
            0.0..5.0_f64
        )
            .prop_map(|(t, w, ha, va)| Telemetry::Wind(Wind {
                time_usec: t,
                wind_north_mps: w[0],
                wind_east_mps: w[1],
                wind_down_mps: w[2],
                var_horiz_mps: w[3],
                var_vert_mps: w[4],
                alt_msl_m: w[5],
                horiz_accuracy_mps: ha,
                vert_accuracy_mps: va,
            })),
        (
            -45.0..45.0_f64,
            0.0..359.0_f64,
            0.0..359.0_f64,
            0.0..65_000.0_f64,
            -1000.0..1000.0_f64,
            -5000.0..5000.0_f64
        )
            .prop_map(|(r, h, b, d, ae, xt)| Telemetry::Guidance(GuidanceStatus {
                desired_roll_deg: r,
                desired_heading_deg: h,
                bearing_to_target_deg: b,
                distance_to_target_m: d,
                alt_error_m: ae,
                xtrack_error_m: xt,
            })),
        (any::<u32>(), lat(), lon(), -400.0..9_000.0_f64).prop_map(|(t, la, lo, alt)| {
            Telemetry::PredictedLanding(PredictedLanding {
                time_boot_ms: t,
                lat_deg: la,
                lon_deg: lo,
                alt_msl_m: alt,
            })
        }),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 512, rng_seed: proptest::test_runner::RngSeed::Fixed(0x57A1), ..ProptestConfig::default() })]

    #[test]
    fn telemetry_round_trips_within_quantisation(t in prop_oneof![status(), gps(), position(), others()]) {
        check_round_trip(&t);
    }

    #[test]
    fn long_status_text_splits_and_reassembles(text in "\\PC{0,400}", id in 1_u16..) {
        let chunks = split_status_text(Severity::Warning, &text, id);
        let mut asm = StatusTextAssembler::default();
        let mut out = None;
        for c in &chunks {
            prop_assert!(c.text.len() <= STATUSTEXT_LEN);
            // Through the wire and back.
            let Some(Telemetry::StatusText(back)) = Telemetry::from_mavlink(&Telemetry::StatusText(c.clone()).to_mavlink()) else {
                panic!("statustext not read back");
            };
            prop_assert_eq!(&back, c);
            if let Some(done) = asm.push(1, 1, &back) {
                out = Some(done);
            }
        }
        prop_assert_eq!(out, Some((Severity::Warning, text)));
    }
}

#[test]
fn heartbeat_packs_mode_stage_phase() {
    let s = VehicleStatus {
        mode: FlightMode::SpiralLanding,
        stage: FlightStage::Parafoil,
        phase: GuidancePhase::FinalApproach,
        state: SystemState::Active,
    };
    let MavMessage::HEARTBEAT(h) = Telemetry::Status(s).to_mavlink() else {
        panic!("not a heartbeat")
    };
    assert_eq!(h.custom_mode, 5 | 4 << 8 | 6 << 16);
    assert_eq!(h.mavtype, mc::MavType::MAV_TYPE_PARAFOIL);
    assert!(
        h.base_mode
            .contains(mc::MavModeFlag::MAV_MODE_FLAG_CUSTOM_MODE_ENABLED)
    );
    // A ground station's heartbeat is not vehicle status.
    let gcs = MavMessage::HEARTBEAT(mc::HEARTBEAT_DATA {
        mavtype: mc::MavType::MAV_TYPE_GCS,
        ..h.clone()
    });
    assert_eq!(Telemetry::from_mavlink(&gcs), None);
    // Unknown codes are refused.
    let bad = MavMessage::HEARTBEAT(mc::HEARTBEAT_DATA {
        custom_mode: 99,
        ..h
    });
    assert_eq!(Telemetry::from_mavlink(&bad), None);
}

#[test]
fn servo_mapping_end_points() {
    assert_eq!(signed_to_pwm_us(-1.0), 1000);
    assert_eq!(signed_to_pwm_us(0.0), 1500);
    assert_eq!(signed_to_pwm_us(1.0), 2000);
    assert_eq!(signed_to_pwm_us(7.0), 2000);
    assert_eq!(unit_to_pwm_us(0.0), 1000);
    assert_eq!(unit_to_pwm_us(1.0), 2000);
    assert_eq!(pwm_us_to_signed(900), -1.0);
    assert_eq!(pwm_us_to_unit(2100), 1.0);
}

#[test]
fn pressure_units_are_converted() {
    let MavMessage::SCALED_PRESSURE(p) = Telemetry::AirData(AirData {
        time_boot_ms: 0,
        abs_pressure_pa: 101_325.0,
        diff_pressure_pa: 250.0,
        temperature_c: -12.34,
        diff_temperature_c: None,
    })
    .to_mavlink() else {
        panic!("not SCALED_PRESSURE")
    };
    assert_eq!(p.press_abs, 1013.25);
    assert_eq!(p.press_diff, 2.5);
    assert_eq!(p.temperature, -1234);
    assert_eq!(p.temperature_press_diff, 0);
}

#[test]
fn position_target_in_other_frames_is_not_a_landing_prediction() {
    let mut m = Telemetry::PredictedLanding(PredictedLanding {
        time_boot_ms: 1,
        lat_deg: 41.0,
        lon_deg: -8.0,
        alt_msl_m: 100.0,
    })
    .to_mavlink();
    if let MavMessage::POSITION_TARGET_GLOBAL_INT(p) = &mut m {
        p.coordinate_frame = mc::MavFrame::MAV_FRAME_GLOBAL_RELATIVE_ALT;
    }
    assert_eq!(Telemetry::from_mavlink(&m), None);
}

//! A body's own IMU speaks as another component of the drone's system: its ATTITUDE reaches
//! the ground tagged with that component, signed, and counted without gaps on either stream.

use std::time::Duration;

use stx_link::endpoint::{
    GroundConfig, GroundEndpoint, GroundEvent, LinkConfig, VehicleConfig, VehicleEndpoint,
};
use stx_link::signing::{SigningConfig, SigningKey};
use stx_link::telemetry::{Attitude, Telemetry};
use stx_types::stack::BodyImu;

fn attitude(ms: u32, roll_rad: f64) -> Telemetry {
    Telemetry::Attitude(Attitude {
        time_boot_ms: ms,
        roll_rad,
        pitch_rad: 0.0,
        yaw_rad: 0.0,
        roll_rate_radps: 0.0,
        pitch_rate_radps: 0.0,
        yaw_rate_radps: 0.0,
    })
}

#[test]
fn a_body_imus_attitude_arrives_from_its_own_component_signed_and_without_loss() {
    let key = |link_id| {
        Some(SigningConfig::new(
            SigningKey::from_bytes([9; 32]),
            link_id,
            Duration::from_secs(1_767_225_600),
        ))
    };
    let mut vehicle = VehicleEndpoint::new(
        VehicleConfig {
            link: LinkConfig::vehicle().with_signing(key(2)),
            ..Default::default()
        },
        Duration::ZERO,
    )
    .expect("vehicle");
    let mut ground = GroundEndpoint::new(
        GroundConfig {
            link: LinkConfig::ground().with_signing(key(1)),
            ..Default::default()
        },
        Duration::ZERO,
    );
    let canopy = BodyImu::Canopy.component_id();
    for i in 0..20_u32 {
        let now = Duration::from_millis(u64::from(i) * 250);
        vehicle.send_telemetry(now, &attitude(i * 250, 0.25));
        if i % 2 == 0 {
            vehicle.send_telemetry_from(now, canopy, &attitude(i * 250, -0.5));
        }
        while let Some(f) = vehicle.poll_transmit(now) {
            ground.handle_bytes(now, &f);
        }
    }
    let mut from_drone = 0;
    let mut from_canopy = 0;
    while let Some(e) = ground.poll_event() {
        if let GroundEvent::Telemetry {
            from,
            telemetry: Telemetry::Attitude(a),
        } = e
        {
            match from {
                (1, 1) => {
                    assert_eq!(a.roll_rad, 0.25);
                    from_drone += 1;
                }
                (1, c) if c == canopy => {
                    assert_eq!(a.roll_rad, -0.5);
                    from_canopy += 1;
                }
                other => panic!("attitude from {other:?}"),
            }
        }
    }
    assert_eq!((from_drone, from_canopy), (20, 10));
    let stats = ground.link_stats(Duration::from_secs(5));
    assert_eq!(stats.signature_failures, 0, "{stats:?}");
    assert_eq!(
        stats.packet_loss_pct, 0.0,
        "each component its own sequence"
    );
}

use stx_agreement::campaign::{station_for};
use stx_agreement::pair::Pair;
use stx_sim::dispersions::Dispersions;
use stx_sim::drone::MissionConfig;

#[test]
fn trace() {
    let seed: u64 = std::env::var("SEED").ok().and_then(|s| s.parse().ok()).unwrap_or(2);
    let mut m = MissionConfig::builtin("mission-short").unwrap();
    m.seed = seed;
    let d = Dispersions::load("realistic").unwrap();
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../config/keep-out/sample.geojson");
    let text = std::fs::read_to_string(&path).unwrap();
    let mut pair = Pair::new(&m, Some(&d), station_for(&m).unwrap(), Some(("z", text)), 20.0).unwrap();
    let mut last = -1.0;
    while !pair.landed() {
        pair.step().unwrap();
        let t = pair.mission_s();
        if t < 780.0 || t - last < 2.0 { continue; }
        last = t;
        let (Some(a), Some(b)) = (pair.drone().estimate(), pair.core().estimate_now()) else { eprintln!("{t} none"); continue };
        eprintln!("{t:.1} onboard t={:.2} wind {:.2},{:.2} vd {:.2} as {:.2} sink {:.2} hdg {:.1} | station t={:.2} wind {:.2},{:.2} vd {:.2} as {:.2} sink {:.2} hdg {:.1} dpos {:.2}",
            a.time_s, a.wind_ned_mps.x, a.wind_ned_mps.y, a.velocity_ned_mps.z, a.airspeed_mps, a.sink_rate_mps, a.heading_rad.to_degrees(),
            b.time_s, b.wind_ned_mps.x, b.wind_ned_mps.y, b.velocity_ned_mps.z, b.airspeed_mps, b.sink_rate_mps, b.heading_rad.to_degrees(), (a.position_ned_m - b.position_ned_m).norm());
        if t > 860.0 { break; }
    }
}

use stx_agreement::campaign::{station_for};
use stx_agreement::pair::Pair;
use stx_agreement::truth::TruthSample;
use stx_sim::dispersions::Dispersions;
use stx_sim::drone::MissionConfig;
use stx_gnc::predict::{predict, PredictorConfig};
use stx_dynamics::atmosphere::StandardAtmosphere;

#[test]
fn trace() {
    let name = std::env::var("MISSION").unwrap_or("mission-short".into());
    let seeds: Vec<u64> = std::env::var("SEEDS").unwrap_or("1,2,3,4,5,6,7,8".into()).split(',').map(|s| s.parse().unwrap()).collect();
    for seed in seeds {
    let mut m = MissionConfig::builtin(&name).unwrap();
    m.seed = seed;
    let d = Dispersions::load("realistic").unwrap();
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../config/keep-out/sample.geojson");
    let text = std::fs::read_to_string(&path).unwrap();
    let mut pair = Pair::new(&m, Some(&d), station_for(&m).unwrap(), Some(("z", text)), 20.0).unwrap();
    let mut rows = vec![];
    let heights = [300.0, 100.0, 50.0];
    let mut next = 0;
    while !pair.landed() {
        pair.step().unwrap();
        let t = TruthSample::of(pair.drone());
        if t.stage != stx_gnc::mission::FlightStage::Parafoil || next >= heights.len() || t.height_m() > heights[next] { continue; }
        next += 1;
        let Some(e) = pair.drone().estimate() else { continue };
        let g = pair.drone().onboard().guidance();
        let perf = g.config().performance;
        let mut out = vec![];
        for (step, learned) in [(0.5, false), (0.25, false), (0.5, true), (0.25, true)] {
            let c = PredictorConfig { step_s: step, ..PredictorConfig::default() };
            let pf = if learned { g.learned_performance() } else { perf };
            let p = predict(e, g, &pf, &StandardAtmosphere, m.site.alt_msl_m, &c);
            out.push(p.planned.position_ne_m);
        }
        let fc = g.spiral_status().final_course_rad;
        rows.push((t.time_s, t.height_m(), format!("{:?}", t.phase), out, fc, e.wind_ned_mps, t.wind_ned_mps));
    }
    let l = stx_agreement::truth::TruthLanding::of(pair.drone()).unwrap();
    let td = l.bodies_ne_m[1];
    for (t, h, ph, out, fc, ew, tw) in rows {
        let errs: Vec<String> = out.iter().map(|p| {
            let (dn, de) = (p[0]-td[0], p[1]-td[1]);
            let along = dn*fc.cos()+de*fc.sin(); let across = -dn*fc.sin()+de*fc.cos();
            format!("{:.1}/{:.1}", along, across)
        }).collect();
        eprintln!("seed {seed} {t:.0} h={h:.0} {ph} along/across {:?} est wind {:.1},{:.1} true {:.1},{:.1}", errs, ew.x, ew.y, tw.x, tw.y);
    }
    }
}

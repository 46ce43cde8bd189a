//! The keep-out zones in the core: loading, operators' edits, refused targets, alarms.

use nalgebra::Vector3;
use serde_json::{Value, json};
use stx_gnc::predict::{LandingPrediction, PredictedTouchdown};

use super::super::tests::core;
use super::super::{CommandRequest, Outbound, StationCore};
use super::CLEAR_AFTER_S;
use crate::keep_out::PredictionKind;
use crate::messages::Level;

/// A square zone `name` of side 2·`half_m` centred `north_m`, `east_m` from the origin.
fn square(core: &StationCore, name: &str, north_m: f64, east_m: f64, half_m: f64) -> Value {
    let corner = |dn: f64, de: f64| {
        let (lat, lon, _) = core
            .frame
            .to_geodetic(&Vector3::new(north_m + dn, east_m + de, 0.0));
        json!([lon, lat])
    };
    let h = half_m;
    json!({
        "type": "Feature",
        "properties": {"name": name},
        "geometry": {"type": "Polygon", "coordinates": [[
            corner(-h, -h), corner(-h, h), corner(h, h), corner(h, -h), corner(-h, -h)
        ]]}
    })
}

fn collection(features: Vec<Value>) -> Value {
    json!({"type": "FeatureCollection", "features": features})
}

fn with_pond(core: &mut StationCore) {
    let pond = collection(vec![square(core, "Pond", 300.0, 0.0, 50.0)]);
    let checked = core.check_keep_out(pond).expect("valid zones");
    core.set_keep_out(0.0, "operator", checked, Some("zones.geojson"));
}

/// The `keep_out` log entries sent since the last call.
pub(in crate::core) fn events(core: &mut StationCore) -> Vec<(Level, String)> {
    core.drain_outbound()
        .into_iter()
        .filter_map(|o| match o {
            Outbound::Event(e) if e.source == "keep_out" => Some((e.level, e.text)),
            _ => None,
        })
        .collect()
}

fn touchdown(ne: [f64; 2]) -> PredictedTouchdown {
    PredictedTouchdown {
        position_ne_m: ne,
        time_to_land_s: 60.0,
        semi_major_m: 10.0,
        semi_minor_m: 5.0,
        major_axis_rad: 0.0,
    }
}

fn predict(core: &mut StationCore, planned: [f64; 2], uncontrolled: [f64; 2]) {
    core.prediction = Some(LandingPrediction {
        time_s: 0.0,
        planned: touchdown(planned),
        uncontrolled: touchdown(uncontrolled),
    });
}

#[test]
fn the_sample_file_loads_and_a_bad_file_is_said_loudly_and_leaves_no_zones() {
    let mut c = core();
    let sample = include_str!("../../../../config/keep-out/sample.geojson");
    c.load_keep_out(0.0, "sample.geojson", Ok(sample.to_string()));
    let msg = c.keep_out_msg(1.0);
    assert_eq!(msg.areas, 3);
    assert_eq!(msg.load_error, None);
    let names: Vec<&str> = c
        .keep_out_zones()
        .zones
        .iter()
        .map(|z| z.name.as_str())
        .collect();
    assert_eq!(names, ["Pond", "Road N114 corridor", "Farmhouse"]);
    // Nor the rehearsal's target (the origin) nor mission-short's (300 m N, 2500 m E) is in
    // a zone; the pond and the farmhouse are within 400 m of them.
    assert!(c.keep_out_zone_at([0.0, 0.0]).is_none());
    assert!(c.keep_out_zone_at([300.0, 2500.0]).is_none());
    assert_eq!(
        c.keep_out_zone_at([280.0, -120.0]).map(|z| z.name.as_str()),
        Some("Pond")
    );
    assert_eq!(
        c.keep_out_zone_at([120.0, 2280.0]).map(|z| z.name.as_str()),
        Some("Farmhouse")
    );
    let logged = events(&mut c);
    assert_eq!(logged.len(), 1, "{logged:?}");
    assert!(logged[0].1.contains("'Pond'"), "{logged:?}");

    for (text, said) in [
        (
            Err("No such file or directory (os error 2)".to_string()),
            "No such file",
        ),
        (Ok("{\"type\": \"FeatureCollection\"".to_string()), "EOF"),
        (
            Ok(r#"{"type":"Point","coordinates":[0,0]}"#.to_string()),
            "not an area",
        ),
    ] {
        let mut c = core();
        with_pond(&mut c);
        c.drain_outbound();
        c.load_keep_out(0.0, "zones.geojson", text);
        let msg = c.keep_out_msg(0.0);
        let error = msg.load_error.expect("the reason is kept for the pages");
        assert!(
            error.contains("NOT loaded from zones.geojson") && error.contains(said),
            "{error}"
        );
        assert_eq!(msg.areas, 0);
        let logged = events(&mut c);
        assert_eq!(logged.len(), 1);
        assert_eq!(logged[0], (Level::Error, error));
    }
}

#[test]
fn an_edit_is_checked_named_logged_with_who_and_what_and_sent_to_the_pages() {
    let mut c = core();
    for (body, said) in [
        (json!({"type": "Feature"}), "FeatureCollection"),
        (json!({"type": "FeatureCollection"}), "`features`"),
        (
            {
                let mut f = square(&c, "x", 0.0, 0.0, 10.0);
                f["properties"] = json!({"name": "  "});
                collection(vec![f])
            },
            "needs a name",
        ),
        (
            {
                let mut f = square(&c, "Open", 0.0, 0.0, 10.0);
                f["geometry"]["coordinates"][0]
                    .as_array_mut()
                    .expect("ring")
                    .pop();
                collection(vec![f])
            },
            "ring 0",
        ),
        (
            {
                // Two corners swapped: a bow tie, as an edit on the map can leave it.
                let mut f = square(&c, "Bow tie", 0.0, 0.0, 10.0);
                let ring = f["geometry"]["coordinates"][0]
                    .as_array_mut()
                    .expect("ring");
                ring.swap(1, 2);
                collection(vec![f])
            },
            "keep-out feature 0: ring 0 crosses itself",
        ),
    ] {
        let err = c.check_keep_out(body).unwrap_err();
        assert_eq!(err.status, 400);
        assert!(err.reason.contains(said), "{said}: {}", err.reason);
    }
    with_pond(&mut c);
    let zones = collection(vec![
        square(&c, "Pond", 300.0, 0.0, 50.0),
        square(&c, "Road", -300.0, 0.0, 20.0),
    ]);
    let checked = c.check_keep_out(zones.clone()).expect("valid");
    c.drain_outbound();
    let msg = c.set_keep_out(5.0, "alice", checked, Some("zones.geojson"));
    assert_eq!(msg.areas, 2);
    assert_eq!(msg.zones, zones);
    assert_eq!(msg.changed_by.as_deref(), Some("alice"));
    let out = c.drain_outbound();
    assert!(
        out.iter()
            .any(|o| matches!(o, Outbound::KeepOut(m) if m.areas == 2))
    );
    let logged: Vec<_> = out
        .iter()
        .filter_map(|o| match o {
            Outbound::Event(e) => Some((e.level, e.text.clone())),
            _ => None,
        })
        .collect();
    assert_eq!(logged.len(), 1, "{logged:?}");
    assert_eq!(logged[0].0, Level::Info);
    assert!(
        logged[0]
            .1
            .starts_with("alice: keep-out zones added 'Road'")
            && logged[0].1.contains("saved to zones.geojson"),
        "{logged:?}"
    );
    // Without a file the edit holds but the log warns it will not survive a restart.
    let checked = c.check_keep_out(collection(vec![])).expect("none is valid");
    c.set_keep_out(6.0, "bob", checked, None);
    let logged = events(&mut c);
    assert_eq!(logged[0].0, Level::Warning);
    assert!(logged[0].1.contains("removed 'Pond', 'Road'"), "{logged:?}");
    assert!(
        logged[0].1.contains("not kept across a restart"),
        "{logged:?}"
    );
}

#[test]
fn a_target_or_a_plan_landing_in_a_zone_is_refused_naming_the_zone() {
    let mut c = core();
    with_pond(&mut c);
    let at = |c: &StationCore, n: f64, e: f64| {
        let (lat, lon, _) = c.frame.to_geodetic(&Vector3::new(n, e, 0.0));
        (lat, lon)
    };
    let (lat, lon) = at(&c, 310.0, 10.0);
    let target = |lat_deg, lon_deg| CommandRequest::Target {
        lat_deg,
        lon_deg,
        alt_msl_m: 245.0,
        approach_course_deg: None,
    };
    let err = c.request(1.0, "operator", target(lat, lon)).unwrap_err();
    assert_eq!(err.status, 400);
    assert_eq!(err.reason, "target inside keep-out zone 'Pond'");
    let (lat_out, lon_out) = at(&c, 200.0, 0.0);
    c.request(1.0, "operator", target(lat_out, lon_out))
        .expect("60 m off the pond is fine");

    use stx_link::plan::PlanItem;
    let plan = |land: (f64, f64)| {
        CommandRequest::Plan(vec![
            // Flying over the pond is allowed.
            PlanItem::Waypoint {
                lat_deg: lat,
                lon_deg: lon,
                alt_msl_m: 600.0,
            },
            PlanItem::Land {
                lat_deg: land.0,
                lon_deg: land.1,
                alt_msl_m: 245.0,
                approach_heading_deg: None,
            },
        ])
    };
    let err = c.request(2.0, "operator", plan((lat, lon))).unwrap_err();
    assert_eq!(
        err.reason,
        "the plan's landing point inside keep-out zone 'Pond'"
    );
    c.request(2.0, "operator", plan((lat_out, lon_out)))
        .expect("a waypoint over the pond, landing beside it");
}

#[test]
fn a_landing_predicted_in_a_zone_alarms_once_and_clears_once_it_stays_out() {
    let mut c = core();
    with_pond(&mut c);
    c.drain_outbound();
    let inside = [300.0, 10.0];
    let outside = [0.0, 0.0];
    predict(&mut c, outside, inside);
    for i in 0..20 {
        c.tick(f64::from(i) * 0.25);
    }
    let logged = events(&mut c);
    assert_eq!(
        logged,
        [(
            Level::Warning,
            "uncontrolled landing predicted inside keep-out zone 'Pond'".to_string()
        )]
    );
    let alarms = c.state_msg_now(5.0).keep_out_alarms;
    assert_eq!(alarms.len(), 1);
    assert_eq!(alarms[0].prediction, PredictionKind::Uncontrolled);
    assert_eq!(alarms[0].zone, "Pond");
    assert_eq!(alarms[0].since_s, 0.0);

    // Out for less than the clearing time and back in: the same alarm, nothing logged.
    predict(&mut c, outside, outside);
    c.tick(5.0);
    c.tick(5.0 + CLEAR_AFTER_S - 0.5);
    predict(&mut c, outside, inside);
    c.tick(10.0);
    assert_eq!(events(&mut c), []);
    assert_eq!(c.state_msg_now(10.0).keep_out_alarms, alarms);

    // The planned landing too: its own alarm beside the other.
    predict(&mut c, inside, inside);
    c.tick(11.0);
    let logged = events(&mut c);
    assert_eq!(
        logged,
        [(
            Level::Warning,
            "planned landing predicted inside keep-out zone 'Pond'".to_string()
        )]
    );
    assert_eq!(c.state_msg_now(11.0).keep_out_alarms.len(), 2);

    // Out for good: each clears once, after the clearing time.
    predict(&mut c, outside, outside);
    let mut t = 12.0;
    while t < 12.0 + 3.0 * CLEAR_AFTER_S {
        c.tick(t);
        if t < 12.0 + CLEAR_AFTER_S - 0.25 {
            assert_eq!(c.state_msg_now(t).keep_out_alarms.len(), 2, "at {t}");
        }
        t += 0.25;
    }
    let logged = events(&mut c);
    assert_eq!(
        logged,
        [
            (
                Level::Info,
                "planned landing prediction clear of keep-out zone 'Pond'".to_string()
            ),
            (
                Level::Info,
                "uncontrolled landing prediction clear of keep-out zone 'Pond'".to_string()
            ),
        ]
    );
    assert!(c.state_msg_now(t).keep_out_alarms.is_empty());
}

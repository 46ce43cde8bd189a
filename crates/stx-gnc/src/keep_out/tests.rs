use super::*;

/// The mission frame at a field in Slovakia (any place works; the zones are placed in it).
fn frame() -> LocalFrame {
    LocalFrame {
        lat_deg: 48.0,
        lon_deg: 17.0,
        alt_msl_m: 200.0,
    }
}

/// A square `[lon, lat]` ring `half_m` either side of (north, east) `centre_m` in `frame()`.
fn square(centre_m: [f64; 2], half_m: f64) -> String {
    let f = frame();
    let corners = [
        [-half_m, -half_m],
        [-half_m, half_m],
        [half_m, half_m],
        [half_m, -half_m],
        [-half_m, -half_m],
    ];
    let positions: Vec<String> = corners
        .iter()
        .map(|[n, e]| {
            let (lat, lon, _) = f.to_geodetic(&nalgebra::Vector3::new(
                centre_m[0] + n,
                centre_m[1] + e,
                0.0,
            ));
            format!("[{lon}, {lat}]")
        })
        .collect();
    format!("[{}]", positions.join(", "))
}

fn geometry(kind: &str, coordinates: &str) -> String {
    format!(r#"{{"type": "{kind}", "coordinates": {coordinates}}}"#)
}

fn feature(name: &str, geometry: &str) -> String {
    format!(r#"{{"type": "Feature", "properties": {{"name": "{name}"}}, "geometry": {geometry}}}"#)
}

fn collection(features: &[String]) -> String {
    format!(
        r#"{{"type": "FeatureCollection", "features": [{}]}}"#,
        features.join(", ")
    )
}

#[test]
fn a_pond_north_of_the_target_holds_its_points_and_blocks_legs_across_it() {
    let pond = feature(
        "pond",
        &geometry("Polygon", &format!("[{}]", square([200.0, 0.0], 50.0))),
    );
    let zones = from_geojson(&collection(&[pond]), &frame()).expect("zones");
    assert_eq!(zones.zones.len(), 1);
    assert_eq!(zones.zones[0].name, "pond");
    assert_eq!(
        zones.zone_at([200.0, 0.0]).map(|z| z.name.as_str()),
        Some("pond")
    );
    assert!(zones.zone_at([240.0, 40.0]).is_some());
    assert!(zones.zone_at([260.0, 0.0]).is_none());
    assert!(zones.zone_at([0.0, 0.0]).is_none());
    // Flattening is centimetres off at this size: the corners are where they were put.
    let corner = zones.zones[0].rings_ne_m[0][0];
    assert!(
        (corner[0] - 150.0).abs() < 0.05 && (corner[1] + 50.0).abs() < 0.05,
        "{corner:?}"
    );
    // A leg straight through, both ends outside; one beside it; one ending inside.
    assert!(zones.crossed_by([0.0, 0.0], [400.0, 0.0]).is_some());
    assert!(zones.crossed_by([0.0, 80.0], [400.0, 80.0]).is_none());
    assert!(zones.crossed_by([0.0, 0.0], [190.0, 10.0]).is_some());
}

#[test]
fn a_hole_is_outside_and_each_polygon_of_a_multipolygon_is_a_zone() {
    let ring_with_hole = format!(
        "[{}, {}]",
        square([0.0, 0.0], 100.0),
        square([0.0, 0.0], 30.0)
    );
    let lone_tree_patch = format!("[{}]", square([0.0, 500.0], 20.0));
    let multi = feature(
        "woods",
        &geometry(
            "MultiPolygon",
            &format!("[{ring_with_hole}, {lone_tree_patch}]"),
        ),
    );
    let zones = from_geojson(&collection(&[multi]), &frame()).expect("zones");
    assert_eq!(zones.zones.len(), 2);
    assert!(
        zones.zone_at([0.0, 0.0]).is_none(),
        "the clearing in the woods"
    );
    assert!(zones.zone_at([60.0, 0.0]).is_some());
    assert!(zones.zone_at([0.0, 500.0]).is_some());
    // A leg from the clearing out of the woods crosses the hole's edge.
    assert!(zones.crossed_by([0.0, 0.0], [0.0, 20.0]).is_none());
    assert!(zones.crossed_by([0.0, 0.0], [0.0, 200.0]).is_some());
}

#[test]
fn a_bare_geometry_is_a_zone_named_by_its_place_in_the_file() {
    let text = geometry("Polygon", &format!("[{}]", square([0.0, 0.0], 10.0)));
    let zones = from_geojson(&text, &frame()).expect("zones");
    assert_eq!(zones.zones[0].name, "zone 0");
}

#[test]
fn a_simple_ring_with_a_repeated_corner_or_a_concave_notch_is_an_area() {
    // A notch (concave) and a corner given twice in a row, as some GIS exports write them.
    let notched = r#"{"type": "Polygon", "coordinates": [[[17.0, 48.0], [17.02, 48.0], [17.02, 48.0], [17.02, 48.02], [17.01, 48.005], [17.0, 48.02], [17.0, 48.0]]]}"#;
    let zones = from_geojson(notched, &frame()).expect("a simple ring");
    assert_eq!(zones.zones.len(), 1);
}

#[test]
fn files_that_are_not_areas_on_the_globe_are_refused_with_the_rule_broken() {
    let f = frame();
    let err = |text: &str| from_geojson(text, &f).expect_err(text);
    assert!(matches!(err("{not json"), KeepOutError::Parse(_)));
    assert!(matches!(
        err(&collection(&[feature(
            "road",
            r#"{"type": "LineString", "coordinates": [[17.0, 48.0], [17.01, 48.0]]}"#
        )])),
        KeepOutError::NotAnArea { feature: 0, .. }
    ));
    let open_ring = r#"{"type": "Polygon", "coordinates": [[[17.0, 48.0], [17.01, 48.0], [17.01, 48.01], [17.0, 48.01]]]}"#;
    assert!(matches!(
        err(open_ring),
        KeepOutError::Ring { ring: 0, reason, .. } if reason.contains("not closed")
    ));
    let short_ring =
        r#"{"type": "Polygon", "coordinates": [[[17.0, 48.0], [17.01, 48.0], [17.0, 48.0]]]}"#;
    assert!(matches!(err(short_ring), KeepOutError::Ring { .. }));
    // A bow tie (two corners swapped) and a ring whose edge runs back onto another's corner.
    let bow_tie = r#"{"type": "Polygon", "coordinates": [[[17.0, 48.0], [17.01, 48.01], [17.0, 48.01], [17.01, 48.0], [17.0, 48.0]]]}"#;
    assert!(matches!(
        err(bow_tie),
        KeepOutError::Ring { ring: 0, reason, .. } if reason.contains("crosses itself")
    ));
    let touching = r#"{"type": "Polygon", "coordinates": [[[17.0, 48.0], [17.02, 48.0], [17.01, 48.0], [17.01, 48.01], [17.0, 48.0]]]}"#;
    assert!(
        matches!(err(touching), KeepOutError::Ring { reason, .. } if reason.contains("crosses itself"))
    );
    let off_globe = r#"{"type": "Polygon", "coordinates": [[[17.0, 48.0], [17.01, 95.0], [17.01, 48.01], [17.0, 48.0]]]}"#;
    assert!(matches!(err(off_globe), KeepOutError::Position { lat, .. } if lat == 95.0));
    let message = err(off_globe).to_string();
    assert!(message.contains("latitude"), "{message}");
}

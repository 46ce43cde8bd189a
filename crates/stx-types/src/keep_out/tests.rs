use super::*;

/// A square ring `half_m` either side of (north, east) `centre_m`, counter-clockwise.
fn square(centre_m: [f64; 2], half_m: f64) -> Vec<[f64; 2]> {
    [[-1.0, -1.0], [-1.0, 1.0], [1.0, 1.0], [1.0, -1.0]]
        .iter()
        .map(|[n, e]| [centre_m[0] + n * half_m, centre_m[1] + e * half_m])
        .collect()
}

#[test]
fn a_point_in_the_hole_is_outside_and_legs_into_the_zone_cross_it() {
    let woods = KeepOutZone {
        name: "woods".into(),
        rings_ne_m: vec![square([0.0, 0.0], 100.0), square([0.0, 0.0], 30.0)],
    };
    let zones = KeepOutZones { zones: vec![woods] };
    assert!(zones.zone_at([60.0, 0.0]).is_some());
    assert!(zones.zone_at([0.0, 0.0]).is_none(), "the clearing");
    assert!(zones.zone_at([150.0, 0.0]).is_none());
    // Within the clearing; out through the trees; beside the woods.
    assert!(zones.crossed_by([0.0, 0.0], [0.0, 20.0]).is_none());
    assert!(zones.crossed_by([0.0, 0.0], [0.0, 200.0]).is_some());
    assert!(zones.crossed_by([-200.0, 150.0], [200.0, 150.0]).is_none());
    // Both ends outside, straight across.
    assert!(zones.crossed_by([-200.0, 50.0], [200.0, 50.0]).is_some());
}

#[test]
fn a_bow_tie_crosses_itself_and_a_repeated_corner_does_not() {
    let bow_tie = [[0.0, 0.0], [10.0, 10.0], [10.0, 0.0], [0.0, 10.0]];
    assert!(ring_crosses_itself(&bow_tie));
    let mut doubled = square([0.0, 0.0], 10.0);
    doubled.insert(1, doubled[1]);
    assert!(!ring_crosses_itself(&doubled));
}

#[test]
fn the_boundary_goes_back_to_latitude_and_longitude_in_its_frame() {
    let frame = LocalFrame::default();
    let zone = KeepOutZone {
        name: "field".into(),
        rings_ne_m: vec![square([500.0, -300.0], 50.0)],
    };
    let boundary = zone.boundary_lat_lon(&frame);
    assert_eq!(boundary.len(), 4);
    for (lat_lon, ne) in boundary.iter().zip(&zone.rings_ne_m[0]) {
        let back = frame.to_ned(lat_lon[0], lat_lon[1], frame.alt_msl_m);
        assert!((back.x - ne[0]).abs() < 1e-6 && (back.y - ne[1]).abs() < 1e-6);
    }
}

//! stx reads what ecCodes reads (to [`ECCODES_TOLERANCE`]), on the files of `testdata/`:
//! ecCodes' readings are committed (`eccodes_reads.json`, made by `make_fixtures.py`), so this
//! needs no Python. The real GFS message checks GFS' own packing of a global 0.25° grid.

use serde_json::Value;

use crate::common::{
    ECCODES_TOLERANCE, compare_decoding, field, key, level_pa, parameter, testdata,
};

fn readings() -> Value {
    serde_json::from_str(&std::fs::read_to_string(testdata("eccodes_reads.json")).unwrap()).unwrap()
}

#[test]
fn eccodes_2_50_values_equal_stx_decoding_on_every_fixture_and_the_real_gfs_message() {
    let r = readings();
    assert_eq!(r["eccodes"], "2.50.0");
    for (name, expected_points) in [
        ("gfs_0p25_subset.grib2", 99 * 16),
        ("gfs_0p50_simple.grib2", 24 * 16),
        ("gdas.t12z.pgrb2.0p25.f000.12", 1000),
    ] {
        let messages = r["files"][name].as_array().unwrap();
        let compared = compare_decoding(name, messages);
        assert!(
            compared >= expected_points * 9 / 10,
            "{name}: {compared} values compared"
        );
    }
}

#[test]
fn eccodes_2_50_values_equal_the_wind_field_at_its_grid_points() {
    let r = readings();
    for name in ["gfs_0p25_subset.grib2", "gfs_0p50_simple.grib2"] {
        let f = field(name);
        let (nj, ni) = f.shape();
        let hours: Vec<i64> = f
            .valid_times()
            .iter()
            .map(|t| (*t - f.reference_time()).whole_hours())
            .collect();
        let mut compared = 0;
        for m in r["files"][name].as_array().unwrap() {
            let variable = match parameter(m["short_name"].as_str().unwrap()) {
                Some((2, 2)) => 0,
                Some((2, 3)) => 1,
                _ => 2,
            };
            let t = hours
                .iter()
                .position(|&h| h == m["step_hours"].as_i64().unwrap())
                .unwrap();
            let k = f
                .levels_pa()
                .iter()
                .position(|&p| (p - level_pa(m)).abs() < 1e-6)
                .unwrap();
            for p in m["points"].as_array().unwrap() {
                let want = key(p[0].as_f64().unwrap(), p[1].as_f64().unwrap());
                let (j, i) = (0..nj)
                    .flat_map(|j| (0..ni).map(move |i| (j, i)))
                    .find(|&(j, i)| {
                        let (lat, lon) = f.grid_point_deg(j, i);
                        key(lat, lon) == want
                    })
                    .unwrap();
                let got = f64::from(f.at_grid_point(t, k, j, i)[variable]);
                let expected = p[2].as_f64().unwrap();
                assert!(
                    (got - expected).abs() <= ECCODES_TOLERANCE,
                    "{name} {} step {t} level {k} ({j}, {i}): stx {got}, ecCodes {expected}",
                    m["short_name"]
                );
                compared += 1;
            }
        }
        assert!(compared > 300, "{name}: {compared}");
    }
}

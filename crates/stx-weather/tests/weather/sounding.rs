//! University of Wyoming soundings (`TEXT:LIST`): the page as saved, its winds in SI units,
//! heights made geometric, lines without a wind skipped and counted; bad tables refused
//! naming the line. The sounding in `testdata/72520_sounding.txt` follows the site's layout
//! (columns, header, units, the `</PRE>` after the table and the station block); its numbers
//! are made up.

use stx_weather::{Sounding, geometric_height_m};

use crate::common::testdata;

fn page() -> String {
    std::fs::read_to_string(testdata("72520_sounding.txt")).unwrap()
}

#[test]
fn a_wyoming_page_gives_one_level_per_line_with_a_wind() {
    let s = Sounding::parse(&page()).unwrap();
    // 18 rows: 1000 hPa (below ground, no wind) and 7 hPa (no wind) skipped.
    assert_eq!(s.levels.len(), 16);
    assert_eq!(s.skipped_lines, 2);
    let first = s.levels[0];
    assert_eq!(first.pressure_pa, Some(97_700.0));
    assert!((first.alt_msl_m - geometric_height_m(360.0)).abs() < 1e-9);
    // 8 knots from 250°: 4.1156 m/s towards 70°.
    assert!((first.speed_mps() - 8.0 * 1852.0 / 3600.0).abs() < 1e-9);
    assert!((first.from_deg() - 250.0).abs() < 1e-9);
    assert!(first.east_mps > 0.0 && first.north_mps > 0.0);
    let top = s.levels[15];
    assert!((top.alt_msl_m - geometric_height_m(31_060.0)).abs() < 1e-9);
    assert!((top.from_deg() - 80.0).abs() < 1e-9);
}

#[test]
fn the_table_reads_without_its_markup_and_with_windows_line_ends() {
    let text: String = page()
        .lines()
        .filter(|l| !l.contains('<'))
        .map(|l| format!("{l}\r\n"))
        .collect();
    assert_eq!(
        Sounding::parse(&text).unwrap(),
        Sounding::parse(&page()).unwrap()
    );
}

#[test]
fn bad_tables_are_refused_naming_the_line_and_column() {
    let page = page();
    let cases = [
        ("no table here", "no sounding table"),
        (
            &page.replace("   DRCT", "   WDIR"),
            "line 7: the table has no DRCT column",
        ),
        (
            &page.replace("  925.0    802", "  925.0    8x2"),
            "line 12: HGHT is not a number: `8x2`",
        ),
        (
            &page.replace("    265     23", "    365     23"),
            "line 12: DRCT = 365 is out of range",
        ),
        (
            &page
                .lines()
                .filter(|l| !l.contains("  0.") || l.contains("PRES"))
                .filter(|l| l.len() < 60 || l.contains("PRES"))
                .collect::<Vec<_>>()
                .join("\n"),
            "no line with a height, a wind direction and a speed",
        ),
    ];
    for (text, expected) in cases {
        let e = Sounding::parse(text).unwrap_err().to_string();
        assert!(e.contains(expected), "{expected}: {e}");
    }
}

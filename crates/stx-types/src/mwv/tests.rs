//! MWV against sentences as instruments write them (each checksum worked out apart from this
//! code), against what they must refuse, and against arbitrary lines.

use proptest::prelude::*;

use super::*;

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() < 1e-9
}

/// The difference of two directions, degrees, in 0..=180.
fn angle_apart(a: f64, b: f64) -> f64 {
    let d = (a - b).rem_euclid(360.0);
    d.min(360.0 - d)
}

#[test]
fn sentences_in_each_unit_are_read_and_converted_to_m_per_s() {
    // The checksum of the m/s sentence by hand: in "WIMWV,235.0,T,3.4,M,A" the pairs W W, M M,
    // 3 3, . . and four of the five commas cancel, leaving I V , 2 5 0 T 4 A:
    // 49^56 = 1F, ^2C = 33, ^32 = 01, ^35 = 34, ^30 = 04, ^54 = 50, ^34 = 64, ^41 = 25.
    // The others were XORed the same way by a short script, not by `checksum`.
    let cases = [
        (
            "$WIMWV,214.8,R,0.1,K,A*28",
            214.8,
            MwvReference::Relative,
            0.1 / 3.6,
        ),
        ("$WIMWV,235.0,T,3.4,M,A*25", 235.0, MwvReference::True, 3.4),
        (
            "$IIMWV,045.0,R,10.2,N,A*0F",
            45.0,
            MwvReference::Relative,
            10.2 * 0.514_444,
        ),
        (
            "$WIMWV,310.2,T,8.1,S,A*31",
            310.2,
            MwvReference::True,
            8.1 * 0.447_04,
        ),
    ];
    for (line, from_deg, reference, speed_mps) in cases {
        let r = parse_mwv(line).expect(line);
        assert!(close(r.from_deg, from_deg), "{line}: {r:?}");
        assert_eq!(r.reference, reference, "{line}");
        // The knot's factor above is rounded to six figures.
        assert!((r.speed_mps - speed_mps).abs() < 1e-5, "{line}: {r:?}");
    }
}

#[test]
fn line_endings_lowercase_checksums_and_a_missing_checksum_are_accepted() {
    let expected = parse_mwv("$WIMWV,235.0,T,3.4,M,A*25").expect("valid");
    for line in [
        "$WIMWV,235.0,T,3.4,M,A*25\r\n",
        "  $WIMWV,235.0,T,3.4,M,A*25 \n",
        "$WIMWV,235.0,T,3.4,M,A",
        "$WIMWV,235.0,T,3.4,M,A\r\n",
    ] {
        assert_eq!(parse_mwv(line), Ok(expected), "{line:?}");
    }
    // Another talker, the same checksum rule: "IIMWV,045.0,R,10.2,N,A" is 0F.
    assert!(parse_mwv("$IIMWV,045.0,R,10.2,N,A*0f").is_ok());
}

#[test]
fn a_wrong_checksum_is_refused_and_says_both_values() {
    let err = parse_mwv("$WIMWV,235.0,T,3.4,M,A*26").expect_err("corrupted");
    assert_eq!(
        err,
        MwvError::Checksum {
            given: 0x26,
            computed: 0x25
        }
    );
    let text = err.to_string();
    assert!(text.contains("26") && text.contains("25"), "{text}");
    // One character changed on the way, the checksum as sent.
    let err = parse_mwv("$WIMWV,236.0,T,3.4,M,A*25").expect_err("corrupted");
    assert!(matches!(err, MwvError::Checksum { .. }), "{err}");
}

#[test]
fn status_v_and_empty_fields_are_no_data() {
    // "WIMWV,,R,,M,V" XORs to 37; an instrument flagging invalid data may fill fields anyway.
    for line in [
        "$WIMWV,,R,,M,V*37",
        "$WIMWV,123.0,T,9.9,M,V",
        "$WIMWV,999,X,,Q,V",
        "$WIMWV,,T,,M,A",
        "$WIMWV,120.0,T,,M,A",
    ] {
        assert_eq!(parse_mwv(line), Err(MwvError::NoData), "{line}");
    }
}

#[test]
fn sentences_of_other_types_are_not_mwv() {
    // "WIXDR,C,12.3,C,TEMP" XORs to 42: a well-formed temperature from the same station.
    for line in [
        "$WIXDR,C,12.3,C,TEMP*42",
        "$GPGGA,123519,4807.038,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,",
        "$PGRMZ,246,f,3",
        "!AIVDM,1,1,,A,13aEOK?P00PD2wVMdLDRhgvL289?,0",
    ] {
        assert_eq!(parse_mwv(line), Err(MwvError::NotMwv), "{line}");
    }
}

#[test]
fn garbage_is_malformed() {
    let long = format!("$WIMWV,235.0,T,3.4,M,A{}", ",".repeat(80));
    for line in [
        "",
        "   \r\n",
        "hello",
        "WIMWV,235.0,T,3.4,M,A*25",
        "$",
        "$*00",
        "$,235.0,T,3.4,M,A",
        "$wimwv,235.0,T,3.4,M,A",
        "$WIMW,235.0,T,3.4,M,A",
        "$WIMWV,235.0,T,3.4,M,A*2",
        "$WIMWV,235.0,T,3.4,M,A*2G",
        "$WIMWV,235.0,T,3.4,M,A*255",
        "$WIMWV,235.0°,T,3.4,M,A",
        "$WIMWV,235.0,T,3.4,M,A,extra",
        "$WIMWV,235.0,T,3.4,M,A$WIMWV,235.0,T,3.4,M,A",
        long.as_str(),
    ] {
        let err = parse_mwv(line).expect_err(line);
        assert!(
            matches!(err, MwvError::Malformed { .. }),
            "{line:?}: {err:?}"
        );
    }
}

#[test]
fn angles_and_speeds_out_of_range_or_not_numbers_are_refused_by_field() {
    let cases = [
        ("$WIMWV,-5.0,T,3.4,M,A", "angle"),
        ("$WIMWV,360.0,T,3.4,M,A", "angle"),
        ("$WIMWV,400,T,3.4,M,A", "angle"),
        ("$WIMWV,NaN,T,3.4,M,A", "angle"),
        ("$WIMWV,inf,T,3.4,M,A", "angle"),
        ("$WIMWV,2e2,T,3.4,M,A", "angle"),
        ("$WIMWV,1.2.3,T,3.4,M,A", "angle"),
        ("$WIMWV,235.0,T,-0.5,M,A", "speed"),
        ("$WIMWV,235.0,T,NaN,M,A", "speed"),
        ("$WIMWV,235.0,T,-,M,A", "speed"),
        // 400 knots is 206 m/s: no surface wind is that fast.
        ("$WIMWV,235.0,T,400,N,A", "speed"),
        ("$WIMWV,235.0,X,3.4,M,A", "reference"),
        ("$WIMWV,235.0,,3.4,M,A", "reference"),
        ("$WIMWV,235.0,T,3.4,B,A", "unit"),
        ("$WIMWV,235.0,T,3.4,m,A", "unit"),
        ("$WIMWV,235.0,T,3.4,M,Q", "status"),
        ("$WIMWV,235.0,T,3.4,M", "status"),
        ("$WIMWV,235.0,T", "speed"),
    ];
    for (line, expected) in cases {
        match parse_mwv(line) {
            Err(MwvError::Field { field, .. }) => assert_eq!(field, expected, "{line}"),
            other => panic!("{line}: {other:?}"),
        }
    }
    let text = parse_mwv("$WIMWV,400,T,3.4,M,A")
        .expect_err("out of range")
        .to_string();
    assert!(
        text.contains("angle") && text.contains("\"400\"") && text.contains("below 360"),
        "{text}"
    );
}

#[test]
fn formatting_writes_one_decimal_in_m_per_s_with_its_checksum() {
    assert_eq!(
        format_mwv(235.0, MwvReference::True, 3.4),
        "$WIMWV,235.0,T,3.4,M,A*25\r\n"
    );
    // Wrapped into 0..360, and never written as 360.0, which no reader accepts.
    assert!(format_mwv(-90.0, MwvReference::True, 1.0).starts_with("$WIMWV,270.0,T,1.0,"));
    assert!(format_mwv(359.96, MwvReference::True, 1.0).starts_with("$WIMWV,0.0,T,"));
    assert!(format_mwv(-0.0, MwvReference::Relative, -0.0).starts_with("$WIMWV,0.0,R,0.0,"));
    // A reading the instrument does not have is the no-data sentence ("WIMWV,,T,,M,V": 31).
    for (from_deg, speed_mps) in [(f64::NAN, 1.0), (10.0, -1.0), (10.0, f64::INFINITY)] {
        let line = format_mwv(from_deg, MwvReference::True, speed_mps);
        assert_eq!(line, "$WIMWV,,T,,M,V*31\r\n");
        assert_eq!(parse_mwv(&line), Err(MwvError::NoData));
    }
}

#[test]
fn what_is_formatted_reads_back() {
    for (from_deg, reference, speed_mps) in [
        (0.0, MwvReference::True, 0.0),
        (12.34, MwvReference::Relative, 7.89),
        (359.94, MwvReference::True, MAX_SPEED_MPS),
    ] {
        let line = format_mwv(from_deg, reference, speed_mps);
        let r = parse_mwv(&line).expect(&line);
        assert!(angle_apart(r.from_deg, from_deg) <= 0.05, "{line}");
        assert!((r.speed_mps - speed_mps).abs() <= 0.05, "{line}");
        assert_eq!(r.reference, reference);
    }
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 2048,
        rng_seed: proptest::test_runner::RngSeed::Fixed(0x3A17),
        ..ProptestConfig::default()
    })]

    #[test]
    fn arbitrary_lines_never_panic(line in any::<String>()) {
        let _ = parse_mwv(&line);
    }

    /// Lines close to MWV reach the field checks, where any arbitrary string stops early.
    #[test]
    fn near_mwv_lines_never_panic(
        line in "[$!]?[A-Z]{2}MWV(,[-0-9.A-Za-z]{0,7}){0,7}(\\*[0-9A-Fa-f]{0,3})?\r?\n?"
    ) {
        if let Ok(r) = parse_mwv(&line) {
            prop_assert!((0.0..360.0).contains(&r.from_deg));
            prop_assert!((0.0..=MAX_SPEED_MPS).contains(&r.speed_mps));
        }
    }

    #[test]
    fn format_then_parse_round_trips_within_a_twentieth(
        from_deg in -720.0..720.0_f64,
        relative in any::<bool>(),
        speed_mps in 0.0..MAX_SPEED_MPS,
    ) {
        let reference = if relative { MwvReference::Relative } else { MwvReference::True };
        let line = format_mwv(from_deg, reference, speed_mps);
        let r = parse_mwv(&line).map_err(|e| TestCaseError::fail(format!("{line:?}: {e}")))?;
        prop_assert!(angle_apart(r.from_deg, from_deg) <= 0.05 + 1e-9, "{} {}", line, from_deg);
        prop_assert!((r.speed_mps - speed_mps).abs() <= 0.05 + 1e-9, "{} {}", line, speed_mps);
        prop_assert_eq!(r.reference, reference);
    }
}

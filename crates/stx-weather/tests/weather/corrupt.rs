//! Corrupt GRIB2 files never panic: truncated or with bytes overwritten anywhere (section
//! lengths, grid sizes, packing parameters, data), the field is refused with an error, or read
//! if the damage fell on values.

use proptest::prelude::*;
use stx_weather::GfsField;

use crate::common::bytes;

proptest! {
    #![proptest_config(ProptestConfig { cases: 200, ..ProptestConfig::default() })]

    #[test]
    fn truncated_or_overwritten_bytes_give_an_error_or_a_field_never_a_panic(
        cut in 0usize..9048,
        hits in proptest::collection::vec((0usize..9048, any::<u8>()), 0..8),
    ) {
        let mut b = bytes("gfs_0p50_simple.grib2");
        for (at, byte) in hits {
            b[at % 9048] = byte;
        }
        b.truncate(cut.max(1));
        let _ = GfsField::from_files([("corrupt", b.as_slice())]);
    }
}

#[test]
fn a_message_claiming_a_huge_grid_is_refused_before_allocating() {
    let mut b = bytes("no_hgt.grib2");
    // Section 3 follows sections 0 (16 bytes) and 1 (its length in its first 4 bytes); its
    // number of data points is at octets 7–10.
    let s1 = u32::from_be_bytes(b[16..20].try_into().unwrap()) as usize;
    let s3 = 16 + s1;
    assert_eq!(b[s3 + 4], 3, "section 3");
    b[s3 + 6..s3 + 10].copy_from_slice(&u32::MAX.to_be_bytes());
    let e = GfsField::from_files([("huge", b.as_slice())])
        .unwrap_err()
        .to_string();
    assert!(e.contains("grid points"), "{e}");
}

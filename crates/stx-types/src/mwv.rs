//! NMEA 0183 `MWV` (wind speed and angle), the sentence marine and weather-station
//! anemometers send: [`parse_mwv`] reads one line as the station receives it, [`format_mwv`]
//! writes one as the simulated ground anemometer sends it.
//!
//! `$--MWV,<angle>,<R|T>,<speed>,<K|M|N|S>,<A|V>*hh`: any two-character talker, the angle the
//! wind blows from (degrees clockwise from the instrument's zero mark, R, or from true north,
//! T), the speed in km/h, m/s, knots or statute mph, the status (V: the instrument says its
//! data are invalid) and an optional checksum, checked when present.
//!
//! Hand-written rather than taken from an NMEA crate: one sentence of five fields is less code
//! than an adapter to a general decoder, and this crate, at the bottom of the graph, keeps its
//! few dependencies. Nothing a line holds can panic, and every refusal says which field and
//! why (the fields are short, and a line longer than NMEA allows is refused whole).

/// Longest sentence NMEA 0183 allows, `$` to the checksum's last digit (82 with CR LF): a
/// longer line is not NMEA, and the cap bounds what an error copies from it.
pub const MAX_SENTENCE_LEN: usize = 80;

/// Fastest wind accepted, m/s: above the strongest surface gust ever measured (113 m/s,
/// Barrow Island, 1996), so a faster reading is a broken instrument or a garbled field.
pub const MAX_SPEED_MPS: f64 = 150.0;

/// Which zero the angle is measured from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MwvReference {
    /// From the instrument's zero mark (`R`); on a fixed mast, wherever it was pointed.
    Relative,
    /// From true north (`T`).
    True,
}

impl MwvReference {
    /// The letter NMEA writes.
    fn letter(self) -> char {
        match self {
            Self::Relative => 'R',
            Self::True => 'T',
        }
    }
}

/// One valid reading.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MwvReading {
    /// Where the wind comes from, degrees clockwise from the reference, in 0..360.
    pub from_deg: f64,
    /// What the angle is measured from.
    pub reference: MwvReference,
    /// Wind speed, m/s (converted from the sentence's unit), ≥ 0.
    pub speed_mps: f64,
}

/// Why a line is not a valid MWV reading.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum MwvError {
    /// A well-formed NMEA sentence of another type (`$WIXDR`, a proprietary `$P…`): not an
    /// error of the line, only not wind; callers skip it.
    #[error("an NMEA sentence of another type than MWV")]
    NotMwv,
    /// The checksum after `*` does not match the sentence's characters: corrupted on the way.
    #[error(
        "checksum mismatch: the sentence says {given:02X}, its characters give {computed:02X} \
         (corrupted on the line)"
    )]
    Checksum {
        /// The checksum written after `*`.
        given: u8,
        /// The XOR of the characters between `$` and `*`.
        computed: u8,
    },
    /// A field is missing or holds what MWV does not allow.
    #[error("MWV field {field} is {value:?}: {}", field_rule(field))]
    Field {
        /// The field's name: `angle`, `reference`, `speed`, `unit` or `status`.
        field: &'static str,
        /// What it held (empty when missing; cut to a few characters).
        value: String,
    },
    /// The instrument marks its data invalid (status V) or leaves angle or speed empty.
    #[error("the anemometer reports no valid wind (status V or empty fields)")]
    NoData,
    /// Not an NMEA sentence at all.
    #[error("not an NMEA 0183 sentence: {reason}")]
    Malformed {
        /// What is wrong with it.
        reason: &'static str,
    },
}

/// What a field must hold, for [`MwvError::Field`]'s message.
fn field_rule(field: &str) -> &'static str {
    match field {
        "angle" => "expected degrees, at least 0 and below 360",
        "reference" => "expected R (relative) or T (true)",
        "speed" => "expected a speed at least 0 and at most 150 m/s",
        "unit" => "expected K (km/h), M (m/s), N (knots) or S (mph)",
        "status" => "expected A (valid) or V (invalid)",
        _ => "not allowed here",
    }
}

/// Most characters of a bad field an error keeps: enough to recognise it in a log.
const FIELD_SHOWN: usize = 16;

fn bad_field(field: &'static str, value: &str) -> MwvError {
    MwvError::Field {
        field,
        value: value.chars().take(FIELD_SHOWN).collect(),
    }
}

fn malformed(reason: &'static str) -> MwvError {
    MwvError::Malformed { reason }
}

/// The NMEA checksum: XOR of every byte between `$` and `*`.
fn checksum(body: &[u8]) -> u8 {
    body.iter().fold(0, |x, b| x ^ b)
}

/// Reads one MWV sentence, as a line from the instrument (surrounding whitespace and CR LF
/// allowed, any talker, checksum optional but checked when present).
pub fn parse_mwv(line: &str) -> Result<MwvReading, MwvError> {
    let line = line.trim();
    if line.len() > MAX_SENTENCE_LEN {
        return Err(malformed("longer than the 82 characters NMEA allows"));
    }
    // `!` starts NMEA's encapsulated sentences (AIS): well-formed, never wind.
    let Some(rest) = line.strip_prefix('$').or_else(|| line.strip_prefix('!')) else {
        return Err(malformed("does not start with $"));
    };
    let (body, given) = match rest.split_once('*') {
        Some((body, hex)) => (body, Some(hex)),
        None => (rest, None),
    };
    // Printable ASCII only, as NMEA allows (this also makes byte offsets character offsets),
    // and no second `$` or `!`: two sentences run together when a line ending was lost.
    if !body
        .bytes()
        .all(|b| (0x20..0x7f).contains(&b) && b != b'$' && b != b'!')
    {
        return Err(malformed("holds characters NMEA does not allow"));
    }
    if let Some(hex) = given {
        if hex.len() != 2 || !hex.bytes().all(|b| b.is_ascii_hexdigit()) {
            return Err(malformed(
                "the checksum after * is not two hexadecimal digits",
            ));
        }
        let given = u8::from_str_radix(hex, 16).map_err(|_| malformed("bad checksum digits"))?;
        let computed = checksum(body.as_bytes());
        if given != computed {
            return Err(MwvError::Checksum { given, computed });
        }
    }
    let mut fields = body.split(',');
    let address = fields.next().unwrap_or_default();
    if address.is_empty()
        || !address
            .bytes()
            .all(|b| b.is_ascii_uppercase() || b.is_ascii_digit())
    {
        return Err(malformed("no sentence address (talker and type) after $"));
    }
    // Proprietary sentences ($P + maker) have addresses of their own length.
    if line.starts_with('!') || address.starts_with('P') {
        return Err(MwvError::NotMwv);
    }
    if address.len() != 5 {
        return Err(malformed(
            "the address is not a talker and a three-letter type",
        ));
    }
    if &address[2..] != "MWV" {
        return Err(MwvError::NotMwv);
    }
    let mut next = |name: &'static str| fields.next().ok_or_else(|| bad_field(name, ""));
    let (angle, reference, speed, unit, status) = (
        next("angle")?,
        next("reference")?,
        next("speed")?,
        next("unit")?,
        next("status")?,
    );
    if fields.next().is_some() {
        return Err(malformed("MWV has five fields, this sentence more"));
    }
    // The status first: an instrument that says its data are invalid may fill the others
    // with anything.
    match status {
        "A" => {}
        "V" => return Err(MwvError::NoData),
        other => return Err(bad_field("status", other)),
    }
    if angle.is_empty() || speed.is_empty() {
        return Err(MwvError::NoData);
    }
    let reference = match reference {
        "R" => MwvReference::Relative,
        "T" => MwvReference::True,
        other => return Err(bad_field("reference", other)),
    };
    let mps_per_unit = match unit {
        "K" => 1.0 / 3.6,
        "M" => 1.0,
        "N" => 1852.0 / 3600.0,
        "S" => 1609.344 / 3600.0,
        other => return Err(bad_field("unit", other)),
    };
    let from_deg = decimal(angle)
        .filter(|a| (0.0..360.0).contains(a))
        .ok_or_else(|| bad_field("angle", angle))?;
    let speed_mps = decimal(speed)
        .map(|s| s * mps_per_unit)
        .filter(|s| (0.0..=MAX_SPEED_MPS).contains(s))
        .ok_or_else(|| bad_field("speed", speed))?;
    // `-0.0` passes the range checks; `abs` keeps the sign of zero out of what callers print.
    Ok(MwvReading {
        from_deg: from_deg.abs(),
        reference,
        speed_mps: speed_mps.abs(),
    })
}

/// An NMEA decimal field: digits with at most one point, optionally signed. Rust's own float
/// syntax is wider (`inf`, `NaN`, `1e3`), none of which an instrument sends.
fn decimal(text: &str) -> Option<f64> {
    let digits = text.strip_prefix('-').unwrap_or(text);
    let well_formed = digits.bytes().any(|b| b.is_ascii_digit())
        && digits.bytes().all(|b| b.is_ascii_digit() || b == b'.')
        && digits.bytes().filter(|&b| b == b'.').count() <= 1;
    well_formed.then(|| text.parse().ok()).flatten()
}

/// The MWV sentence of a wind blowing from `from_deg` (degrees clockwise from `reference`,
/// wrapped into 0..360) at `speed_mps` (m/s): talker `WI`, one decimal, m/s, with checksum
/// and CR LF, e.g. `$WIMWV,235.0,T,3.4,M,A*25\r\n`. A non-finite angle or a speed that is not a
/// finite number ≥ 0 gives the no-data sentence (status V, angle and speed empty), as an
/// instrument reports a reading it does not have.
pub fn format_mwv(from_deg: f64, reference: MwvReference, speed_mps: f64) -> String {
    let r = reference.letter();
    let body = if from_deg.is_finite() && speed_mps.is_finite() && speed_mps >= 0.0 {
        // Rounded to the tenth written, then wrapped, so that 359.96 is written 0.0 and
        // never 360.0, which no reader accepts; `abs` turns −0 into 0.
        let tenths = (from_deg.rem_euclid(360.0) * 10.0)
            .round()
            .rem_euclid(3600.0);
        let angle = (tenths / 10.0).abs();
        format!("WIMWV,{angle:.1},{r},{:.1},M,A", speed_mps.abs())
    } else {
        format!("WIMWV,,{r},,M,V")
    };
    format!("${body}*{:02X}\r\n", checksum(body.as_bytes()))
}

#[cfg(test)]
mod tests;

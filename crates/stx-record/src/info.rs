//! The metadata record at the start of every recording file: which station wrote it, for
//! which vehicle and mission, and who could command it.
//!
//! The type has fixed fields and no free-form map, and the people who hold access tokens
//! are given as the token objects themselves through [`Named`], of which only the name is
//! ever read: there is no field into which a token or a signing key could be passed.

use std::collections::BTreeMap;

/// Name of the MCAP metadata record stx writes in every file.
pub const METADATA_NAME: &str = "stx.recording";

/// Something with a public name beside a secret (an access token and its holder's name):
/// the recorder reads the name and nothing else.
pub trait Named {
    /// The public name (e.g. the person or screen a token was issued to).
    fn name(&self) -> &str;
}

impl<T: Named + ?Sized> Named for &T {
    fn name(&self) -> &str {
        (**self).name()
    }
}

/// What a recording is of, written as its metadata record.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct RecordingInfo {
    station_version: String,
    vehicle: String,
    mission: String,
    token_names: Vec<String>,
}

impl RecordingInfo {
    /// A recording by station `station_version` (e.g. `env!("CARGO_PKG_VERSION")`) of
    /// `vehicle` flying `mission`.
    pub fn new(
        station_version: impl Into<String>,
        vehicle: impl Into<String>,
        mission: impl Into<String>,
    ) -> Self {
        Self {
            station_version: station_version.into(),
            vehicle: vehicle.into(),
            mission: mission.into(),
            token_names: Vec::new(),
        }
    }

    /// Adds the names of the holders of `tokens` (the tokens themselves are not read).
    pub fn with_token_holders<T: Named>(mut self, tokens: impl IntoIterator<Item = T>) -> Self {
        self.token_names
            .extend(tokens.into_iter().map(|t| t.name().to_owned()));
        self
    }

    /// The station's version.
    pub fn station_version(&self) -> &str {
        &self.station_version
    }

    /// The vehicle's name.
    pub fn vehicle(&self) -> &str {
        &self.vehicle
    }

    /// The mission's name.
    pub fn mission(&self) -> &str {
        &self.mission
    }

    /// Names of the access tokens' holders.
    pub fn token_names(&self) -> &[String] {
        &self.token_names
    }

    /// The metadata record of file `part` (counted from 1) of a run.
    pub(crate) fn to_metadata(&self, part: u32) -> mcap::records::Metadata {
        let token_names =
            serde_json::to_string(&self.token_names).unwrap_or_else(|_| "[]".to_owned());
        let metadata = BTreeMap::from([
            ("station_version".to_owned(), self.station_version.clone()),
            ("vehicle".to_owned(), self.vehicle.clone()),
            ("mission".to_owned(), self.mission.clone()),
            ("token_names".to_owned(), token_names),
            ("part".to_owned(), part.to_string()),
        ]);
        mcap::records::Metadata {
            name: METADATA_NAME.to_owned(),
            metadata,
        }
    }

    /// Reads back what the recorder wrote, with the file's part number; `None` when
    /// the record is not stx's.
    pub fn from_metadata(record: &mcap::records::Metadata) -> Option<(Self, u32)> {
        if record.name != METADATA_NAME {
            return None;
        }
        let get = |k: &str| record.metadata.get(k).cloned().unwrap_or_default();
        let token_names = record
            .metadata
            .get("token_names")
            .and_then(|t| serde_json::from_str(t).ok())
            .unwrap_or_default();
        let part = record
            .metadata
            .get("part")
            .and_then(|p| p.parse().ok())
            .unwrap_or(1);
        Some((
            Self {
                station_version: get("station_version"),
                vehicle: get("vehicle"),
                mission: get("mission"),
                token_names,
            },
            part,
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// What a station's token looks like: a name and a secret.
    struct Token {
        name: String,
        secret: String,
    }

    impl Named for Token {
        fn name(&self) -> &str {
            &self.name
        }
    }

    #[test]
    fn metadata_carries_token_names_and_never_the_tokens() {
        let tokens = [
            Token {
                name: "alice".into(),
                secret: "s3cret-alice-token".into(),
            },
            Token {
                name: "tablet".into(),
                secret: "s3cret-tablet-token".into(),
            },
        ];
        let info =
            RecordingInfo::new("0.1.0", "straplex-1", "flight 7").with_token_holders(&tokens);
        let record = info.to_metadata(2);
        let text = format!("{:?}", record.metadata);
        for t in &tokens {
            assert!(!text.contains(&t.secret), "a secret leaked: {text}");
        }
        assert_eq!(record.metadata["token_names"], r#"["alice","tablet"]"#);
        let (back, part) = RecordingInfo::from_metadata(&record).unwrap();
        assert_eq!(back, info);
        assert_eq!(part, 2);
    }

    #[test]
    fn foreign_metadata_is_not_taken_for_ours() {
        let record = mcap::records::Metadata {
            name: "other".into(),
            metadata: BTreeMap::new(),
        };
        assert!(RecordingInfo::from_metadata(&record).is_none());
    }
}

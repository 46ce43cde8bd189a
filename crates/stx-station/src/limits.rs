//! Limits on what one caller can ask of the station, so someone on the field network cannot
//! crowd out the operators: requests per token, wrong tokens per source address, and pages
//! (WebSockets) at once. Pure: every check takes `now` (s, the station's clock), so the
//! limits are tested on a fake clock; the HTTP adapter holds one [`Limits`] and answers 429
//! with `Retry-After` when a check fails.
//!
//! Each limit is a token bucket per key (a token's name, an address): `burst` requests at
//! once, refilled at `per_s`. A bucket table holds at most [`MAX_KEYS`] keys, dropping the
//! fullest (idlest) bucket first, so a flood from many addresses cannot grow memory.

use std::collections::HashMap;
use std::hash::Hash;
use std::net::IpAddr;

use serde::{Deserialize, Serialize};

/// Most keys a bucket table remembers.
pub const MAX_KEYS: usize = 4096;
/// Requests a token may make at once, and per second after that (one token may serve a
/// dozen pages and a script: far above what operators do, far below a flood).
pub const TOKEN_BURST: f64 = 300.0;
/// See [`TOKEN_BURST`], requests/s.
pub const TOKEN_PER_S: f64 = 100.0;
/// Wrong tokens an address may send at once, and per second after that (one a minute:
/// a mistyped token is retried by hand, a guesser is slowed to nothing).
pub const BAD_TOKEN_BURST: f64 = 10.0;
/// See [`BAD_TOKEN_BURST`], per s.
pub const BAD_TOKEN_PER_S: f64 = 1.0 / 60.0;
/// Pages (WebSockets) connected at once.
pub const MAX_WEBSOCKETS: usize = 64;

/// `[limits]` of the station's TOML; every field may be left out (the defaults above).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct LimitSettings {
    /// Requests a token may make at once, requests.
    pub token_burst: f64,
    /// Requests a token may make per second after its burst, requests/s.
    pub token_per_s: f64,
    /// Wrong tokens an address may send at once, requests.
    pub bad_token_burst: f64,
    /// Wrong tokens an address may send per minute after that, requests/min.
    pub bad_tokens_per_min: f64,
    /// Pages (WebSockets) connected at once.
    pub max_websockets: usize,
}

impl Default for LimitSettings {
    fn default() -> Self {
        Self {
            token_burst: TOKEN_BURST,
            token_per_s: TOKEN_PER_S,
            bad_token_burst: BAD_TOKEN_BURST,
            bad_tokens_per_min: BAD_TOKEN_PER_S * 60.0,
            max_websockets: MAX_WEBSOCKETS,
        }
    }
}

impl LimitSettings {
    /// The first rule broken, as `(field, rule)`.
    pub fn check(&self) -> Result<(), (&'static str, &'static str)> {
        let positive = |x: f64| x.is_finite() && x > 0.0;
        if !(positive(self.token_burst) && self.token_burst >= 1.0) {
            return Err(("limits.token_burst", "a number of requests ≥ 1"));
        }
        if !positive(self.token_per_s) {
            return Err(("limits.token_per_s", "requests per second > 0"));
        }
        if !(positive(self.bad_token_burst) && self.bad_token_burst >= 1.0) {
            return Err(("limits.bad_token_burst", "a number of requests ≥ 1"));
        }
        if !positive(self.bad_tokens_per_min) {
            return Err(("limits.bad_tokens_per_min", "requests per minute > 0"));
        }
        if !(1..=10_000).contains(&self.max_websockets) {
            return Err(("limits.max_websockets", "from 1 to 10000 pages"));
        }
        Ok(())
    }
}

/// How long to wait before asking again, s (whole seconds, as `Retry-After` carries it).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RetryAfter(pub u64);

#[derive(Debug, Clone, Copy)]
struct Bucket {
    level: f64,
    at_s: f64,
    /// The bucket has refused since it last allowed: a burst of refusals is logged once.
    refusing: bool,
}

/// Token buckets, one per key.
#[derive(Debug)]
pub struct Buckets<K> {
    burst: f64,
    per_s: f64,
    buckets: HashMap<K, Bucket>,
}

/// What a check found.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Verdict {
    /// Go ahead.
    Allowed,
    /// Refused; `first` on the first refusal of a burst (log it), then false.
    Refused { retry: RetryAfter, first: bool },
}

impl<K: Hash + Eq + Clone> Buckets<K> {
    /// Buckets of `burst` refilled at `per_s`.
    pub fn new(burst: f64, per_s: f64) -> Self {
        Self {
            burst,
            per_s,
            buckets: HashMap::new(),
        }
    }

    /// Takes one from `key`'s bucket at `now_s`, if there is one.
    pub fn take(&mut self, now_s: f64, key: &K) -> Verdict {
        if !self.buckets.contains_key(key) && self.buckets.len() >= MAX_KEYS {
            self.forget_one(now_s);
        }
        let (burst, per_s) = (self.burst, self.per_s);
        let b = self.buckets.entry(key.clone()).or_insert(Bucket {
            level: burst,
            at_s: now_s,
            refusing: false,
        });
        b.level = (b.level + (now_s - b.at_s).max(0.0) * per_s).min(burst);
        b.at_s = now_s;
        if b.level >= 1.0 {
            b.level -= 1.0;
            b.refusing = false;
            Verdict::Allowed
        } else {
            let wait_s = if per_s > 0.0 {
                (1.0 - b.level) / per_s
            } else {
                f64::INFINITY
            };
            let first = !b.refusing;
            b.refusing = true;
            Verdict::Refused {
                retry: RetryAfter(wait_s.ceil().clamp(1.0, 86_400.0) as u64),
                first,
            }
        }
    }

    /// Keys remembered.
    pub fn len(&self) -> usize {
        self.buckets.len()
    }

    /// Whether no key is remembered.
    pub fn is_empty(&self) -> bool {
        self.buckets.is_empty()
    }

    /// Drops the bucket fullest at `now_s` (it has the least to remember).
    fn forget_one(&mut self, now_s: f64) {
        let level = |b: &Bucket| b.level + (now_s - b.at_s).max(0.0) * self.per_s;
        let fullest = self
            .buckets
            .iter()
            .max_by(|a, b| level(a.1).total_cmp(&level(b.1)))
            .map(|(k, _)| k.clone());
        if let Some(k) = fullest {
            self.buckets.remove(&k);
        }
    }
}

/// The station's limits.
#[derive(Debug)]
pub struct Limits {
    /// Requests per token (by the token's name).
    pub requests: Buckets<String>,
    /// Wrong tokens per source address.
    pub bad_tokens: Buckets<IpAddr>,
}

impl Default for Limits {
    fn default() -> Self {
        Self::new(&LimitSettings::default())
    }
}

impl Limits {
    /// The limits `settings` ask for.
    pub fn new(settings: &LimitSettings) -> Self {
        Self {
            requests: Buckets::new(settings.token_burst, settings.token_per_s),
            bad_tokens: Buckets::new(settings.bad_token_burst, settings.bad_tokens_per_min / 60.0),
        }
    }
}

impl Limits {
    /// Whether `address` may still try a token (it has wrong ones left), without using one.
    pub fn may_try(&mut self, now_s: f64, address: IpAddr) -> Result<(), RetryAfter> {
        let b = self.bad_tokens.buckets.get(&address).copied();
        match b {
            Some(b) if b.level + (now_s - b.at_s).max(0.0) * self.bad_tokens.per_s < 1.0 => {
                let wait = (1.0 - b.level) / self.bad_tokens.per_s - (now_s - b.at_s);
                Err(RetryAfter(wait.ceil().clamp(1.0, 86_400.0) as u64))
            }
            _ => Ok(()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_bucket_allows_its_burst_then_its_rate_and_says_when_to_come_back() {
        let mut b = Buckets::new(3.0, 2.0);
        let k = "operator".to_string();
        for _ in 0..3 {
            assert_eq!(b.take(0.0, &k), Verdict::Allowed);
        }
        assert_eq!(
            b.take(0.0, &k),
            Verdict::Refused {
                retry: RetryAfter(1),
                first: true
            }
        );
        assert!(matches!(
            b.take(0.1, &k),
            Verdict::Refused { first: false, .. }
        ));
        // 2 per second: half a second later one more.
        assert_eq!(b.take(0.6, &k), Verdict::Allowed);
        // Another key has its own bucket.
        assert_eq!(b.take(0.6, &"viewer".to_string()), Verdict::Allowed);
    }

    #[test]
    fn wrong_tokens_lock_an_address_out_for_minutes_and_others_not_at_all() {
        let mut l = Limits::default();
        let guesser: IpAddr = "10.0.0.66".parse().expect("address");
        let operator: IpAddr = "10.0.0.2".parse().expect("address");
        for _ in 0..BAD_TOKEN_BURST as usize {
            assert_eq!(l.may_try(0.0, guesser), Ok(()));
            assert_eq!(l.bad_tokens.take(0.0, &guesser), Verdict::Allowed);
        }
        let Verdict::Refused { retry, first } = l.bad_tokens.take(0.0, &guesser) else {
            panic!("the eleventh wrong token is refused")
        };
        assert!(first && retry.0 >= 59, "{retry:?}");
        assert!(l.may_try(30.0, guesser).is_err());
        assert_eq!(l.may_try(30.0, operator), Ok(()));
        assert_eq!(l.may_try(61.0, guesser), Ok(()), "one more a minute");
    }

    #[test]
    fn the_configured_limits_are_the_ones_in_force_and_checked() {
        let settings = LimitSettings {
            token_burst: 2.0,
            bad_tokens_per_min: 6.0,
            ..LimitSettings::default()
        };
        assert_eq!(settings.check(), Ok(()));
        let mut l = Limits::new(&settings);
        let k = "operator".to_string();
        assert_eq!(l.requests.take(0.0, &k), Verdict::Allowed);
        assert_eq!(l.requests.take(0.0, &k), Verdict::Allowed);
        assert!(matches!(l.requests.take(0.0, &k), Verdict::Refused { .. }));
        let guesser: IpAddr = "10.0.0.66".parse().expect("address");
        for _ in 0..BAD_TOKEN_BURST as usize + 1 {
            l.bad_tokens.take(0.0, &guesser);
        }
        // Six a minute: one more after ten seconds.
        assert!(l.may_try(5.0, guesser).is_err());
        assert_eq!(l.may_try(11.0, guesser), Ok(()));
        let bad = |edit: fn(&mut LimitSettings)| {
            let mut s = LimitSettings::default();
            edit(&mut s);
            s.check().unwrap_err().0
        };
        assert_eq!(bad(|s| s.token_burst = 0.5), "limits.token_burst");
        assert_eq!(bad(|s| s.token_per_s = f64::NAN), "limits.token_per_s");
        assert_eq!(
            bad(|s| s.bad_tokens_per_min = 0.0),
            "limits.bad_tokens_per_min"
        );
        assert_eq!(bad(|s| s.max_websockets = 0), "limits.max_websockets");
        assert_eq!(LimitSettings::default().check(), Ok(()));
    }

    #[test]
    fn a_flood_from_many_addresses_stays_within_the_table() {
        let mut b = Buckets::new(1.0, 0.01);
        for i in 0..(MAX_KEYS as u32 + 1000) {
            b.take(f64::from(i) * 1e-3, &IpAddr::from(i.to_be_bytes()));
        }
        assert_eq!(b.len(), MAX_KEYS);
    }
}

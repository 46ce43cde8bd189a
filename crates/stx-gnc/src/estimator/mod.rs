//! The navigation estimator: GPS, AHRS and pitot measurements in, an [`Estimate`] with an
//! uncertainty for every quantity out. The same code runs on the (simulated) drone and in the
//! ground station.
//!
//! Pure: no clock, no threads, no randomness. The caller hands in each measurement with the
//! instant it arrived ([`Estimator::handle`]) and asks for the estimate at any later instant
//! ([`Estimator::estimate`]); tests drive it with a fake clock.
//!
//! # What the drone measures, and what that allows
//!
//! GPS position and NED velocity (≈4 Hz, late by a few tenths of a second), the AHRS's roll,
//! pitch and yaw of the drone, and a pitot whose differential pressure gives the air's speed
//! along the drone's x axis only, plus static pressure and temperature. No gyro rates, no
//! accelerations. The drone hangs 3.3 m below the canopy and swings: in the flight model its
//! heading jitters by tens of degrees at about 1 Hz around the stack's track, its body sideslip
//! reaches 10–25° in steady turns and far more while a turn reverses (the air sometimes comes
//! from behind), and its x axis sits 17–20° above the air-relative velocity in a glide. So the
//! pitot's reading is not the airspeed, the air does not come from straight ahead, and the
//! drone's heading is a poor guide to where the stack is going. The filter assumes none of
//! these.
//!
//! # Design
//!
//! Two parts, advanced together one measurement at a time in timestamp order:
//!
//! 1. **Angle filters** (roll φ, pitch θ, yaw ψ; `angle.rs`): angle and rate with a white
//!    angular-acceleration model, fed by the AHRS angle (wrapped innovations, a physical rate
//!    limit against aliasing). They give the attitude at any instant between AHRS samples, the
//!    heading and heading rate the estimate reports, and the attitude's uncertainty.
//!
//! 2. **Navigation EKF** (state, prediction and Kalman update in `ekf.rs`; one file per
//!    measurement: `gps.rs`, `pitot.rs`, `baro.rs`, `sideslip.rs`; the estimate read out in
//!    `readout.rs`; `filter.rs` advances the angle filters and the EKF together), fourteen
//!    states
//!
//!    ```text
//!    x = [ p (NED position, m) | a (NED velocity relative to the air, m/s) | ω (turn rate
//!          of the horizontal air velocity, rad/s) | w_N, w_E, w_D (wind, m/s)
//!          | k (pitot scale) | b (barometric bias, ln Pa) | β₀ (straight-flight sideslip
//!          offset from the drone's true heading, rad) | δψ (AHRS heading bias, rad) ]
//!    ```
//!
//!    The ground velocity is `v = a + w`. The air velocity is kept in NED, not in the drone's
//!    frame, because the stack's air velocity is smooth (a twelve-metre, nine-kilogram
//!    stack) while the drone's frame jitters with its swing; it turns at the rate ω
//!    in a turn. The vertical wind is a Gauss–Markov process about zero: in a spiral the drone
//!    pitches 35° nose-down, so the pitot sees a good part of the sink rate, and an unmodelled
//!    vertical gust would otherwise be blamed on the horizontal wind.
//!
//!    Process model over a step `Δt`, with `R(α)` the horizontal rotation by `α`:
//!
//!    ```text
//!    a_h⁺ = R(ωΔt)·a_h + n,   a_D⁺ = a_D + n            (turning, random walks)
//!    p_h⁺ = p_h + G·a_h + w_h·Δt,   G = ∫₀^Δt R(ωτ) dτ   (exact along a constant-rate arc)
//!    p_D⁺ = p_D + (a_D + w_D)·Δt
//!    ω⁺ = ω + n,  w_h⁺ = w_h + n,  w_D⁺ = e^(−Δt/τ)·w_D + n,  k⁺ = k + n,  b⁺ = b + n,  β₀⁺ = β₀ + n,
//!    δψ⁺ = δψ + n
//!    ```
//!
//!    and `P⁺ = F P Fᵀ + Q` with `F` the Jacobian (including `∂G/∂ω` and `∂R/∂ω`) and the
//!    air velocity's and wind's random walks carried into position (`Δt²/2`, `Δt³/3` terms).
//!
//!    Measurements (each an EKF update, gated on its normalised innovation squared):
//!
//!    ```text
//!    GPS position   z = p                                    R = diag(σ_h², σ_h², σ_v²)
//!    GPS velocity   z = a + w                                R = σ_s²·I
//!    pitot          z = √(2Δp/ρ), ρ = p_s/(R_air·T)  = k·(e_x·a)
//!                   e_x = [cos θ cos ψ', cos θ sin ψ', −sin θ],  ψ' = ψ − δψ
//!                                                             R = (σ_Δp/(ρ z))² + J Σ_θψ Jᵀ + σ_floor²
//!    barometer      z = ln p_s = ln p_US76(h₀ − p_D) + b      R = (σ_ps/p_s)²
//!    straight       z = 0 = e_y·a_h − |a_h|·β₀,  e_y = [−sin ψ', cos ψ']
//!                                                             R = (|a_h| σ_β)² + (e_x·a_h)² σ_ψ²
//!    ```
//!
//!    `ψ` is the AHRS's heading, `ψ'` the drone's true one. `J = k·∂(e_x·a)/∂(θ, ψ)` and
//!    `Σ_θψ` the variances of the pitch and heading used: an uncertain attitude makes the pitot
//!    less informative. Which pitch and heading: the AHRS's
//!    own when it sampled in the same instant (the drone's 4 Hz loop reads all its sensors
//!    together); else interpolated between the AHRS samples either side (the pitot sample is
//!    processed again when the later one arrives, and waits for it before being committed);
//!    else the angle filters' extrapolation. The drone's swing makes this matter: a pitot
//!    0.05–0.1 s off the AHRS costs 0.1 m/s of wind accuracy even with the interpolation. The
//!    pitot is not used below a minimum airspeed (it reads nothing for air from behind, which
//!    the swinging drone does see). The last line is
//!    a pseudo-measurement used with each AHRS sample once the flight has been straight for a
//!    moment (slow ω and heading rate): a weathervaning drone points into its relative wind
//!    give or take its swing and an offset `β₀`; in turns the sideslip is 10–25° and varies,
//!    and the line is not used.
//!    The vertical wind is reported as zero (the estimate's contract); it is estimated only so
//!    that vertical gusts are not blamed on the horizontal wind, and it is in the airspeed and
//!    the air-relative glide ratio.
//!
//! **The AHRS's heading bias** `δψ` (a magnetometer's, 5° 1-σ in the realistic dispersions)
//! turns the x axis the pitot and the straight line are projected on. Where it shows:
//! - through the pitot, `∂z/∂δψ = −k·cos θ·(e_y·a_h)`: wherever the air comes from beside
//!   the x axis, i.e. in the drone's swing (tens of degrees at about 1 Hz) and in turns. With
//!   the air velocity's direction fixed by the GPS (the wind is fixed in NED, so as the
//!   heading changes a wrong heading would turn the air velocity with the vehicle), the pitot
//!   reads most where the true x axis points into the air, which places `δψ`;
//! - in straight flight only `δψ − β₀` shows: the straight line and the pitot see the angle
//!   from the AHRS's heading to the air, not how much of it is the magnetometer and how much
//!   the drone's trim, and without a turn nothing separates the bias from a turned wind
//!   either. The split follows the priors: the drone's own straight-flight sideslip is small
//!   (in the simulation −0.4° ± 1.0° per run over the realistic dispersions; its swing 5°
//!   RMS), so `β₀` is held by a 1° prior against the bias's 5°, and a straight leg after
//!   turns, whose wind is known, measures the bias too.
//!
//! Without the bias state the swing turned a 6° bias into wind errors of 0.3–0.7 m/s on a
//! pattern of quarter turns (`a_heading_bias_is_learnt_round_a_pattern_…`), and the Monte
//! Carlo's wind-estimate RMS with the heading bias as the only dispersion was 0.43 m/s; with
//! it, 0.25 m/s (nominal: 0.24), the bias learnt to 0.4° (median) by the touchdown.
//!
//! **How the wind is found.** Each pitot sample, with the GPS velocity of the same instant,
//! measures the wind along the drone's x axis: `e_x·w = e_x·v − u_pitot/k`. The component
//! across x is seen as x points elsewhere — in turns, and through the drone's swing — and, in
//! straight flight, through the sideslip pseudo-measurement. In turbulence the accuracy is set
//! by how fast the x axis sweeps compared with how fast the wind changes. On the flight model
//! with the simulator's default sensors and MIL-F-8785C low-altitude turbulence
//! (σ = 0.1 × wind, L = 300 m), 22 flights of 200 s in 2–5 m/s of wind, in alternating
//! spirals, spiral-landing legs and slow weaving, give 0.12–0.29 m/s RMS from 30 s on (the
//! project's goal is 0.3); steady air about 0.1 m/s. In gusts 0.2 m/s stronger and faster
//! (L = 200 m horizontally, 50 m vertically), 0.28–0.42 m/s: the goal then is not met. The
//! figures are printed by `crates/stx-sim/tests/sim/sensors_estimator.rs`. The scale `k`
//! separates from the along-x wind once the flight turns.
//!
//! During a GPS dropout the same equations dead-reckon: the air velocity keeps turning at ω,
//! the pitot keeps its x component, the barometer keeps the height, and the covariance grows.
//! When fixes return the gate still passes them because `P` grew; a filter that has gone wrong
//! anyway is re-started from GPS after [`EstimatorConfig::reset_after_rejections`] rejected
//! fixes in a row.
//!
//! The drone's heading and heading rate come from the angle filters. Between AHRS samples they
//! are extrapolated, and the drone's ~1 Hz swing under the canopy is barely sampled at 4 Hz, so
//! these are the least accurate outputs (about 20° RMS in alternating spirals, 3–10° in gentler
//! flight). The course, from the velocity, is smooth and good to a few degrees.
//!
//! # Late and out-of-order measurements
//!
//! Every measurement is stamped with the instant it describes, and the filter processes them
//! in that order. Measurements newer than the latest arrival minus
//! [`EstimatorConfig::max_latency_s`] wait in a short buffer sorted by instant, each with a
//! copy of the filter just after it; older ones are *committed*, final, never revisited. One
//! that arrives in order is applied to the newest copy; one that slots in earlier is applied to
//! the copy before its place, and only the measurements after it are replayed (with GPS 0.25 s
//! late and the AHRS and pitot on time, one). As long as every measurement arrives within the
//! window, the result does not depend on the order of arrival. A measurement older than the
//! window is
//! counted as stale and dropped. Each sensor's outcome (used, gated, reset, unused) is counted
//! when its measurement is committed, so replays count nothing twice.
//!
//! Cost: fixed-size `nalgebra` matrices, the transition's sparsity exploited, no allocation
//! after [`Estimator::new`]; `crates/stx-sim/tests/sim/sensors_estimator.rs` prints the measured
//! time per call.

mod angle;
mod baro;
mod config;
mod ekf;
mod filter;
mod gps;
mod pitot;
mod readout;
mod sideslip;

pub use config::{EstimatorConfig, EstimatorConfigError};

use std::collections::VecDeque;

use serde::{Deserialize, Serialize};

use crate::estimate::Estimate;
use crate::measurement::Measurement;
use config::Tuning;
use ekf::Outcome;
use filter::{NavFilter, Timeouts};
use pitot::MAX_INTERPOLATION_S;

/// Most measurements held for re-ordering, each with a filter snapshot (about 1.5 kB). At 4 Hz
/// from three sensors and a 0.6-s window about eight wait at once; the rest is headroom for
/// faster sensors or a longer window. When full, the oldest is committed early (counted in
/// [`EstimatorCounters::early_commits`]).
pub const PENDING_CAPACITY: usize = 48;

/// What [`Estimator::handle`] did with a measurement.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Disposition {
    /// Taken in (its effect on the filter is counted when it is committed).
    Accepted,
    /// Older than the latency window, or than what is already committed: dropped.
    Stale,
    /// A non-finite time or value: refused.
    NonFinite,
    /// Finite but impossible (non-positive pressure or temperature, pitch beyond ±90°):
    /// refused.
    Invalid,
    /// Stamped later than its arrival plus the allowed clock skew: refused.
    FromFuture,
}

/// Counts per sensor.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct SensorCounts {
    /// GPS fixes.
    pub gps: u64,
    /// AHRS samples.
    pub attitude: u64,
    /// Pitot samples.
    pub air_data: u64,
}

impl SensorCounts {
    fn bump(&mut self, m: &Measurement) {
        match m {
            Measurement::Gps(_) => self.gps += 1,
            Measurement::Attitude(_) => self.attitude += 1,
            Measurement::AirData(_) => self.air_data += 1,
        }
    }

    /// All sensors together.
    pub fn total(&self) -> u64 {
        self.gps + self.attitude + self.air_data
    }
}

/// What happened to every measurement handed in: for the link statistics and the operators
/// (loss is shown, never hidden).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct EstimatorCounters {
    /// Measurements taken in.
    pub accepted: u64,
    /// Dropped as older than the latency window.
    pub stale: u64,
    /// Refused for a non-finite time or value.
    pub non_finite: u64,
    /// Refused as physically impossible.
    pub invalid: u64,
    /// Refused as stamped in the future.
    pub from_future: u64,
    /// Committed and used by the filter.
    pub used: SensorCounts,
    /// Committed but (partly) rejected by the innovation gate.
    pub gated: SensorCounts,
    /// Committed and (re)started a filter: the first of each, or after repeated rejections.
    pub resets: SensorCounts,
    /// Committed but unusable (nothing to update yet; pitot below its minimum airspeed).
    pub unused: SensorCounts,
    /// Times the head was rebuilt because a measurement arrived out of order.
    pub replays: u64,
    /// Measurements committed before their latency window closed because the buffer was full.
    pub early_commits: u64,
}

/// The navigation estimator. See the module documentation for the filter.
#[derive(Debug, Clone)]
pub struct Estimator {
    config: EstimatorConfig,
    tuning: Tuning,
    timeouts: Timeouts,
    /// Final state: every measurement older than the latency window applied.
    committed: NavFilter,
    /// Measurements newer than the committed state, sorted by instant then sensor, each with
    /// the filter state just after it (the last one's is the head).
    pending: VecDeque<Pending>,
    /// Latest arrival seen, s: the estimator's notion of "now" for staleness.
    latest_arrival_s: f64,
    /// Instant of the newest committed measurement, s (−∞ before the first).
    committed_time_s: f64,
    counters: EstimatorCounters,
}

/// A measurement waiting to be committed, with what applying it did.
#[derive(Debug, Clone)]
struct Pending {
    measurement: Measurement,
    outcome: Outcome,
    /// The filter after this measurement: replays start from the one before an insertion.
    after: NavFilter,
}

/// Order among measurements of the same instant: attitude first (the others are projected
/// with it), then GPS, then air data.
fn sensor_rank(m: &Measurement) -> u8 {
    match m {
        Measurement::Attitude(_) => 0,
        Measurement::Gps(_) => 1,
        Measurement::AirData(_) => 2,
    }
}

fn is_attitude(p: &Pending) -> bool {
    matches!(p.measurement, Measurement::Attitude(_))
}

fn is_air_data(m: &Measurement) -> bool {
    matches!(m, Measurement::AirData(_))
}

/// Checks a measurement from outside before it touches the filter.
fn check(m: &Measurement) -> Result<(), Disposition> {
    let finite = |values: &[f64]| values.iter().all(|v| v.is_finite());
    match m {
        Measurement::Gps(g) => {
            let ok = finite(&[
                g.time_s,
                g.horizontal_accuracy_m,
                g.vertical_accuracy_m,
                g.speed_accuracy_mps,
            ]) && finite(g.position_ned_m.as_slice())
                && finite(g.velocity_ned_mps.as_slice());
            if !ok {
                return Err(Disposition::NonFinite);
            }
            if g.horizontal_accuracy_m < 0.0
                || g.vertical_accuracy_m < 0.0
                || g.speed_accuracy_mps < 0.0
            {
                return Err(Disposition::Invalid);
            }
        }
        Measurement::Attitude(a) => {
            if !finite(&[a.time_s, a.roll_rad, a.pitch_rad, a.yaw_rad]) {
                return Err(Disposition::NonFinite);
            }
            if a.pitch_rad.abs() > std::f64::consts::FRAC_PI_2 + 1e-9 {
                return Err(Disposition::Invalid);
            }
        }
        Measurement::AirData(a) => {
            if !finite(&[
                a.time_s,
                a.differential_pressure_pa,
                a.static_pressure_pa,
                a.temperature_k,
            ]) {
                return Err(Disposition::NonFinite);
            }
            if a.static_pressure_pa <= 0.0 || a.temperature_k <= 0.0 {
                return Err(Disposition::Invalid);
            }
        }
    }
    Ok(())
}

impl Estimator {
    /// An estimator that has seen nothing, after validating `config`.
    pub fn new(config: EstimatorConfig) -> Result<Self, EstimatorConfigError> {
        config.validate()?;
        let tuning = Tuning::new(&config);
        let timeouts = Timeouts {
            gps_s: config.gps_timeout_s,
            attitude_s: config.attitude_timeout_s,
            air_data_s: config.air_data_timeout_s,
        };
        Ok(Self::unstarted(config, tuning, timeouts))
    }

    /// An estimator with this configuration and tuning that has seen nothing.
    fn unstarted(config: EstimatorConfig, tuning: Tuning, timeouts: Timeouts) -> Self {
        Self {
            config,
            tuning,
            timeouts,
            committed: NavFilter::new(),
            pending: VecDeque::with_capacity(PENDING_CAPACITY),
            latest_arrival_s: f64::NEG_INFINITY,
            committed_time_s: f64::NEG_INFINITY,
            counters: EstimatorCounters::default(),
        }
    }

    /// A fresh estimator that starts from what this one has learnt of the sensors (the pitot's
    /// scale and the AHRS's heading bias, with their variances) and nothing else: for a new
    /// flight phase whose air and wind the old state would only mislead (the parafoil after
    /// the round chute). The drone and the station's replica both restart so; without the
    /// sensors kept, the replica, which restarts when it hears of the deployment, missed the
    /// first swinging seconds that place the heading bias, and its wind parted from the
    /// drone's by 0.7° of direction for the whole flight (agreement campaign, seed 1).
    pub fn restarted(&self) -> Self {
        let mut tuning = self.tuning;
        if let Some((scale, bias)) = self.head().calibration() {
            (tuning.initial_scale, tuning.initial_scale_variance) = scale;
            (
                tuning.initial_heading_bias_rad,
                tuning.initial_heading_bias_variance,
            ) = bias;
        }
        Self::unstarted(self.config.clone(), tuning, self.timeouts)
    }

    /// The configuration in use.
    pub fn config(&self) -> &EstimatorConfig {
        &self.config
    }

    /// What happened to the measurements so far.
    pub fn counters(&self) -> &EstimatorCounters {
        &self.counters
    }

    /// Takes in a measurement that reached the estimator at `arrival_s` (s, mission clock).
    /// Never panics: bad input is refused and counted.
    pub fn handle(&mut self, arrival_s: f64, m: &Measurement) -> Disposition {
        let disposition = self.admit(arrival_s, m);
        match disposition {
            Disposition::Accepted => self.counters.accepted += 1,
            Disposition::Stale => self.counters.stale += 1,
            Disposition::NonFinite => self.counters.non_finite += 1,
            Disposition::Invalid => self.counters.invalid += 1,
            Disposition::FromFuture => self.counters.from_future += 1,
        }
        disposition
    }

    fn admit(&mut self, arrival_s: f64, m: &Measurement) -> Disposition {
        if !arrival_s.is_finite() {
            return Disposition::NonFinite;
        }
        if let Err(refusal) = check(m) {
            return refusal;
        }
        let time_s = m.time_s();
        if time_s > arrival_s + self.tuning.max_clock_skew_s {
            return Disposition::FromFuture;
        }
        self.latest_arrival_s = self.latest_arrival_s.max(arrival_s);
        let horizon_s = self.latest_arrival_s - self.tuning.max_latency_s;
        if self.pending.len() == PENDING_CAPACITY {
            self.commit_front();
            self.counters.early_commits += 1;
        }
        if time_s < horizon_s || time_s < self.committed_time_s {
            return Disposition::Stale;
        }

        // Insert after every pending measurement that sorts before or with it, then bring the
        // states from there on up to date: only the measurements after it are replayed.
        let key = (time_s, sensor_rank(m));
        let at = self
            .pending
            .iter()
            .rposition(|p| (p.measurement.time_s(), sensor_rank(&p.measurement)) <= key)
            .map_or(0, |i| i + 1);
        self.pending.insert(
            at,
            Pending {
                measurement: *m,
                outcome: Outcome::Unused,
                after: NavFilter::new(),
            },
        );
        // A new AHRS sample closes the interval of the pitot samples since the previous one,
        // which were projected with an extrapolated attitude: replay them with it. (A pitot
        // sample of the very instant of an AHRS sample needs no interpolation.)
        let mut start = at;
        if matches!(m, Measurement::Attitude(_)) {
            let previous = self.pending.range(..at).rposition(is_attitude);
            let (first, previous_s) = match previous {
                Some(i) => (i + 1, self.pending[i].measurement.time_s()),
                None => (0, self.committed.last_attitude_time_s()),
            };
            if let Some(i) = (first..at).find(|&i| {
                let p = &self.pending[i].measurement;
                is_air_data(p) && p.time_s() > previous_s
            }) {
                start = i;
            }
        }
        if start + 1 < self.pending.len() {
            self.counters.replays += 1;
        }
        let mut state = match start {
            0 => self.committed,
            _ => self.pending[start - 1].after,
        };
        for i in start..self.pending.len() {
            let next_attitude = self
                .pending
                .range(i + 1..)
                .find_map(|p| match &p.measurement {
                    Measurement::Attitude(a) => Some(*a),
                    _ => None,
                });
            let entry = &mut self.pending[i];
            entry.outcome = state.apply(&entry.measurement, next_attitude.as_ref(), &self.tuning);
            entry.after = state;
        }

        // Commit what the window has closed on; a pitot sample waits (a little longer) for
        // the AHRS sample after it, so that its final processing does not depend on the order
        // in which the two arrived.
        while let Some(front) = self.pending.front() {
            let front_s = front.measurement.time_s();
            let awaits_attitude = is_air_data(&front.measurement)
                && front_s > self.committed.last_attitude_time_s()
                && front_s >= horizon_s - MAX_INTERPOLATION_S
                && !self.pending.iter().skip(1).any(is_attitude);
            if front_s >= horizon_s || awaits_attitude {
                break;
            }
            self.commit_front();
        }
        Disposition::Accepted
    }

    /// Makes the oldest pending measurement final and counts what it did.
    fn commit_front(&mut self) {
        let Some(entry) = self.pending.pop_front() else {
            return;
        };
        self.committed = entry.after;
        self.committed_time_s = entry.measurement.time_s();
        let c = &mut self.counters;
        let m = &entry.measurement;
        match entry.outcome {
            Outcome::Used => c.used.bump(m),
            Outcome::Gated => c.gated.bump(m),
            Outcome::Reset => c.resets.bump(m),
            Outcome::Unused => c.unused.bump(m),
        }
    }

    /// The newest state: the committed one with every pending measurement applied.
    fn head(&self) -> &NavFilter {
        self.pending.back().map_or(&self.committed, |p| &p.after)
    }

    /// The estimate at `now_s` (s): the newest state predicted forward to `now_s`. For an
    /// instant before the newest measurement, the newest state is reported as it is.
    pub fn estimate(&self, now_s: f64) -> Estimate {
        self.head().estimate(now_s, &self.tuning, &self.timeouts)
    }
}

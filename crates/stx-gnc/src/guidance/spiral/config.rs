//! The spiral's settings, with their units and defaults, and the choice of law for the final
//! approach's brakes.

use serde::{Deserialize, Serialize};

/// Spiral-landing settings, with units.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SpiralConfig {
    /// Half the side of the square spiral, m (each branch is twice as long).
    pub half_size_m: f64,
    /// Longest final approach the downwind leg may be extended to, m.
    pub max_final_m: f64,
    /// Shortest final approach, m: time to settle on the line before the ground.
    pub min_final_m: f64,
    /// Height of the drone above the lowest hanging body (the transponder), m: the drone is
    /// this high when the stack touches down.
    pub hang_height_m: f64,
    /// Height of the lowest body above the ground at which the flare starts, m.
    pub flare_height_m: f64,
    /// Whether to flare at all; without, the final approach's last brake setting is held to
    /// the ground (to measure what the flare is worth).
    pub flare: bool,
    /// Turn rate planned for the corners, rad/s; 0 (the default) plans with the rate the
    /// control gains actually turn at
    /// ([`corner_turn_rate_rad_s`](super::corner_turn_rate_rad_s)), which is what the corners
    /// should be cut for: a fixed rate goes stale whenever the gains are retuned.
    pub planned_turn_rate_rad_s: f64,
    /// Height kept in hand above the planned glide when leaving the spiral, m.
    pub final_margin_m: f64,
    /// Below this wind the approach direction is held as it is, m/s.
    pub calm_wind_mps: f64,
    /// Share of the glide's still-air reach guidance counts on before calling a target out of
    /// reach (checked in every phase until the flare; see [the spiral](super)).
    pub reach_margin: f64,
    /// Time constant of the wind filter that orients the pattern, s.
    pub wind_filter_s: f64,
    /// Touchdown aimed this far beyond the target along the final, m (corrects the trail of
    /// the hanging bodies and the flare's dynamics, measured by the Monte Carlo).
    pub aim_beyond_m: f64,
    /// Height of the payload's (the capsule's) lowest point above the lowest hanging body's
    /// (the transponder's), m. Once the transponder touches, its line goes slack and the
    /// stack sinks this much further, flying on, before the capsule touches; the final aims
    /// the transponder's contact short by the way flown meanwhile, so that the payload comes
    /// down on the target. 0 aims the first contact at the target.
    pub payload_height_m: f64,
    /// Headwind added to the measured wind when planning the final, m/s.
    pub wind_margin_mps: f64,
    /// Headwind added as a share of the measured wind when planning the final.
    pub wind_margin_fraction: f64,
    /// Which law sets the brakes on the final approach.
    pub final_law: FinalLaw,
    /// Whether the pattern's legs along the wind are shortened with the wind (see
    /// [the spiral](super)); without, the pattern is the square of side `2·half_size_m` in any
    /// wind.
    pub wind_scaled_branches: bool,
}

/// The law that sets the symmetric brakes on the final approach.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum FinalLaw {
    /// The brake whose steady glide over the ground, into the planned headwind, ends on the
    /// aim point from where the vehicle is: the glide performance inverted, every update.
    #[default]
    GlideInversion,
    /// The seed's glide-slope law (eqs. 5.12–5.17) down a straight path through the aim point
    /// whose slope is fixed at the turn onto the final, about a feed-forward brake.
    GlideSlope,
}

impl Default for SpiralConfig {
    fn default() -> Self {
        Self {
            half_size_m: 50.0,
            max_final_m: 300.0,
            min_final_m: 40.0,
            hang_height_m: 8.4,
            flare_height_m: 6.0,
            flare: true,
            planned_turn_rate_rad_s: 0.0,
            final_margin_m: 0.0,
            calm_wind_mps: 0.3,
            reach_margin: 1.0,
            wind_filter_s: 10.0,
            aim_beyond_m: 0.0,
            // The transponder's 5 m line less half the capsule's and the transponder's
            // heights (0.2 m each, config/vehicle/straplex.toml).
            payload_height_m: 4.8,
            wind_margin_mps: 0.2,
            wind_margin_fraction: 0.1,
            final_law: FinalLaw::GlideInversion,
            wind_scaled_branches: true,
        }
    }
}

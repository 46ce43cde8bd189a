//! What steering could reach from the deploy point, in a closed form cheap enough to ask for
//! every Monte Carlo sample: the parafoil flies through an air mass that drifts with the wind,
//! so the points it can land on are a disc around where the air it deployed in ends up, of
//! radius the distance it glides through that air on the way down.
//!
//! The unsteered glide measures both: its landing minus the path flown through the air is the
//! drifted air mass's centre; the length of that path (full glide at neutral brake, whose glide
//! ratio does not change with density) is the radius. Any heading flown all the way down lands
//! on the disc's edge, because the wind's drift depends on the altitude only, not on where the
//! parafoil is. The disc is optimistic: the turn onto the chosen heading costs height (a few
//! seconds at the full turn rate), and brake, which guidance uses to lose height over the
//! target, only shortens the glide — the spiral landing reaches the inside of the disc.
//!
//! The reachable-region module (`footprint`), when present, answers the same question with
//! the parafoil's turns and the wind's uncertainty; this disc is what the plan uses until it is
//! wired in, behind [`ReachDisc::contains`].

use serde::{Deserialize, Serialize};

/// The landing points steering can reach from a deploy point.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
pub struct ReachDisc {
    /// Centre: where the air the parafoil deployed in reaches the ground (north, east), m.
    pub centre_ne_m: [f64; 2],
    /// Radius: the glide through the air from the deploy point, m.
    pub radius_m: f64,
}

impl ReachDisc {
    /// The disc of an unsteered glide that landed at `landing_ne_m` after flying
    /// `through_air_ne_m` through the air (north, east), m.
    pub fn from_unsteered_glide(landing_ne_m: [f64; 2], through_air_ne_m: [f64; 2]) -> Self {
        Self {
            centre_ne_m: [
                landing_ne_m[0] - through_air_ne_m[0],
                landing_ne_m[1] - through_air_ne_m[1],
            ],
            radius_m: through_air_ne_m[0].hypot(through_air_ne_m[1]),
        }
    }

    /// Whether steering can land on `point_ne_m` (north, east), m.
    pub fn contains(&self, point_ne_m: [f64; 2]) -> bool {
        let d = (point_ne_m[0] - self.centre_ne_m[0]).hypot(point_ne_m[1] - self.centre_ne_m[1]);
        d <= self.radius_m
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_unsteered_landing_lies_on_the_edge_and_the_far_side_is_out() {
        let disc = ReachDisc::from_unsteered_glide([1000.0, 500.0], [600.0, 0.0]);
        assert_eq!(disc.centre_ne_m, [400.0, 500.0]);
        assert!((disc.radius_m - 600.0).abs() < 1e-12);
        assert!(disc.contains([1000.0, 500.0]));
        assert!(disc.contains([400.0, 1099.0]));
        assert!(!disc.contains([-201.0, 500.0]));
    }
}

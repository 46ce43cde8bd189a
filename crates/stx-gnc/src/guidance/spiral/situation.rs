//! Where the vehicle stands at one update, everything the phase machine decides on and the
//! steering flies with: its place in the pattern, the wind, the energy sums, the reach and
//! the final approach's geometry.

use super::energy::Energy;
use super::final_approach::FinalGeometry;
use super::pattern::Pattern;
use super::reach::Reach;
use super::wind::WindNow;

/// The situation at one update.
#[derive(Debug, Clone, Copy)]
pub(super) struct Situation {
    /// Time of the estimate, s.
    pub(super) now_s: f64,
    /// Height of the target's ground, m.
    pub(super) ground_m: f64,
    /// Where the vehicle is (north, east), m.
    pub(super) position: [f64; 2],
    /// The vehicle in the wind frame (x downwind of the target, y right of it), m.
    pub(super) x: f64,
    pub(super) y: f64,
    /// Drone height above the target's ground, m.
    pub(super) height: f64,
    /// Height of the lowest hanging body above the target's ground, m.
    pub(super) lowest_body_height: f64,
    pub(super) wind: WindNow,
    pub(super) pattern: Pattern,
    pub(super) energy: Energy,
    pub(super) reach: Reach,
    pub(super) final_approach: FinalGeometry,
}

impl Situation {
    /// The target (north, east), m.
    pub(super) fn target_ne(&self) -> [f64; 2] {
        self.pattern.frame.target_ne
    }

    /// Height needed to turn base at `x_base` from the downwind leg and glide in, m.
    pub(super) fn needed_to_turn_base(&self, x_base: f64) -> f64 {
        self.energy.needed_from(x_base, self.pattern.downwind_y)
    }

    /// Height needed to go for the final from here with no more pattern, m.
    pub(super) fn needed_direct(&self) -> f64 {
        self.energy.needed_direct(self.x, self.y)
    }

    /// Height one more loop of the pattern takes, m.
    pub(super) fn loop_loss(&self) -> f64 {
        self.energy.loop_loss(self.pattern.ax, self.pattern.ay)
    }
}

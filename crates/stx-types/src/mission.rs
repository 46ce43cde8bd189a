//! The mission's vocabulary: where in its flight the vehicle is ([`FlightStage`]), what the
//! operator asked the drone to do ([`FlightMode`]) and where spiral-landing guidance is in
//! its plan ([`GuidancePhase`]).
//!
//! Each enum has a stable numeric code (`as u8`) that is sent over the link, so codes are
//! only ever added, never renumbered.

use serde::{Deserialize, Serialize};

/// Stage of a STRAPLEX mission, from the launch pad to the landing field (gnc.md, "Flight
/// stages").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
#[serde(rename_all = "snake_case")]
#[repr(u8)]
pub enum FlightStage {
    /// On the ground before release of the balloon.
    PreLaunch = 0,
    /// Rising under the helium balloon.
    Ascent = 1,
    /// Falling under the round parachute after burst or cutdown; nothing can be steered.
    RoundChute = 2,
    /// Round chute released, parafoil inflating and settling.
    ParafoilDeploy = 3,
    /// Controlled descent under the parafoil: guidance runs here.
    Parafoil = 4,
    /// On the ground.
    Landed = 5,
}

/// Control mode the operator selected (seed §2.2: manual and the autonomous modes of ch. 5).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
#[serde(rename_all = "snake_case")]
#[repr(u8)]
pub enum FlightMode {
    /// Servos held neutral; the parafoil flies straight by itself.
    Uncontrolled = 0,
    /// The operator's joystick drives the servos (MANUAL_CONTROL).
    Manual = 1,
    /// Hold a heading (seed §5.1.1).
    Heading = 2,
    /// Hold a course over the ground, wind-aware (seed §5.1.2).
    Course = 3,
    /// Follow a localizer line (seed §5.1.3), optionally with glide-slope control (§5.2).
    Localizer = 4,
    /// Spiral landing on the target (seed §5.3).
    SpiralLanding = 5,
}

/// Phase of spiral-landing guidance (seed §5.3, Fig. 5.7), plus the phases a real operator
/// needs around it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
#[serde(rename_all = "snake_case")]
#[repr(u8)]
pub enum GuidancePhase {
    /// Guidance is not steering (another mode is active, or not in parafoil flight).
    Idle = 0,
    /// Phase 1: flying to the entry of the spiral branch chosen by the region.
    Approximation = 1,
    /// Phases 2–5: the four branches of the square spiral around the target.
    Branch1 = 2,
    Branch2 = 3,
    Branch3 = 4,
    Branch4 = 5,
    /// Phase 6: the glide into the wind onto the target.
    FinalApproach = 6,
    /// Phase 7: full brakes below the flare height.
    Flare = 7,
    /// The wind is too strong to reach the target: flying to the best reachable point.
    BestReachable = 8,
    /// On the ground.
    Landed = 9,
}

macro_rules! impl_code {
    ($ty:ident { $($variant:ident),* $(,)? }) => {
        impl $ty {
            /// Every value, in code order.
            pub const ALL: &'static [$ty] = &[$($ty::$variant),*];

            /// The value sent over the link for this variant.
            pub fn code(self) -> u8 {
                self as u8
            }

            /// The variant for a code read from the link, `None` for an unknown code.
            pub fn from_code(code: u8) -> Option<Self> {
                Self::ALL.iter().copied().find(|v| v.code() == code)
            }
        }
    };
}

impl_code!(FlightStage {
    PreLaunch,
    Ascent,
    RoundChute,
    ParafoilDeploy,
    Parafoil,
    Landed
});
impl_code!(FlightMode {
    Uncontrolled,
    Manual,
    Heading,
    Course,
    Localizer,
    SpiralLanding
});
impl_code!(GuidancePhase {
    Idle,
    Approximation,
    Branch1,
    Branch2,
    Branch3,
    Branch4,
    FinalApproach,
    Flare,
    BestReachable,
    Landed,
});

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn codes_round_trip_and_unknown_codes_are_refused() {
        for stage in FlightStage::ALL {
            assert_eq!(FlightStage::from_code(stage.code()), Some(*stage));
        }
        for mode in FlightMode::ALL {
            assert_eq!(FlightMode::from_code(mode.code()), Some(*mode));
        }
        for phase in GuidancePhase::ALL {
            assert_eq!(GuidancePhase::from_code(phase.code()), Some(*phase));
        }
        assert_eq!(FlightStage::from_code(200), None);
        assert_eq!(FlightMode::from_code(6), None);
        assert_eq!(GuidancePhase::from_code(10), None);
    }
}

//! Which MAVLink component speaks for which body of the stack.
//!
//! A real stack measures the drone's attitude only (its AHRS, the autopilot's component),
//! unless another body carries an IMU of its own. Such a body reports as a component of the
//! drone's system, with a standard `ATTITUDE` message; the ids below are MAVLink's own
//! inertial-measurement components (`MAV_COMP_ID_IMU`, `_IMU_2`, `_IMU_3` of `minimal.xml`),
//! so other ground stations see them as what they are. The simulated drone sends them and
//! the station reads them; both take the mapping from here, the one place it is written.
//! The drone's own `ATTITUDE` keeps coming from the autopilot's component: the estimator
//! reads that one only.

/// A body of the stack that may carry an IMU of its own (the drone's is the autopilot's).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum BodyImu {
    /// The parafoil canopy.
    Canopy,
    /// The payload capsule.
    Capsule,
    /// The transponder.
    Transponder,
}

/// Interval between two attitudes of each body IMU, s (2 Hz: enough to draw the stack, a
/// small share of a 57.6 kbit/s radio).
pub const BODY_ATTITUDE_PERIOD_S: f64 = 0.5;

impl BodyImu {
    /// Every body IMU, top to bottom.
    pub const ALL: [BodyImu; 3] = [BodyImu::Canopy, BodyImu::Capsule, BodyImu::Transponder];

    /// Its MAVLink component id.
    pub fn component_id(self) -> u8 {
        match self {
            BodyImu::Canopy => 200,
            BodyImu::Capsule => 201,
            BodyImu::Transponder => 202,
        }
    }

    /// The body a component id speaks for, if it is a body IMU.
    pub fn from_component_id(id: u8) -> Option<BodyImu> {
        BodyImu::ALL.into_iter().find(|b| b.component_id() == id)
    }

    /// Lower-case name.
    pub fn name(self) -> &'static str {
        match self {
            BodyImu::Canopy => "canopy",
            BodyImu::Capsule => "capsule",
            BodyImu::Transponder => "transponder",
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn component_ids_map_both_ways_and_spare_the_autopilot() {
        for b in BodyImu::ALL {
            assert_eq!(BodyImu::from_component_id(b.component_id()), Some(b));
        }
        // MAV_COMP_ID_AUTOPILOT1: the drone's own telemetry is no body IMU's.
        assert_eq!(BodyImu::from_component_id(1), None);
        assert_eq!(BodyImu::from_component_id(0), None);
    }
}

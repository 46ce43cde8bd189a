//! Where the stack is, from a state: the height of its lowest point above the ground (the
//! event that ends every flight) and how well its constrained line lengths hold.

use stx_dynamics::model::{Body, Kinematics};
use stx_dynamics::state::{StateVector, idx};
use stx_dynamics::vehicle::Vehicle;

/// Height of the lowest point of the stack above the ground, m: the event that ends a flight.
/// Far above the ground the canopy's height stands in for it (both are positive there), which
/// spares walking the chain at every step.
pub fn height_above_ground_m(vehicle: &Vehicle, x: &StateVector) -> f64 {
    height_of_lowest_m(vehicle, x, &Body::ALL)
}

/// Height above the ground of the lowest point of `bodies`, m (the canopy's height while the
/// stack is high up).
pub fn height_of_lowest_m(vehicle: &Vehicle, x: &StateVector, bodies: &[Body]) -> f64 {
    let canopy_height = -x[idx::POSITION + 2];
    let stack_height_m = 30.0;
    if canopy_height > stack_height_m {
        return canopy_height;
    }
    let k = Kinematics::new(vehicle, x, 0.0);
    lowest_of(vehicle, &k, bodies).1
}

/// The body whose lowest point is nearest the ground, and that point's height, m.
pub fn lowest_point(vehicle: &Vehicle, k: &Kinematics) -> (Body, f64) {
    lowest_of(vehicle, k, &Body::ALL)
}

/// Among `bodies`, the one whose lowest point is nearest the ground, and that point's height,
/// m.
pub fn lowest_of(vehicle: &Vehicle, k: &Kinematics, bodies: &[Body]) -> (Body, f64) {
    let half_heights = [
        0.5 * vehicle.config.canopy.thickness_m,
        0.5 * vehicle.config.drone.height_m,
        0.5 * vehicle.capsule.height_m,
        0.5 * vehicle.transponder.height_m,
    ];
    bodies
        .iter()
        .map(|&b| {
            (
                b,
                -k.position_ned_m[b as usize].z - half_heights[b as usize],
            )
        })
        .fold((Body::Canopy, f64::INFINITY), |best, c| {
            if c.1 < best.1 { c } else { best }
        })
}

/// Largest deviation of the constrained line lengths (mean main line, capsule line,
/// transponder line) from their design values, measured between the points the lines are
/// fixed to on each body, m. Those points come from the same chain that places the bodies,
/// so the lengths hold by construction and this measures rounding in the chain only.
pub fn max_line_length_error_m(
    vehicle: &Vehicle,
    x: &StateVector,
    main_line_command_m: f64,
) -> f64 {
    let k = Kinematics::new(vehicle, x, main_line_command_m);
    let ends = k.line_ends_ned_m(vehicle);
    let top = (ends[0].0 + ends[1].0) * 0.5;
    let bottom = (ends[0].1 + ends[1].1) * 0.5;
    [
        (top - bottom).norm() - k.line_drop_m.norm(),
        (ends[2].0 - ends[2].1).norm() - vehicle.capsule_line_length_m,
        (ends[3].0 - ends[3].1).norm() - vehicle.transponder_line_length_m,
    ]
    .into_iter()
    .fold(0.0, |m, e| m.max(e.abs()))
}

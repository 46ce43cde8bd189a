//! The three control inputs: the commands guidance sends to the servos and the flight model
//! flies (seed eqs. 4.15–4.17).

use serde::{Deserialize, Serialize};

/// Control inputs, the commands to the three servos (seed eqs. 4.15–4.17).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Controls {
    /// `U_L`: differential main-line displacement, m; positive pulls the right side (turns
    /// right).
    pub main_line_m: f64,
    /// `U_SR`: right brake, normalised 0 (released) … 1 (fully pulled).
    pub brake_right: f64,
    /// `U_SL`: left brake, normalised 0 … 1.
    pub brake_left: f64,
}

impl Controls {
    /// Both brakes at `deflection` (the seed's symmetric brake `U_V`).
    pub fn symmetric_brake(deflection: f64) -> Self {
        Self {
            main_line_m: 0.0,
            brake_right: deflection,
            brake_left: deflection,
        }
    }

    /// The inputs limited to what the servos can do: |ΔL| ≤ travel, brakes in 0…1. Non-finite
    /// commands become neutral rather than poisoning the state.
    pub fn saturated(self, main_line_travel_m: f64) -> Self {
        let finite_or_zero = |v: f64| if v.is_finite() { v } else { 0.0 };
        Self {
            main_line_m: finite_or_zero(self.main_line_m)
                .clamp(-main_line_travel_m, main_line_travel_m),
            brake_right: finite_or_zero(self.brake_right).clamp(0.0, 1.0),
            brake_left: finite_or_zero(self.brake_left).clamp(0.0, 1.0),
        }
    }
}

//! The point-mass models of the stack before the parafoil flies: the balloon's ascent rate
//! as the air thins, and the stack's drag under its round chute. Shared by the flight-path
//! planner (this module's parent) and the simulated drone's mission physics (stx-sim), so
//! that what the plan predicts and what the simulation flies are the same physics.
//!
//! - Balloon: a latex balloon's free lift stays about constant on the way up while its
//!   envelope grows as `V ∝ 1/ρ`, so its drag area grows as `ρ^(−2/3)` and the rate at which
//!   lift balances drag is `v = v₀·(ρ₀/ρ)^k` with `k = 1/6` (0 gives a constant rate). What a
//!   flight is planned with is the *mean* rate `v̄` from launch to burst; the launch rate
//!   follows from the time to burst `T = H/v̄` ([`Balloon::with_mean_rate`]).
//! - Round chute: `m·dv/dt = m·g − ½ρ|v−w|(v−w)·C_D·A`; its terminal speed
//!   `√(2mg/(ρ·C_D·A))` follows the air density (about 6 m/s at the ground and 70 m/s at
//!   35 km for the STRAPLEX stack under 4 m²).

use nalgebra::Vector3;
use stx_types::atmosphere::Atmosphere;

/// The balloon's ascent model: `v = v₀·(ρ₀/ρ)^k`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Balloon {
    /// Ascent rate at the launch site, m/s.
    pub ascent_rate_mps: f64,
    /// Exponent of the density ratio.
    pub density_exponent: f64,
    /// Air density at the launch site, kg/m³.
    pub launch_density_kg_per_m3: f64,
}

/// Intervals of the Simpson rule over the climb in [`Balloon::with_mean_rate`] (even).
const CLIMB_INTERVALS: usize = 2000;

impl Balloon {
    /// Ascent rate in air of density `density_kg_per_m3`, m/s.
    pub fn ascent_rate_mps(&self, density_kg_per_m3: f64) -> f64 {
        let ratio = self.launch_density_kg_per_m3 / density_kg_per_m3.max(1e-9);
        self.ascent_rate_mps * ratio.powf(self.density_exponent)
    }

    /// The balloon that climbs from `launch_msl_m` to `burst_msl_m` (above it) in `atmosphere`
    /// at `mean_rate_mps` on average (climb over time), with density exponent `exponent`: its
    /// launch rate is `v̄·(1/H)∫(ρ/ρ₀)^k dz` (see the module documentation).
    pub fn with_mean_rate(
        mean_rate_mps: f64,
        exponent: f64,
        atmosphere: &dyn Atmosphere,
        launch_msl_m: f64,
        burst_msl_m: f64,
    ) -> Self {
        let rho0 = atmosphere.air_at(launch_msl_m).density_kg_per_m3;
        let climb_m = (burst_msl_m - launch_msl_m).max(0.0);
        let slowness = |z: f64| {
            let rho = atmosphere.air_at(launch_msl_m + z).density_kg_per_m3;
            (rho / rho0).powf(exponent)
        };
        let h = climb_m / CLIMB_INTERVALS as f64;
        let inner: f64 = (1..CLIMB_INTERVALS)
            .map(|i| slowness(i as f64 * h) * if i % 2 == 1 { 4.0 } else { 2.0 })
            .sum();
        let integral = h / 3.0 * (slowness(0.0) + inner + slowness(climb_m));
        let mean_slowness = if climb_m > 0.0 {
            integral / climb_m
        } else {
            1.0
        };
        Self {
            ascent_rate_mps: mean_rate_mps * mean_slowness,
            density_exponent: exponent,
            launch_density_kg_per_m3: rho0,
        }
    }

    /// The rate at the launch site, m/s.
    pub fn launch_rate_mps(&self) -> f64 {
        self.ascent_rate_mps
    }
}

/// The stack under its round parachute.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RoundChute {
    /// Cd·A, m².
    pub drag_area_m2: f64,
    /// Mass under the chute, kg.
    pub mass_kg: f64,
    /// Gravity, m/s².
    pub gravity_mps2: f64,
}

impl RoundChute {
    /// Acceleration, NED m/s², of the stack moving at `velocity_ned_mps` in wind `wind_ned_mps`
    /// and air of density `density_kg_per_m3`.
    pub fn acceleration(
        &self,
        velocity_ned_mps: &Vector3<f64>,
        wind_ned_mps: &Vector3<f64>,
        density_kg_per_m3: f64,
    ) -> Vector3<f64> {
        let relative = velocity_ned_mps - wind_ned_mps;
        let drag = -0.5 * density_kg_per_m3 * self.drag_area_m2 * relative.norm() * relative;
        Vector3::new(0.0, 0.0, self.gravity_mps2) + drag / self.mass_kg
    }

    /// Steady falling speed in still air of density `density_kg_per_m3`, m/s.
    pub fn terminal_speed_mps(&self, density_kg_per_m3: f64) -> f64 {
        (2.0 * self.mass_kg * self.gravity_mps2 / (density_kg_per_m3 * self.drag_area_m2)).sqrt()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use stx_types::atmosphere::StandardAtmosphere;

    #[test]
    fn balloon_rises_faster_in_thin_air_by_the_sixth_root() {
        let b = Balloon {
            ascent_rate_mps: 5.0,
            density_exponent: 1.0 / 6.0,
            launch_density_kg_per_m3: 1.2,
        };
        assert!((b.ascent_rate_mps(1.2) - 5.0).abs() < 1e-12);
        assert!((b.ascent_rate_mps(1.2 / 64.0) - 10.0).abs() < 1e-9);
    }

    #[test]
    fn the_launch_rate_gives_the_mean_ascent_rate_to_burst() {
        let atmosphere = StandardAtmosphere;
        for (burst, exponent) in [(35_000.0, 1.0 / 6.0), (3_000.0, 1.0 / 6.0), (35_000.0, 0.0)] {
            let b = Balloon::with_mean_rate(5.0, exponent, &atmosphere, 245.0, burst);
            // Time to burst by stepping through the climb (independent of the Simpson rule).
            let (mut z, mut t) = (245.0, 0.0);
            let dz = 1.0;
            while z < burst {
                let v = b.ascent_rate_mps(atmosphere.air_at(z + dz / 2.0).density_kg_per_m3);
                t += dz / v;
                z += dz;
            }
            let mean = (burst - 245.0) / t;
            assert!(
                (mean - 5.0).abs() < 2e-3,
                "{burst} m, k {exponent}: mean {mean}"
            );
            if exponent == 0.0 {
                assert!((b.launch_rate_mps() - 5.0).abs() < 1e-12);
            } else {
                assert!(b.launch_rate_mps() < 5.0);
            }
        }
        let b = Balloon::with_mean_rate(5.0, 1.0 / 6.0, &atmosphere, 245.0, 35_000.0);
        let top = b.ascent_rate_mps(atmosphere.air_at(35_000.0).density_kg_per_m3);
        assert!(
            (b.launch_rate_mps() - 3.5).abs() < 0.05,
            "{}",
            b.launch_rate_mps()
        );
        assert!((top - 8.0).abs() < 0.1, "{top}");
    }

    #[test]
    fn round_chute_drag_balances_weight_at_its_terminal_speed() {
        let c = RoundChute {
            drag_area_m2: 4.0,
            mass_kg: 9.0,
            gravity_mps2: 9.80665,
        };
        for rho in [1.2, 0.1, 0.008] {
            let v = c.terminal_speed_mps(rho);
            let a = c.acceleration(&Vector3::new(0.0, 0.0, v), &Vector3::zeros(), rho);
            assert!(a.norm() < 1e-9, "{a:?}");
        }
        // Near the ground about 6 m/s, at 35 km (ρ ≈ 0.0085) about 70 m/s.
        assert!((c.terminal_speed_mps(1.2) - 6.06).abs() < 0.1);
        assert!((c.terminal_speed_mps(0.0085) - 72.0).abs() < 2.0);
        // Horizontally the drag pulls the stack toward the wind's velocity.
        let a = c.acceleration(&Vector3::zeros(), &Vector3::new(5.0, 0.0, 0.0), 1.2);
        assert!(a.x > 0.0);
    }
}

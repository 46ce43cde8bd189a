//! Where the stack would come down if the parafoil never opened: the answer the drone's map
//! shows before release, flown coarsely through a forecast wind.

use nalgebra::Vector3;
use stx_dynamics::wind::WindField;
use stx_gnc::mission::FlightStage;

use super::MissionPhysics;

impl MissionPhysics {
    /// Where the stack would land under its round chute from `from_ned_m` (the drone's
    /// estimated position) in the `forecast` wind: rising with the balloon to the burst
    /// altitude first if still before burst, then falling at the chute's terminal speed,
    /// drifting with the forecast. `None` once the parafoil is out. Returns the touchdown
    /// point (north, east), m, and the time to it, s.
    pub fn forecast_round_chute_landing(
        &self,
        from_ned_m: &Vector3<f64>,
        forecast: &dyn WindField,
    ) -> Option<([f64; 2], f64)> {
        let ground = self.environment.ground_altitude_msl_m;
        let air = |p: &Vector3<f64>| {
            self.environment
                .atmosphere
                .air_at(ground - p.z)
                .density_kg_per_m3
        };
        let mut p = *from_ned_m;
        let mut t = 0.0;
        match self.stage {
            FlightStage::PreLaunch | FlightStage::Ascent => {
                // Coarse steps: the forecast is smooth and the answer is for a map.
                while ground - p.z < self.burst_altitude_msl_m && t < 1.0e5 {
                    let w = forecast.wind_ned_mps(self.time_s, &p);
                    let dt = 10.0;
                    p += Vector3::new(w.x, w.y, -self.balloon.ascent_rate_mps(air(&p))) * dt;
                    t += dt;
                }
            }
            FlightStage::RoundChute => {}
            _ => return None,
        }
        while p.z < 0.0 && t < 2.0e5 {
            let w = forecast.wind_ned_mps(self.time_s, &p);
            let sink = self.chute.terminal_speed_mps(air(&p));
            // About 50 m of fall per step, shorter at the end so the ground is not overshot.
            let dt = (50.0 / sink).min(-p.z / sink).max(0.05);
            p += Vector3::new(w.x, w.y, sink) * dt;
            t += dt;
        }
        Some(([p.x, p.y], t))
    }
}

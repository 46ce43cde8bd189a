//! The pitot's static pressure and temperature: the barometric height update (with its bias
//! state) and the air density the estimate reports.

use nalgebra::SMatrix;
use stx_types::atmosphere::{Atmosphere, STANDARD_GRAVITY_MPS2, StandardAtmosphere};

use super::config::Tuning;
use super::ekf::{N, Nav, Outcome, ix};
use crate::measurement::{AIR_GAS_CONSTANT, AirDataSample};

/// The air density of a sample and its 1-σ, kg/m³.
pub(super) fn air_density(a: &AirDataSample, t: &Tuning) -> (f64, f64) {
    // ρ = p/(R·T): relative errors add in quadrature.
    let density = a.density_kg_per_m3();
    let relative = (t.static_pressure_noise_pa / a.static_pressure_pa)
        .hypot(t.temperature_sigma_k / a.temperature_k);
    (density, density * relative)
}

/// Whether a static pressure has set the barometric bias of the navigation state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Barometer {
    started: bool,
}

impl Barometer {
    pub(super) const fn new() -> Self {
        Self { started: false }
    }

    /// The navigation state was started afresh: its bias is to be set again.
    pub(super) fn restart(&mut self) {
        self.started = false;
    }

    /// Barometric altitude: `ln p_s = ln p_std(h₀ − p_D) + b`.
    pub(super) fn update(&mut self, nav: &mut Nav, a: &AirDataSample, t: &Tuning) -> Outcome {
        let altitude_msl_m = t.ground_altitude_msl_m - nav.x[ix::POSITION + 2];
        let standard = StandardAtmosphere.air_at(altitude_msl_m);
        if !(standard.pressure_pa > 0.0 && standard.temperature_k > 0.0) {
            return Outcome::Unused;
        }
        let measured = a.static_pressure_pa.ln();
        let mut h = SMatrix::<f64, 1, N>::zeros();
        // d ln p / d(altitude) = −g/(R·T), and altitude = h₀ − p_D.
        h[(0, ix::POSITION + 2)] =
            STANDARD_GRAVITY_MPS2 / (AIR_GAS_CONSTANT * standard.temperature_k);
        h[(0, ix::BARO)] = 1.0;
        let r =
            SMatrix::<f64, 1, 1>::new((t.static_pressure_noise_pa / a.static_pressure_pa).powi(2));
        if !self.started {
            // First reading: the bias takes up the whole difference, uncorrelated before the
            // update ties it to the altitude's uncertainty.
            nav.x[ix::BARO] = measured - standard.pressure_pa.ln();
            for j in 0..N {
                nav.p[(ix::BARO, j)] = 0.0;
                nav.p[(j, ix::BARO)] = 0.0;
            }
            nav.p[(ix::BARO, ix::BARO)] = t.initial_baro_variance;
            nav.update(&SMatrix::<f64, 1, 1>::zeros(), &h, &r, None);
            self.started = true;
            return Outcome::Reset;
        }
        let y = SMatrix::<f64, 1, 1>::new(measured - standard.pressure_pa.ln() - nav.x[ix::BARO]);
        if nav.update(&y, &h, &r, Some(t.gate_nis[0])) {
            Outcome::Used
        } else {
            Outcome::Gated
        }
    }
}

//! The nonlinear model and its linearisation flown side by side from the same perturbed trim
//! with the same input step: how far the linear model can be trusted (`stx analyze` plots it,
//! the linearisation tests check it).

use nalgebra::DVector;
use stx_dynamics::model::ParafoilModel;
use stx_dynamics::state::StateVector;
use stx_dynamics::vehicle::Vehicle;

use crate::linearize::{LinearModel, input_vector};
use crate::lti::DiscreteSystem;
use crate::trim::{Trim, uniform_environment};

/// A state perturbed by `delta` (in the state's units) from a trim, for comparing the linear
/// and nonlinear models.
pub fn perturbed(trim: &Trim, delta: &[(usize, f64)]) -> StateVector {
    let mut x = trim.state;
    for &(i, d) in delta {
        x[i] += d;
    }
    x
}

/// Samples `(time s, nonlinear deviation, linear deviation)` of [`forced_responses`].
pub type ResponseSamples = Vec<(f64, DVector<f64>, DVector<f64>)>;

/// Responses of the nonlinear model and of its linearisation from the same perturbed state
/// `delta` with the input stepped by `du` (`[U_L m, U_S]`) at time 0, sampled every `sample_s`
/// over `duration_s`: `(time, nonlinear deviation from the trim's motion, linear deviation)`.
/// The nonlinear model flies in air of the trim's density ([`uniform_environment`]).
pub fn forced_responses(
    vehicle: &Vehicle,
    lin: &LinearModel,
    delta: &[(usize, f64)],
    du: [f64; 2],
    duration_s: f64,
    sample_s: f64,
) -> Result<ResponseSamples, String> {
    use stx_dynamics::integrate::{Hooks, Rk4, integrate};
    let t = &lin.trim;
    let mut model = ParafoilModel::new(vehicle.clone(), uniform_environment(t.altitude_m));
    let u = input_vector(&t.controls) + DVector::from_row_slice(&du);
    model.set_controls(crate::linearize::controls_of(&u));
    let disc = DiscreteSystem::new(&lin.system.a, &lin.system.b, sample_s);
    let mut x_nl = perturbed(t, delta);
    let mut dx_lin = DVector::from_column_slice((x_nl - t.state).as_slice());
    let du = DVector::from_row_slice(&du);
    let mut out = Vec::new();
    let steps = (duration_s / sample_s).round() as usize;
    for k in 0..=steps {
        let time = k as f64 * sample_s;
        // The trim moves: its position advances at the trim's rates.
        let mut reference = t.state;
        for i in 0..3 {
            reference[i] += t.derivative[i] * time;
        }
        let dev = DVector::from_column_slice((x_nl - reference).as_slice());
        out.push((time, dev, dx_lin.clone()));
        if k == steps {
            break;
        }
        let outcome = integrate(
            &mut Rk4::new(0.01),
            &mut model,
            time,
            &x_nl,
            time + sample_s,
            Hooks::default(),
        )
        .map_err(|e| e.to_string())?;
        x_nl = outcome.state;
        dx_lin = disc.step(&dx_lin, &du);
    }
    Ok(out)
}

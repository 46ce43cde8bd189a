//! Trim: the steady glide of the nonlinear model for held servo commands, in still air.
//!
//! A glide is not an equilibrium of all 31 states: the position moves at the glide's
//! velocity. Calm air and a flat Earth make the dynamics independent of the north and east
//! position and of the heading, so those are pinned (x = y = 0, ψ = 0); the altitude is pinned
//! to the one asked for (density depends on it, so it is not free, but the glide's slow drift
//! through the density gradient is not part of a trim either). The servo states equal their
//! commands (`Δ̇ = K(U − Δ)` vanishes nowhere else). The other 24 states are solved for so
//! that the 25 remaining derivatives vanish — the Euler-angle rates (heading rate included:
//! a straight glide), the 14 generalized accelerations and the relative angle rates. That is
//! one equation more than unknowns, consistent because the vehicle is left–right symmetric;
//! Levenberg–Marquardt solves it in the least-squares sense and the residual shows that it
//! was solved exactly.
//!
//! A solution is a glide only inside the model's domain: lift and drag are polynomials in α,
//! so the equations also balance flying backwards or falling flat. The canopy must fly
//! forwards, sink, and hold an angle of attack inside the range its coefficients are stated
//! for (`canopy.aero.alpha_range_deg`); anything else is refused as [`TrimError::NotAGlide`].
//! When Newton from the guess does not converge, or converges to a balance that is not such a
//! glide (with the Munk moment the guess lies in the basin of a nose-down balance the stack
//! never flies), the model flies itself for a minute and Newton starts again from there.

use std::sync::Arc;

use nalgebra::{DMatrix, DVector};
use stx_dynamics::atmosphere::{Atmosphere, StandardAtmosphere, US76_MAX_ALTITUDE_M, UniformAir};
use stx_dynamics::integrate::{Hooks, Rk4, integrate};
use stx_dynamics::model::{Body, CanopyAir, Environment, Kinematics, ParafoilModel, Tensions};
use stx_dynamics::state::{Controls, N_STATES, Pose, StateVector, idx};
use stx_dynamics::vehicle::Vehicle;
use stx_dynamics::wind::Calm;
use thiserror::Error;

use crate::jacobian::{Step, jacobian};

/// Lowest altitude a trim is computed at, m: the standard atmosphere's own lower end.
pub const MIN_ALTITUDE_M: f64 = -5_000.0;
/// Highest, m: the standard atmosphere's upper end (above it the air is extrapolated).
pub const MAX_ALTITUDE_M: f64 = US76_MAX_ALTITUDE_M;
/// Largest derivative left at a converged trim, in state-derivative units (rad/s, m/s², …).
pub const RESIDUAL_TOLERANCE: f64 = 1e-9;

/// Why no trim was found.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum TrimError {
    /// The altitude is outside the atmosphere model's range.
    #[error("altitude {altitude_m} m is outside the trim range {min_m} … {max_m} m")]
    AltitudeOutOfRange {
        altitude_m: f64,
        min_m: f64,
        max_m: f64,
    },
    /// A command is outside what the servos can do.
    #[error("trim command `{field}` = {value} is outside {rule}")]
    BadCommand {
        field: &'static str,
        value: f64,
        rule: &'static str,
    },
    /// Newton's iteration did not bring the derivatives to zero.
    #[error(
        "trim did not converge: largest derivative {residual:.3e} after {iterations} iterations \
         (tolerance {RESIDUAL_TOLERANCE:e})"
    )]
    NotConverged { iterations: usize, residual: f64 },
    /// It converged to a state in which a line pushes: not a glide this model can fly.
    #[error("trim has a slack line (tension {tension_n:.3} N): not a glide")]
    SlackLine { tension_n: f64 },
    /// It converged to a steady state outside the model's domain: flying backwards, rising,
    /// or at an angle of attack the canopy's coefficients do not describe.
    #[error("trim is not a glide the model describes: {quantity} = {value:.3} {unit} {rule}")]
    NotAGlide {
        /// What is out of range.
        quantity: &'static str,
        /// Its value.
        value: f64,
        /// Its unit.
        unit: &'static str,
        /// The rule it breaks.
        rule: String,
    },
}

/// A steady glide.
#[derive(Debug, Clone)]
pub struct Trim {
    /// The trimmed state (x = y = 0, z = −altitude, ψ = 0).
    pub state: StateVector,
    /// The held commands.
    pub controls: Controls,
    /// Altitude, m above mean sea level.
    pub altitude_m: f64,
    /// Air density there, kg/m³.
    pub density_kg_per_m3: f64,
    /// Ẋ at the trim: zero but for the position rates.
    pub derivative: StateVector,
    /// Largest derivative other than the position rates, at the end.
    pub residual: f64,
    /// Levenberg–Marquardt iterations.
    pub iterations: usize,
    /// Line tensions, N.
    pub tensions: Tensions,
    /// Canopy airspeed, m/s.
    pub airspeed_mps: f64,
    /// Canopy angle of attack, rad.
    pub alpha_rad: f64,
    /// Horizontal speed of the canopy CM, m/s.
    pub horizontal_speed_mps: f64,
    /// Sink rate, m/s (positive down).
    pub sink_rate_mps: f64,
    /// Drone velocity, inertial NED, m/s.
    pub drone_velocity_ned_mps: [f64; 3],
}

impl Trim {
    /// Glide ratio, horizontal over vertical distance.
    pub fn glide_ratio(&self) -> f64 {
        self.horizontal_speed_mps / self.sink_rate_mps
    }

    /// How fast the air around the glide changes, 1/s: the sink rate times the relative
    /// density gradient of the standard atmosphere there, `w·|d ln ρ/dh|` — the inverse of the
    /// time it takes to sink through one density scale height. A linearisation about this
    /// trim describes the motion for times short against it.
    pub fn density_change_rate_per_s(&self) -> f64 {
        const HALF_SPAN_M: f64 = 50.0;
        let rho = |h: f64| StandardAtmosphere.air_at(h).density_kg_per_m3;
        let (above, below) = (
            rho(self.altitude_m + HALF_SPAN_M),
            rho(self.altitude_m - HALF_SPAN_M),
        );
        let per_m = ((below.ln() - above.ln()) / (2.0 * HALF_SPAN_M)).abs();
        self.sink_rate_mps.abs() * per_m
    }
}

/// The still-air environment of a trim.
pub fn calm_environment() -> Environment {
    Environment {
        atmosphere: Arc::new(StandardAtmosphere),
        wind: Arc::new(Calm),
        ground_altitude_msl_m: 0.0,
    }
}

/// Calm air whose density is held at `altitude_m`'s everywhere: the environment in which a
/// trim is an exact relative equilibrium. In the standard atmosphere a glide sinks into
/// denser air and slows by about 0.3 % a minute, a drift no linearisation about a point
/// contains; comparisons of the linear and nonlinear models use this air so that they
/// measure the linearisation alone.
pub fn uniform_environment(altitude_m: f64) -> Environment {
    Environment {
        atmosphere: Arc::new(UniformAir(StandardAtmosphere.air_at(altitude_m))),
        wind: Arc::new(Calm),
        ground_altitude_msl_m: 0.0,
    }
}

/// The states solved for: all but x, y, z, ψ and the three servos.
fn free_states() -> Vec<usize> {
    (0..N_STATES)
        .filter(|&i| !(i < 3 || i == idx::CANOPY_EULER + 2 || i >= idx::MAIN_LINE))
        .collect()
}

/// The derivatives that must vanish: all but the position rates and the servo rates (zero by
/// construction).
fn residual_rows() -> Vec<usize> {
    (3..idx::MAIN_LINE).collect()
}

/// The seed's Table 6.1 glide read in km/h (flight-model.md item 4), with speeds scaled by
/// `√(ρ₀/ρ)` so that the dynamic pressure, and so the angles, stay those of sea level.
fn initial_guess(altitude_m: f64, density: f64, controls: &Controls) -> StateVector {
    let scale = (1.225 / density).sqrt();
    let mut x = Pose {
        position_ned_m: [0.0, 0.0, -altitude_m],
        canopy_euler_deg: [0.0, -8.1, 0.0],
        canopy_velocity_mps: [22.0 / 3.6 * scale, 0.0, 11.0 / 3.6 * scale],
        line_pitch_deg: -5.3,
        drone_euler_deg: [0.0, 6.1, 0.0],
        capsule_angles_deg: [0.0, -7.1],
        transponder_angles_deg: [0.0, 5.4],
        ..Default::default()
    }
    .to_state();
    x[idx::MAIN_LINE] = controls.main_line_m;
    x[idx::BRAKE_RIGHT] = controls.brake_right;
    x[idx::BRAKE_LEFT] = controls.brake_left;
    x
}

/// Trims `vehicle` at `altitude_m` with the servos held at `controls` (symmetric brakes, no
/// main line: a straight glide).
pub fn trim(vehicle: &Vehicle, altitude_m: f64, controls: Controls) -> Result<Trim, TrimError> {
    if !(MIN_ALTITUDE_M..=MAX_ALTITUDE_M).contains(&altitude_m) {
        return Err(TrimError::AltitudeOutOfRange {
            altitude_m,
            min_m: MIN_ALTITUDE_M,
            max_m: MAX_ALTITUDE_M,
        });
    }
    if controls.main_line_m != 0.0 {
        return Err(TrimError::BadCommand {
            field: "main_line_m",
            value: controls.main_line_m,
            rule: "{0}: a straight glide has the main lines centred",
        });
    }
    for (field, value) in [
        ("brake_right", controls.brake_right),
        ("brake_left", controls.brake_left),
    ] {
        if !(0.0..1.0).contains(&value) {
            return Err(TrimError::BadCommand {
                field,
                value,
                rule: "[0, 1)",
            });
        }
    }
    let env = calm_environment();
    let density = env.atmosphere.air_at(altitude_m).density_kg_per_m3;
    let mut model = ParafoilModel::new(vehicle.clone(), env);
    model.set_controls(controls);

    let guess = initial_guess(altitude_m, density, &controls);
    let glide = |solved: (StateVector, usize, f64)| glide_at(&model, altitude_m, density, solved);
    match levenberg_marquardt(&model, &guess).and_then(glide) {
        Ok(trimmed) => Ok(trimmed),
        // Far from sea level, or for an unusual vehicle, the guess may lie outside Newton's
        // basin, or in the basin of a balance the model does not fly (with the Munk moment, a
        // nose-down one at α ≈ −5°, beside the glide at 46°): let the model fly itself towards
        // its glide for a minute, then polish.
        Err(first) => {
            let settled = integrate(
                &mut Rk4::new(0.01),
                &mut model.clone(),
                0.0,
                &guess,
                60.0,
                Hooks::default(),
            );
            let retried = match settled {
                Ok(outcome) if outcome.state.iter().all(|v| v.is_finite()) => {
                    let mut x = outcome.state;
                    for i in 0..3 {
                        x[i] = guess[i];
                    }
                    x[idx::CANOPY_EULER + 2] = 0.0;
                    levenberg_marquardt(&model, &x).and_then(glide)
                }
                _ => Err(first.clone()),
            };
            // What the model flies to says more than the guess's balance; a retry that does
            // not converge says less than whatever the guess found.
            retried.map_err(|again| match again {
                TrimError::NotConverged { .. } => first,
                refused => refused,
            })
        }
    }
}

/// The trim at a converged state, if it is a glide: every line taut, inside the model's domain.
fn glide_at(
    model: &ParafoilModel,
    altitude_m: f64,
    density: f64,
    (state, iterations, residual): (StateVector, usize, f64),
) -> Result<Trim, TrimError> {
    let vehicle = &model.vehicle;
    let controls = model.controls();
    let evaluation = model.evaluate(0.0, &state);
    let tensions = evaluation.tensions;
    if tensions.min() <= 0.0 {
        return Err(TrimError::SlackLine {
            tension_n: tensions.min(),
        });
    }
    let derivative = evaluation.derivative;
    let kin = Kinematics::new(vehicle, &state, controls.main_line_m);
    let v_canopy = kin.velocity_ned_mps(Body::Canopy);
    let v_drone = kin.velocity_ned_mps(Body::Drone);
    check_domain(vehicle, &state, &evaluation.canopy_air, v_canopy.z)?;
    Ok(Trim {
        state,
        controls,
        altitude_m,
        density_kg_per_m3: density,
        derivative,
        residual,
        iterations,
        tensions,
        airspeed_mps: evaluation.canopy_air.airspeed_mps,
        alpha_rad: evaluation.canopy_air.alpha_rad,
        horizontal_speed_mps: v_canopy.x.hypot(v_canopy.y),
        sink_rate_mps: v_canopy.z,
        drone_velocity_ned_mps: [v_drone.x, v_drone.y, v_drone.z],
    })
}

/// Refuses a steady state the model does not describe as a glide: the canopy must fly forwards
/// through the air (calm air: its body-frame u), sink (nothing pushes it), and hold an angle of
/// attack inside the range its coefficients are meant for (`canopy.aero.alpha_range_deg`). Lift
/// and drag are polynomials in α, so Newton can balance them anywhere, backwards included.
fn check_domain(
    vehicle: &Vehicle,
    state: &StateVector,
    air: &CanopyAir,
    sink_rate_mps: f64,
) -> Result<(), TrimError> {
    let forward_mps = state[idx::CANOPY_VELOCITY];
    // NaN is refused with the rest: only a positive value passes.
    if forward_mps.is_nan() || forward_mps <= 0.0 {
        return Err(TrimError::NotAGlide {
            quantity: "canopy forward speed u",
            value: forward_mps,
            unit: "m/s",
            rule: "must be > 0: the canopy would fly backwards".into(),
        });
    }
    if sink_rate_mps.is_nan() || sink_rate_mps <= 0.0 {
        return Err(TrimError::NotAGlide {
            quantity: "sink rate",
            value: sink_rate_mps,
            unit: "m/s",
            rule: "must be > 0: an unpowered glide descends".into(),
        });
    }
    let [low, high] = vehicle.config.canopy.aero.alpha_range_deg;
    let alpha_deg = air.alpha_rad.to_degrees();
    if !(low..=high).contains(&alpha_deg) {
        return Err(TrimError::NotAGlide {
            quantity: "angle of attack",
            value: alpha_deg,
            unit: "deg",
            rule: format!(
                "is outside [{low}, {high}] deg, the range the canopy's coefficients describe \
                 (canopy.aero.alpha_range_deg)"
            ),
        });
    }
    Ok(())
}

/// Largest |derivative| over the residual rows.
fn residual_of(model: &ParafoilModel, x: &StateVector) -> (DVector<f64>, f64) {
    let dx = model.evaluate(0.0, x).derivative;
    let rows = residual_rows();
    let r = DVector::from_iterator(rows.len(), rows.iter().map(|&i| dx[i]));
    let max = r.iter().map(|v| v.abs()).fold(0.0, f64::max);
    (r, if max.is_nan() { f64::INFINITY } else { max })
}

/// Levenberg–Marquardt on the free states: `(JᵀJ + λ diag JᵀJ) δ = −Jᵀr`, λ shrunk after a
/// step that lowers ‖r‖ and grown after one that does not.
fn levenberg_marquardt(
    model: &ParafoilModel,
    start: &StateVector,
) -> Result<(StateVector, usize, f64), TrimError> {
    const MAX_ITERATIONS: usize = 100;
    let free = free_states();
    let mut x = *start;
    let (mut r, mut worst) = residual_of(model, &x);
    let mut cost = r.norm_squared();
    let mut lambda = 1e-3;
    let scales = vec![1.0; free.len()];
    let steps = vec![Step::Central; free.len()];
    for iteration in 0..MAX_ITERATIONS {
        if worst < RESIDUAL_TOLERANCE {
            return Ok((x, iteration, worst));
        }
        let base = x;
        let j = jacobian(
            |z: &DVector<f64>| {
                let mut y = base;
                for (k, &i) in free.iter().enumerate() {
                    y[i] = z[k];
                }
                residual_of(model, &y).0
            },
            &DVector::from_iterator(free.len(), free.iter().map(|&i| x[i])),
            &scales,
            &steps,
        );
        let jtj = j.transpose() * &j;
        let g = j.transpose() * &r;
        let mut improved = false;
        for _ in 0..12 {
            let mut lhs: DMatrix<f64> = jtj.clone();
            for k in 0..free.len() {
                lhs[(k, k)] += lambda * jtj[(k, k)].max(1e-12);
            }
            let Some(delta) = lhs.lu().solve(&(-&g)) else {
                lambda *= 10.0;
                continue;
            };
            let mut trial = x;
            for (k, &i) in free.iter().enumerate() {
                trial[i] += delta[k];
            }
            let (r_trial, worst_trial) = residual_of(model, &trial);
            let cost_trial = r_trial.norm_squared();
            if cost_trial.is_finite() && cost_trial < cost {
                x = trial;
                r = r_trial;
                worst = worst_trial;
                cost = cost_trial;
                lambda = (lambda / 10.0).max(1e-12);
                improved = true;
                break;
            }
            lambda *= 10.0;
        }
        if !improved {
            return if worst < RESIDUAL_TOLERANCE {
                Ok((x, iteration, worst))
            } else {
                Err(TrimError::NotConverged {
                    iterations: iteration,
                    residual: worst,
                })
            };
        }
    }
    if worst < RESIDUAL_TOLERANCE {
        Ok((x, MAX_ITERATIONS, worst))
    } else {
        Err(TrimError::NotConverged {
            iterations: MAX_ITERATIONS,
            residual: worst,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sea_level_glide_has_vanishing_derivatives_and_taut_lines() {
        let v = Vehicle::straplex();
        let t = trim(&v, 100.0, Controls::default()).expect("trim");
        assert!(t.residual < RESIDUAL_TOLERANCE, "{}", t.residual);
        // The full derivative, not just the rows solved: only the position moves.
        for i in 3..N_STATES {
            assert!(
                t.derivative[i].abs() < 1e-8,
                "{} = {}",
                idx::NAMES[i],
                t.derivative[i]
            );
        }
        assert!(t.tensions.min() > 0.0);
        // Symmetric: no lateral state.
        for i in idx::LATERAL {
            assert!(
                t.state[i].abs() < 1e-8,
                "{} = {}",
                idx::NAMES[i],
                t.state[i]
            );
        }
        // Flight tests (seed §3.2.2): about 18 km/h forward, 10 km/h down, glide ≈ 2.
        assert!((4.0..8.0).contains(&t.horizontal_speed_mps), "{t:?}");
        assert!((1.5..4.5).contains(&t.sink_rate_mps), "{t:?}");
        assert!((1.5..3.5).contains(&t.glide_ratio()), "{}", t.glide_ratio());
    }

    #[test]
    fn thin_air_glides_faster_at_the_same_angle_of_attack() {
        let v = Vehicle::straplex();
        let low = trim(&v, 0.0, Controls::default()).expect("trim at sea level");
        let high = trim(&v, 20_000.0, Controls::default()).expect("trim at 20 km");
        let expected = (low.density_kg_per_m3 / high.density_kg_per_m3).sqrt();
        let ratio = high.airspeed_mps / low.airspeed_mps;
        // Apparent mass and the pendants' drag scale the same way with density, so the
        // airspeed goes with 1/√ρ to within a few per cent.
        assert!(
            (ratio / expected - 1.0).abs() < 0.05,
            "{ratio} vs {expected}"
        );
        assert!((high.alpha_rad - low.alpha_rad).abs() < 0.02);
    }

    #[test]
    fn brakes_steepen_the_glide() {
        let v = Vehicle::straplex();
        let free = trim(&v, 100.0, Controls::default()).expect("trim");
        let braked = trim(&v, 100.0, Controls::symmetric_brake(0.4)).expect("braked trim");
        assert!(braked.glide_ratio() < free.glide_ratio());
    }

    fn vehicle_with(edits: &[(&str, &str)]) -> Vehicle {
        let mut text = stx_dynamics::vehicle::STRAPLEX_TOML.to_string();
        for (from, to) in edits {
            assert!(text.contains(from), "{from}");
            text = text.replace(from, to);
        }
        Vehicle::from_toml_str(&text).expect("a valid vehicle file")
    }

    #[test]
    fn a_canopy_with_negative_lift_does_not_trim_flying_backwards() {
        // Regression: cl0 = −3 with no lift slope "trimmed" at u = −1.68 m/s, α = 126°, and
        // was reported as a steady glide.
        let v = vehicle_with(&[
            ("cl0 = 0.250", "cl0 = -3.0"),
            ("cl_alpha = 2.300", "cl_alpha = 0.0"),
        ]);
        match trim(&v, 100.0, Controls::default()) {
            Err(TrimError::NotAGlide {
                quantity, value, ..
            }) => {
                assert_eq!(quantity, "canopy forward speed u");
                assert!(value < 0.0, "{value}");
            }
            other => panic!("expected a refusal, got {other:?}"),
        }
    }

    #[test]
    fn a_trim_outside_the_coefficients_angle_of_attack_range_is_refused() {
        // Without a lift slope the canopy "trims" falling nearly flat at α ≈ 89°.
        let v = vehicle_with(&[("cl_alpha = 2.300", "cl_alpha = 0.0")]);
        let err = trim(&v, 100.0, Controls::default()).expect_err("not a glide");
        match &err {
            TrimError::NotAGlide {
                quantity, value, ..
            } => {
                assert_eq!(*quantity, "angle of attack");
                assert!(*value > 80.0, "{value}");
            }
            other => panic!("expected the angle of attack to be refused, got {other:?}"),
        }
        assert!(err.to_string().contains("alpha_range_deg"), "{err}");
        // The same vehicle is accepted when its file says its coefficients hold there.
        let wide = vehicle_with(&[
            ("cl_alpha = 2.300", "cl_alpha = 0.0"),
            (
                "alpha_range_deg = [0.0, 45.0]",
                "alpha_range_deg = [0.0, 90.0]",
            ),
        ]);
        let t = trim(&wide, 100.0, Controls::default()).expect("inside the stated range");
        assert!(t.alpha_rad.to_degrees() > 80.0);
    }

    #[test]
    fn a_balance_the_model_does_not_fly_is_passed_over_for_the_glide_it_flies() {
        // With the Munk moment, Newton from the Table 6.1 guess balances the canopy nose-down
        // at α ≈ −5°, outside the coefficients' range; the stack itself glides at α ≈ 46°.
        let munk = [("munk_moment = false", "munk_moment = true")];
        let err = trim(&vehicle_with(&munk), 100.0, Controls::default())
            .expect_err("46° is outside the shipped 0…45°");
        match err {
            TrimError::NotAGlide { value, .. } => assert!((45.0..48.0).contains(&value), "{value}"),
            other => panic!("expected the flown glide's α to be refused, got {other:?}"),
        }
        let wide = vehicle_with(&[
            munk[0],
            (
                "alpha_range_deg = [0.0, 45.0]",
                "alpha_range_deg = [0.0, 60.0]",
            ),
        ]);
        let t = trim(&wide, 100.0, Controls::default()).expect("inside the stated range");
        assert!(t.residual < RESIDUAL_TOLERANCE);
        let alpha_deg = t.alpha_rad.to_degrees();
        assert!((45.0..48.0).contains(&alpha_deg), "{alpha_deg}");
        // The shipped vehicle converges from the guess, as before.
        let shipped = trim(&Vehicle::straplex(), 100.0, Controls::default()).expect("trims");
        assert!(shipped.iterations < 10);
    }

    #[test]
    fn a_canopy_too_small_to_carry_the_stack_does_not_converge() {
        // 10 cm² of canopy: no glide near the guess, none after flying a minute either.
        let v = vehicle_with(&[("area_m2 = 3.000 ", "area_m2 = 0.001 ")]);
        match trim(&v, 100.0, Controls::default()) {
            Err(TrimError::NotConverged {
                iterations,
                residual,
            }) => {
                assert!(residual > RESIDUAL_TOLERANCE, "{residual}");
                assert!(iterations > 0);
            }
            other => panic!("expected no convergence, got {other:?}"),
        }
    }

    #[test]
    fn refuses_altitudes_outside_the_atmosphere_and_bad_commands() {
        let v = Vehicle::straplex();
        assert!(matches!(
            trim(&v, 120_000.0, Controls::default()),
            Err(TrimError::AltitudeOutOfRange { .. })
        ));
        assert!(matches!(
            trim(&v, f64::NAN, Controls::default()),
            Err(TrimError::AltitudeOutOfRange { .. })
        ));
        assert!(matches!(
            trim(&v, 100.0, Controls::symmetric_brake(1.5)),
            Err(TrimError::BadCommand { .. })
        ));
    }
}

//! `stx analyze`: trim, linearise, and report eigenvalues, modes and ranks beside the seed's.

use nalgebra::{Complex, DMatrix, DVector};
use serde::Serialize;
use stx_dynamics::state::{Controls, N_STATES, idx};
use stx_dynamics::vehicle::Vehicle;

use crate::linearize::{INPUT_NAMES, LinearModel, OUTPUT_NAMES, linearize};
use crate::lti::{HautusReport, LinearSystem, RankReport, balance, hautus, scaled, staircase_rank};
use crate::seed::{self, SeedReference};
use crate::trim::{Trim, TrimError, trim};

/// Floor of the zero threshold, s⁻¹: far above the 1e-11 at which the exact invariances (x,
/// y, ψ) come out, far below any mode of the vehicle. It decides only where the air's density
/// does not change along the glide.
pub const NUMERICAL_ZERO_FLOOR: f64 = 1e-6;

/// Rank tolerance relative to the norm of the balanced pair (`lti::balance`): a direction is
/// lost when `[λI − A, B]` (or the staircase's step) has a singular value below
/// `1e-5 · max(‖A‖₂, ‖B‖₂)` in the system's own units. From 100 m to 40 km the lost directions
/// sit at least 4× below it and every kept one at least 5× above (the report lists them all,
/// and warns when one comes within [`MARGIN_FACTOR`]).
pub const RANK_RELATIVE_TOLERANCE: f64 = 1e-5;

/// A decision whose nearest singular value or eigenvalue lies within this factor of its
/// threshold is reported as marginal.
pub const MARGIN_FACTOR: f64 = 3.0;

/// Relative size (largest entry against `A`'s largest) of the mirror-antisymmetric part of
/// `A` below which it is finite-difference noise: at a symmetric trim it is ≈ 1e-11.
pub const MIRROR_NOISE: f64 = 1e-8;

/// The zero threshold for a model trimmed at `trim`, s⁻¹: an eigenvalue slower than the rate
/// at which the glide's air changes ([`Trim::density_change_rate_per_s`]) cannot be told from
/// the drift of the trim itself, and counts as zero. The altitude's own mode, the glide
/// sinking into denser air, is half that rate by the 1/√ρ law of the glide's speed, so it
/// counts as zero at every altitude, as it is in the seed's constant-density model.
pub fn zero_tolerance(trim: &Trim) -> f64 {
    trim.density_change_rate_per_s().max(NUMERICAL_ZERO_FLOOR)
}

/// One state's trimmed value.
#[derive(Debug, Clone, Serialize)]
pub struct NamedValue {
    /// State name (`stx_dynamics::state::idx::NAMES`).
    pub name: &'static str,
    /// Value in SI units (angles in rad).
    pub value: f64,
    /// Unit.
    pub unit: &'static str,
}

/// The trim as reported.
#[derive(Debug, Clone, Serialize)]
pub struct TrimReport {
    /// Altitude, m.
    pub altitude_m: f64,
    /// Air density, kg/m³.
    pub density_kg_per_m3: f64,
    /// Every state.
    pub state: Vec<NamedValue>,
    /// Canopy airspeed, m/s.
    pub airspeed_mps: f64,
    /// Canopy angle of attack, degrees.
    pub alpha_deg: f64,
    /// Canopy CM velocity in the canopy frame, u and w, m/s. (Table 6.1's "u" and "w" are not
    /// these but the ground speeds, `horizontal_speed_mps` and `sink_rate_mps`, in km/h.)
    pub u_c_mps: f64,
    /// See `u_c_mps`.
    pub w_c_mps: f64,
    /// Pitch angles of Table 6.1, degrees: θ_C/I, θ_L/C, θ_D/L, θ_CAP/D, θ_T/CAP.
    pub pitch_chain_deg: [f64; 5],
    /// Horizontal speed, m/s.
    pub horizontal_speed_mps: f64,
    /// Sink rate, m/s.
    pub sink_rate_mps: f64,
    /// Glide ratio.
    pub glide_ratio: f64,
    /// Tensions: right main, left main, capsule line, transponder line, N.
    pub tensions_n: [f64; 4],
    /// Largest derivative left (position rates excepted).
    pub residual: f64,
    /// Levenberg–Marquardt iterations.
    pub iterations: usize,
}

/// One eigenvalue (upper half-plane of a pair) with what moves in it.
#[derive(Debug, Clone, Serialize)]
pub struct Mode {
    /// `[re, im]`, s⁻¹.
    pub eigenvalue: [f64; 2],
    /// Natural frequency |λ|, rad/s.
    pub natural_frequency_rad_s: f64,
    /// Damping ratio −re/|λ|.
    pub damping_ratio: f64,
    /// The states that dominate its eigenvector (coordinates; rates and velocities divided by
    /// |λ| so that they count as the displacement they cause), with their share.
    pub dominant_states: Vec<(String, f64)>,
    /// The seed eigenvalue paired with it (nearest, each used once).
    pub seed: Option<[f64; 2]>,
}

/// Everything `stx analyze` reports.
#[derive(Debug, Clone, Serialize)]
pub struct AnalysisReport {
    /// The trim.
    pub trim: TrimReport,
    /// States in the model.
    pub n_states: usize,
    /// Eigenvalues of A, `[re, im]`, sorted by real part (largest first).
    pub eigenvalues: Vec<[f64; 2]>,
    /// How many have |λ| below `zero_tolerance`.
    pub zero_eigenvalues: usize,
    /// The zero threshold, s⁻¹ ([`zero_tolerance`]).
    pub zero_tolerance: f64,
    /// What the zero threshold is, in words with its numbers.
    pub zero_tolerance_basis: String,
    /// Largest real part among the others, s⁻¹ (negative: stable).
    pub max_real_part_nonzero: f64,
    /// Modes, one per real eigenvalue or conjugate pair.
    pub modes: Vec<Mode>,
    /// Inputs.
    pub inputs: [&'static str; 2],
    /// Outputs (seed eq. 6.4).
    pub outputs: [&'static str; 9],
    /// Controllability rank with both inputs (Hautus test).
    pub controllability_rank: usize,
    /// Observability rank with the outputs (Hautus test).
    pub observability_rank: usize,
    /// Rank tolerance relative to the balanced matrices' norm.
    pub rank_relative_tolerance: f64,
    /// Controllability with the main line alone (orthogonal staircase, which counts a lost
    /// Jordan chain in full where the Hautus test counts one direction).
    pub controllability_rank_main_line_only: usize,
    /// Controllability with the brake alone (orthogonal staircase).
    pub controllability_rank_brake_only: usize,
    /// Every mode's Hautus singular values for controllability.
    pub controllability: HautusReport,
    /// The same for observability.
    pub observability: HautusReport,
    /// Cross-check: the orthogonal staircase's controllability rank and step singular values.
    pub controllability_staircase: RankReport,
    /// Cross-check for observability.
    pub observability_staircase: RankReport,
    /// Base-2 logarithms of the state scaling the rank tests ran in (`lti::balance`), for
    /// controllability (`[A B]`) and observability (`[Aᵀ Cᵀ]`), in state order.
    pub state_scaling_log2: StateScaling,
    /// Largest entry of `A`'s mirror-antisymmetric part against `A`'s largest: finite-difference
    /// noise (≈ 1e-11) at a symmetric trim. Below [`MIRROR_NOISE`] the rank tests ran on the
    /// mirror-symmetric part, which keeps the lateral and longitudinal motions exactly apart.
    pub mirror_asymmetry: f64,
    /// Decisions that are uncertain: the two rank methods disagree, a singular value or an
    /// eigenvalue lies within [`MARGIN_FACTOR`] of its threshold, or the model is not
    /// symmetric. Empty when every decision is clear.
    pub warnings: Vec<String>,
    /// The matrices, row by row.
    pub matrices: Matrices,
    /// The seed's values.
    pub seed: SeedReference,
}

/// State scalings, as powers of two.
#[derive(Debug, Clone, Serialize)]
pub struct StateScaling {
    /// Balancing `[A B]`.
    pub controllability: Vec<i32>,
    /// Balancing `[Aᵀ Cᵀ]`.
    pub observability: Vec<i32>,
}

/// A, B, C, D row by row.
#[derive(Debug, Clone, Serialize)]
pub struct Matrices {
    /// State names, the order of A's rows and columns.
    pub states: Vec<&'static str>,
    /// A.
    pub a: Vec<Vec<f64>>,
    /// B.
    pub b: Vec<Vec<f64>>,
    /// C.
    pub c: Vec<Vec<f64>>,
    /// D.
    pub d: Vec<Vec<f64>>,
}

fn rows(m: &DMatrix<f64>) -> Vec<Vec<f64>> {
    m.row_iter().map(|r| r.iter().copied().collect()).collect()
}

/// Trims at `altitude_m` with released controls, linearises and analyses.
pub fn analyze(
    vehicle: &Vehicle,
    altitude_m: f64,
) -> Result<(AnalysisReport, LinearModel), TrimError> {
    let t = trim(vehicle, altitude_m, Controls::default())?;
    let lin = linearize(vehicle, &t);
    Ok((report(&lin), lin))
}

/// The left–right mirror: the sign of every lateral state (y, roll and yaw of each body,
/// sideslip velocity, roll and yaw rates, the differential main line), with the two brake
/// servos swapped.
fn state_mirror() -> DMatrix<f64> {
    let mut m = DMatrix::identity(N_STATES, N_STATES);
    for i in idx::LATERAL {
        m[(i, i)] = -1.0;
    }
    let (r, l) = (idx::BRAKE_RIGHT, idx::BRAKE_LEFT);
    (m[(r, r)], m[(l, l)], m[(r, l)], m[(l, r)]) = (0.0, 0.0, 1.0, 1.0);
    m
}

/// The mirror-symmetric part of a system linearised at a symmetric trim, and the relative
/// size of what it drops from `A`. Finite differences leave lateral–longitudinal couplings of
/// 1e-11 relative where symmetry makes them zero; the staircase multiplies by `A` thirty times
/// and would grow them into directions a single input does not reach.
pub fn mirror_symmetric(sys: &LinearSystem) -> (LinearSystem, f64) {
    let s = state_mirror();
    // Inputs: U_L flips, U_S does not. Outputs x y z u v w φ θ ψ: y, v, φ, ψ flip.
    let s_u = DMatrix::from_diagonal(&DVector::from_vec(vec![-1.0, 1.0]));
    let s_y = DMatrix::from_diagonal(&DVector::from_vec(vec![
        1.0, -1.0, 1.0, 1.0, -1.0, 1.0, -1.0, 1.0, -1.0,
    ]));
    let mirrored_a = &s * &sys.a * &s;
    let asymmetry = (&sys.a - &mirrored_a).amax() * 0.5 / sys.a.amax().max(f64::MIN_POSITIVE);
    let symmetric = LinearSystem {
        a: (&sys.a + mirrored_a) * 0.5,
        b: (&sys.b + &s * &sys.b * &s_u) * 0.5,
        c: (&sys.c + &s_y * &sys.c * &s) * 0.5,
        d: (&sys.d + &s_y * &sys.d * &s_u) * 0.5,
    };
    (symmetric, asymmetry)
}

/// Warnings about one rank decision: the two methods disagree, or a singular value either
/// method decided on lies within [`MARGIN_FACTOR`] of the tolerance.
pub fn rank_warnings(what: &str, hautus: &HautusReport, staircase: &RankReport) -> Vec<String> {
    let mut warnings = Vec::new();
    if hautus.rank != staircase.rank {
        warnings.push(format!(
            "{what}: the Hautus test gives rank {} and the orthogonal staircase {}; the rank \
             is uncertain",
            hautus.rank, staircase.rank
        ));
    }
    let tolerance = hautus.absolute_tolerance;
    let kept = hautus
        .modes
        .iter()
        .filter_map(|m| m.smallest_singular_values.get(m.deficiency).copied())
        .fold(f64::INFINITY, f64::min);
    let lost = hautus
        .modes
        .iter()
        .filter(|m| m.deficiency > 0)
        .map(|m| m.smallest_singular_values[m.deficiency - 1])
        .fold(0.0, f64::max);
    let close = |value: f64| value < MARGIN_FACTOR * tolerance && value > tolerance / MARGIN_FACTOR;
    for (method, kept, lost) in [
        ("Hautus", kept, lost),
        (
            "staircase",
            staircase.smallest_kept,
            staircase.largest_dropped,
        ),
    ] {
        for (side, value) in [("kept", kept), ("lost", lost)] {
            if close(value) {
                warnings.push(format!(
                    "{what}: a {side} direction's singular value {value:.2e} ({method}) is \
                     within a factor {MARGIN_FACTOR} of the tolerance {tolerance:.2e}"
                ));
            }
        }
    }
    warnings
}

/// The report of a linear model.
pub fn report(lin: &LinearModel) -> AnalysisReport {
    let raw = &lin.system;
    let eigenvalues = raw.eigenvalues();
    let zero_tol = zero_tolerance(&lin.trim);
    let is_zero = |e: &(f64, f64)| e.0.hypot(e.1) < zero_tol;
    let zero = eigenvalues.iter().filter(|e| is_zero(e)).count();
    let max_real = eigenvalues
        .iter()
        .filter(|e| !is_zero(e))
        .map(|e| e.0)
        .fold(f64::NEG_INFINITY, f64::max);
    let mut warnings = Vec::new();
    let slowest_nonzero = eigenvalues
        .iter()
        .filter(|e| !is_zero(e))
        .map(|e| e.0.hypot(e.1))
        .fold(f64::INFINITY, f64::min);
    if slowest_nonzero < MARGIN_FACTOR * zero_tol {
        warnings.push(format!(
            "an eigenvalue of modulus {slowest_nonzero:.2e} 1/s counts as non-zero but lies \
             within a factor {MARGIN_FACTOR} of the zero threshold {zero_tol:.2e} 1/s"
        ));
    }

    let (symmetric, asymmetry) = mirror_symmetric(raw);
    let sys = if asymmetry <= MIRROR_NOISE {
        &symmetric
    } else {
        warnings.push(format!(
            "the linear model is not mirror-symmetric (antisymmetric part {asymmetry:.1e} of A); \
             ranks are decided on it as it is"
        ));
        raw
    };
    let scaling_c = balance(&sys.a, &sys.b);
    let (a_c, b_c) = scaled(&sys.a, &sys.b, &scaling_c);
    let (a_t, c_t) = (sys.a.transpose(), sys.c.transpose());
    let scaling_o = balance(&a_t, &c_t);
    let (a_o, c_o) = scaled(&a_t, &c_t, &scaling_o);
    let controllability = hautus(&a_c, &b_c, RANK_RELATIVE_TOLERANCE, zero_tol);
    let observability = hautus(&a_o, &c_o, RANK_RELATIVE_TOLERANCE, zero_tol);
    let controllability_staircase = staircase_rank(&a_c, &b_c, RANK_RELATIVE_TOLERANCE);
    let observability_staircase = staircase_rank(&a_o, &c_o, RANK_RELATIVE_TOLERANCE);
    warnings.extend(rank_warnings(
        "controllability",
        &controllability,
        &controllability_staircase,
    ));
    warnings.extend(rank_warnings(
        "observability",
        &observability,
        &observability_staircase,
    ));
    let single = |col: usize| {
        staircase_rank(
            &a_c,
            &b_c.columns(col, 1).into_owned(),
            RANK_RELATIVE_TOLERANCE,
        )
        .rank
    };
    let log2 = |d: &DVector<f64>| d.iter().map(|v| v.log2().round() as i32).collect();
    AnalysisReport {
        trim: trim_report(&lin.trim),
        n_states: raw.n_states(),
        modes: modes(&raw.a, &eigenvalues, lin.servo_rates_per_s, zero_tol),
        eigenvalues: eigenvalues.iter().map(|&(re, im)| [re, im]).collect(),
        zero_eigenvalues: zero,
        zero_tolerance: zero_tol,
        zero_tolerance_basis: format!(
            "the rate at which the glide's air changes: sink {:.2} m/s × |d ln ρ/dh| {:.3e} 1/m \
             (floor {NUMERICAL_ZERO_FLOOR:e} 1/s)",
            lin.trim.sink_rate_mps,
            lin.trim.density_change_rate_per_s() / lin.trim.sink_rate_mps.abs()
        ),
        max_real_part_nonzero: max_real,
        inputs: INPUT_NAMES,
        outputs: OUTPUT_NAMES,
        controllability_rank: controllability.rank,
        observability_rank: observability.rank,
        rank_relative_tolerance: RANK_RELATIVE_TOLERANCE,
        controllability_rank_main_line_only: single(0),
        controllability_rank_brake_only: single(1),
        controllability,
        observability,
        controllability_staircase,
        observability_staircase,
        state_scaling_log2: StateScaling {
            controllability: log2(&scaling_c),
            observability: log2(&scaling_o),
        },
        mirror_asymmetry: asymmetry,
        warnings,
        matrices: Matrices {
            states: idx::NAMES.to_vec(),
            a: rows(&raw.a),
            b: rows(&raw.b),
            c: rows(&raw.c),
            d: rows(&raw.d),
        },
        seed: seed::reference(),
    }
}

fn unit_of(i: usize) -> &'static str {
    match i {
        0..=2 => "m",
        6..=8 => "m/s",
        9..=11 | 13 | 17..=19 | 22 | 23 | 26 | 27 => "rad/s",
        idx::MAIN_LINE => "m",
        idx::BRAKE_RIGHT | idx::BRAKE_LEFT => "1",
        _ => "rad",
    }
}

fn trim_report(t: &Trim) -> TrimReport {
    let x = &t.state;
    TrimReport {
        altitude_m: t.altitude_m,
        density_kg_per_m3: t.density_kg_per_m3,
        state: (0..N_STATES)
            .map(|i| NamedValue {
                name: idx::NAMES[i],
                value: x[i],
                unit: unit_of(i),
            })
            .collect(),
        airspeed_mps: t.airspeed_mps,
        alpha_deg: t.alpha_rad.to_degrees(),
        u_c_mps: x[idx::CANOPY_VELOCITY],
        w_c_mps: x[idx::CANOPY_VELOCITY + 2],
        pitch_chain_deg: [
            x[idx::CANOPY_EULER + 1].to_degrees(),
            x[idx::LINE_PITCH].to_degrees(),
            x[idx::DRONE_EULER + 1].to_degrees(),
            x[idx::CAPSULE_ANGLES + 1].to_degrees(),
            x[idx::TRANSPONDER_ANGLES + 1].to_degrees(),
        ],
        horizontal_speed_mps: t.horizontal_speed_mps,
        sink_rate_mps: t.sink_rate_mps,
        glide_ratio: t.glide_ratio(),
        tensions_n: t.tensions.as_array(),
        residual: t.residual,
        iterations: t.iterations,
    }
}

/// Whether state `i` is a rate or velocity (its displacement is the value over |λ|).
fn is_rate(i: usize) -> bool {
    matches!(i, 6..=11 | 13 | 17..=19 | 22 | 23 | 26 | 27)
}

/// The eigenvector of `λ` by inverse iteration on `A − (λ + δ) I` in complex arithmetic.
fn eigenvector(a: &DMatrix<f64>, re: f64, im: f64) -> Option<DVector<Complex<f64>>> {
    let n = a.nrows();
    let shift = Complex::new(re, im) + Complex::new(1e-7 * (1.0 + re.hypot(im)), 0.0);
    let mut m = a.map(|v| Complex::new(v, 0.0));
    for i in 0..n {
        m[(i, i)] -= shift;
    }
    let lu = m.lu();
    let mut v = DVector::from_element(n, Complex::new(1.0, 0.0));
    for _ in 0..3 {
        v = lu.solve(&v)?;
        let norm = v.norm();
        if !(norm.is_finite() && norm > 0.0) {
            return None;
        }
        v /= Complex::new(norm, 0.0);
    }
    Some(v)
}

fn modes(
    a: &DMatrix<f64>,
    eigenvalues: &[(f64, f64)],
    servo_rates: [f64; 3],
    zero_tolerance: f64,
) -> Vec<Mode> {
    let ours: Vec<(f64, f64)> = eigenvalues.iter().copied().filter(|e| e.1 >= 0.0).collect();
    let seed_upper: Vec<(f64, f64)> = seed::EIGENVALUES
        .iter()
        .copied()
        .filter(|e| e.1 >= 0.0)
        .collect();
    let pairing = pair_nearest(&ours, &seed_upper);
    ours.iter()
        .enumerate()
        .map(|(k, &(re, im))| {
            let modulus = re.hypot(im);
            let is_servo = im == 0.0 && servo_rates.iter().any(|k| (re + k).abs() < 1e-6);
            let dominant = if modulus < zero_tolerance {
                vec![(
                    "x, y, psi_c (invariances), z (drifts with the air)".to_string(),
                    1.0,
                )]
            } else if is_servo {
                // A repeated eigenvalue: its eigenvectors are any mix of the servos'.
                vec![("delta_l, servo_r, servo_l (servo lags)".to_string(), 1.0)]
            } else {
                eigenvector(a, re, im)
                    .map(|v| {
                        let weights: Vec<f64> = (0..v.len())
                            .map(|i| {
                                let w = v[i].norm();
                                if is_rate(i) { w / modulus } else { w }
                            })
                            .collect();
                        let total: f64 = weights.iter().sum();
                        let mut order: Vec<usize> = (0..weights.len()).collect();
                        order.sort_by(|&i, &j| weights[j].total_cmp(&weights[i]));
                        order
                            .into_iter()
                            .take(3)
                            .map(|i| (idx::NAMES[i].to_string(), weights[i] / total))
                            .collect()
                    })
                    .unwrap_or_default()
            };
            Mode {
                eigenvalue: [re, im],
                natural_frequency_rad_s: modulus,
                // Undefined for the invariances: reported as 0.
                damping_ratio: if modulus >= zero_tolerance {
                    -re / modulus
                } else {
                    0.0
                },
                dominant_states: dominant,
                seed: pairing[k].map(|j| [seed_upper[j].0, seed_upper[j].1]),
            }
        })
        .collect()
}

/// Pairs each of `ours` with a distinct nearest of `theirs`, greedily by distance in the
/// complex plane relative to the seed value's size (so 0.1 apart matters more at −0.3 than at
/// −15 ± 10j).
pub fn pair_nearest(ours: &[(f64, f64)], theirs: &[(f64, f64)]) -> Vec<Option<usize>> {
    let mut candidates: Vec<(f64, usize, usize)> = Vec::new();
    for (i, a) in ours.iter().enumerate() {
        for (j, b) in theirs.iter().enumerate() {
            let d = (a.0 - b.0).hypot(a.1 - b.1) / (0.5 + b.0.hypot(b.1));
            candidates.push((d, i, j));
        }
    }
    candidates.sort_by(|p, q| p.0.total_cmp(&q.0));
    let mut result = vec![None; ours.len()];
    let mut used = vec![false; theirs.len()];
    for (_, i, j) in candidates {
        if result[i].is_none() && !used[j] {
            result[i] = Some(j);
            used[j] = true;
        }
    }
    result
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pairing_uses_each_seed_value_once_and_prefers_the_nearest() {
        let ours = [(-0.2, 1.6), (-0.35, 1.7), (-5.0, 0.0)];
        let theirs = [(-0.36, 1.64), (-0.26, 1.53), (-5.0, 0.0), (-0.62, 0.0)];
        let p = pair_nearest(&ours, &theirs);
        assert_eq!(p, vec![Some(1), Some(0), Some(2)]);
    }

    #[test]
    fn disagreeing_rank_methods_and_marginal_values_are_warned_about() {
        // A chain of lags whose last, fast mode the input reaches only weakly: the Hautus
        // singular value there falls below the tolerance while the staircase keeps it.
        let a = DMatrix::from_row_slice(3, 3, &[-0.02, 0.0, 0.0, 0.3, -0.05, 0.0, 0.0, 0.3, -30.0]);
        let b = DMatrix::from_row_slice(3, 1, &[1.0, 0.0, 0.0]);
        let h = crate::lti::hautus(&a, &b, 1e-5, 1e-6);
        let s = crate::lti::staircase_rank(&a, &b, 1e-5);
        assert_ne!(h.rank, s.rank);
        let warnings = rank_warnings("controllability", &h, &s);
        assert!(
            warnings
                .iter()
                .any(|w| w.contains("Hautus test gives rank 2")),
            "{warnings:?}"
        );
        // Clear decisions raise nothing.
        let a = DMatrix::from_row_slice(2, 2, &[-1.0, 0.0, 1.0, -2.0]);
        let b = DMatrix::from_row_slice(2, 1, &[1.0, 0.0]);
        let h = crate::lti::hautus(&a, &b, 1e-5, 1e-6);
        let s = crate::lti::staircase_rank(&a, &b, 1e-5);
        assert!(rank_warnings("controllability", &h, &s).is_empty());
    }

    #[test]
    fn the_mirror_keeps_a_symmetric_system_and_measures_an_asymmetric_one() {
        let mut a = DMatrix::<f64>::zeros(N_STATES, N_STATES);
        // Longitudinal u ← θ and lateral v ← φ couplings are symmetric; v ← θ is not.
        a[(idx::CANOPY_VELOCITY, idx::CANOPY_EULER + 1)] = -9.8;
        a[(idx::CANOPY_VELOCITY + 1, idx::CANOPY_EULER)] = 9.8;
        let sys = LinearSystem {
            a: a.clone(),
            b: DMatrix::zeros(N_STATES, 2),
            c: DMatrix::zeros(9, N_STATES),
            d: DMatrix::zeros(9, 2),
        };
        let (sym, asymmetry) = mirror_symmetric(&sys);
        assert_eq!(asymmetry, 0.0);
        assert_eq!(sym.a, a);
        let mut skew = sys.clone();
        skew.a[(idx::CANOPY_VELOCITY + 1, idx::CANOPY_EULER + 1)] = 0.98;
        let (sym, asymmetry) = mirror_symmetric(&skew);
        assert!((asymmetry - 0.1).abs() < 1e-12, "{asymmetry}");
        assert_eq!(
            sym.a[(idx::CANOPY_VELOCITY + 1, idx::CANOPY_EULER + 1)],
            0.0
        );
    }

    #[test]
    fn inverse_iteration_finds_the_eigenvector_of_a_known_matrix() {
        // Block diagonal: an oscillator in states 0–1 and a lag in state 2.
        let a = DMatrix::from_row_slice(3, 3, &[0.0, 1.0, 0.0, -4.0, -0.4, 0.0, 0.0, 0.0, -5.0]);
        let v = eigenvector(&a, -5.0, 0.0).expect("vector");
        assert!(v[2].norm() > 0.999 && v[0].norm() < 1e-6);
        let im = (4.0f64 - 0.04).sqrt();
        let w = eigenvector(&a, -0.2, im).expect("vector");
        assert!(w[2].norm() < 1e-6);
        // Second component is λ times the first.
        let ratio = w[1] / w[0];
        assert!((ratio - Complex::new(-0.2, im)).norm() < 1e-5, "{ratio}");
    }
}

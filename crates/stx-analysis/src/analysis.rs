//! `stx analyze`: trim, linearise, and report eigenvalues, modes and ranks beside the seed's.

use nalgebra::{Complex, DMatrix, DVector};
use serde::Serialize;
use stx_dynamics::state::{Controls, N_STATES, idx};
use stx_dynamics::vehicle::Vehicle;

use crate::linearize::{INPUT_NAMES, LinearModel, OUTPUT_NAMES, linearize};
use crate::lti::{HautusReport, RankReport};
use crate::seed::{self, SeedReference};
use crate::trim::{Trim, TrimError, trim};

/// An eigenvalue counts as zero below this modulus, s⁻¹: a time constant over 1000 s, longer
/// than a descent from 3 km. The altitude's mode (density gradient) sits near 10⁻⁴.
pub const ZERO_EIGENVALUE_TOLERANCE: f64 = 1e-3;

/// Rank tolerance relative to `max(‖A‖₂, ‖B‖₂)` (or `‖C‖₂`); `‖A‖₂` is about 4500 (the
/// stiff line-pitch and drone modes), so the absolute tolerance is about 4.5·10⁻⁴. At the
/// sea-level trim the Hautus singular values of the modes that are controllable are all
/// above 0.03, and the two that are not sit at 10⁻⁶ (the x/z direction, reachable only
/// through the density gradient) and 0 (the antisymmetric brake): the tolerance lies two
/// decades from either side. The report lists every mode's values so the choice can be
/// checked.
pub const RANK_RELATIVE_TOLERANCE: f64 = 1e-7;

/// Eigenvalues closer than this are tested together (the four invariances, the three servo
/// lags), s⁻¹: the zero threshold.
pub const RANK_CLUSTER_TOLERANCE: f64 = ZERO_EIGENVALUE_TOLERANCE;

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
    /// Canopy CM velocity in the canopy frame, u and w, m/s (seed Table 6.1's u, w).
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
    /// The zero threshold, s⁻¹.
    pub zero_tolerance: f64,
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
    /// Rank tolerance relative to the matrices' norm.
    pub rank_relative_tolerance: f64,
    /// Controllability with the main line alone (Hautus; a lower bound on what is lost where
    /// an uncontrollable eigenvalue is defective, as the y–ψ chain is for the brake alone).
    pub controllability_rank_main_line_only: usize,
    /// Controllability with the brake alone (same caveat).
    pub controllability_rank_brake_only: usize,
    /// Every mode's Hautus singular values for controllability.
    pub controllability: HautusReport,
    /// The same for observability.
    pub observability: HautusReport,
    /// Cross-check: the orthogonal staircase's controllability rank and step singular values.
    pub controllability_staircase: RankReport,
    /// Cross-check for observability.
    pub observability_staircase: RankReport,
    /// The matrices, row by row.
    pub matrices: Matrices,
    /// The seed's values.
    pub seed: SeedReference,
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

/// The report of a linear model.
pub fn report(lin: &LinearModel) -> AnalysisReport {
    let sys = &lin.system;
    let eigenvalues = sys.eigenvalues();
    let zero = eigenvalues
        .iter()
        .filter(|(re, im)| re.hypot(*im) < ZERO_EIGENVALUE_TOLERANCE)
        .count();
    let max_real = eigenvalues
        .iter()
        .filter(|(re, im)| re.hypot(*im) >= ZERO_EIGENVALUE_TOLERANCE)
        .map(|e| e.0)
        .fold(f64::NEG_INFINITY, f64::max);
    let controllability =
        sys.controllability_hautus(RANK_RELATIVE_TOLERANCE, RANK_CLUSTER_TOLERANCE);
    let observability = sys.observability_hautus(RANK_RELATIVE_TOLERANCE, RANK_CLUSTER_TOLERANCE);
    let single = |col: usize| {
        crate::lti::hautus(
            &sys.a,
            &sys.b.columns(col, 1).into_owned(),
            RANK_RELATIVE_TOLERANCE,
            RANK_CLUSTER_TOLERANCE,
        )
        .rank
    };
    AnalysisReport {
        trim: trim_report(&lin.trim),
        n_states: sys.n_states(),
        modes: modes(&sys.a, &eigenvalues, lin.servo_rates_per_s),
        eigenvalues: eigenvalues.iter().map(|&(re, im)| [re, im]).collect(),
        zero_eigenvalues: zero,
        zero_tolerance: ZERO_EIGENVALUE_TOLERANCE,
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
        controllability_staircase: sys.controllability(RANK_RELATIVE_TOLERANCE),
        observability_staircase: sys.observability(RANK_RELATIVE_TOLERANCE),
        matrices: Matrices {
            states: idx::NAMES.to_vec(),
            a: rows(&sys.a),
            b: rows(&sys.b),
            c: rows(&sys.c),
            d: rows(&sys.d),
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

fn modes(a: &DMatrix<f64>, eigenvalues: &[(f64, f64)], servo_rates: [f64; 3]) -> Vec<Mode> {
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
            let dominant = if modulus < ZERO_EIGENVALUE_TOLERANCE {
                vec![("x, y, z, psi_c (invariance)".to_string(), 1.0)]
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
                damping_ratio: if modulus >= ZERO_EIGENVALUE_TOLERANCE {
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

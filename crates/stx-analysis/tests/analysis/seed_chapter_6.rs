//! The seed's chapter 6 and appendix A.12 at 100 m: the trim of Table 6.1, the eigenvalues of
//! §6.2.1 matched mode by mode, and the kinematic rows of the matrix A. (Its ranks, 29 and 31,
//! are asserted in linearisation.rs, `stability_results_match_the_seeds_shape`.)
//!
//! As in stx-sim's seed_behaviour.rs: `seed_…` tests assert the seed's figures within the
//! tolerance their statement carries, and what of them holds where ours differ by more;
//! `regression_pin_…` tests pin our own figures (ANALYSIS_NOTES.md and MODEL_NOTES.md give
//! both with the reasons for each difference).

use std::sync::OnceLock;

use stx_analysis::analysis::{AnalysisReport, analyze};
use stx_analysis::linearize::LinearModel;
use stx_dynamics::state::idx;
use stx_dynamics::vehicle::Vehicle;

/// The shipped vehicle analysed at 100 m, once for every test of this file.
fn at_100_m() -> &'static (AnalysisReport, LinearModel) {
    static ANALYSIS: OnceLock<(AnalysisReport, LinearModel)> = OnceLock::new();
    ANALYSIS.get_or_init(|| analyze(&Vehicle::straplex(), 100.0).expect("trim"))
}

fn assert_within(what: &str, value: f64, low: f64, high: f64, why: &str) {
    assert!(
        (low..=high).contains(&value),
        "{what}: ours {value:.4}, the seed allows [{low:.4}, {high:.4}] ({why})"
    );
}

fn assert_pinned(what: &str, value: f64, expected: f64, tolerance: f64) {
    assert!(
        (value - expected).abs() <= tolerance,
        "{what}: {value} where the notes document {expected} (±{tolerance})"
    );
}

/// Table 6.1's pitch angles, degrees: θ_C/I, θ_L/C, θ_D/L, θ_CAP/D, θ_T/CAP.
const TABLE_6_1_PITCH_DEG: [f64; 5] = [-8.1, -5.3, 6.1, -7.1, 5.4];
/// Table 6.1's u and w, printed "22m/s" and "11m/s": km/h (A.12's rows give them as 6.1 and
/// 3.1 m/s), and the canopy's ground speeds forward and down (A.12's ẋ and ż rows).
const TABLE_6_1_SPEEDS_KMH: [f64; 2] = [22.0, 11.0];

#[test]
fn seed_table_6_1_trim() {
    let t = &at_100_m().0.trim;
    // The speeds, printed to two significant figures: ±0.5 km/h. (A.12 prints the same point
    // finer, and there ours fall 0.2 % and 3 % short: seed_a12_position_rows_….)
    let [forward, down] = TABLE_6_1_SPEEDS_KMH;
    let why = "printed to two significant figures";
    let horizontal_kmh = t.horizontal_speed_mps * 3.6;
    assert_within(
        "horizontal speed, km/h",
        horizontal_kmh,
        forward - 0.5,
        forward + 0.5,
        why,
    );
    let sink_kmh = t.sink_rate_mps * 3.6;
    assert_within("sink rate, km/h", sink_kmh, down - 0.5, down + 0.5, why);
    // The angles of the canopy and of the capsule and transponder swings: "this equilibrium
    // point was chosen observing the simulation results" (§6.1.1), i.e. read off the plots of
    // chapter 4, to about half a degree.
    let why = "read off plots: ±0.5°";
    for (k, name) in [(0, "θ_C/I"), (3, "θ_CAP/D"), (4, "θ_T/CAP")] {
        let seed = TABLE_6_1_PITCH_DEG[k];
        assert_within(name, t.pitch_chain_deg[k], seed - 0.5, seed + 0.5, why);
    }
    // The angle of attack those imply: the canopy's pitch less the path angle of 22 and 11
    // km/h, each within its reading, 16.4° to 20.5° (the old reading, atan(11/22) = 26.6°,
    // took u and w for the canopy frame's components).
    let path = |f: f64, d: f64| (d / f).atan().to_degrees();
    let low = TABLE_6_1_PITCH_DEG[0] - 0.5 + path(forward + 0.5, down - 0.5);
    let high = TABLE_6_1_PITCH_DEG[0] + 0.5 + path(forward - 0.5, down + 0.5);
    assert_within(
        "angle of attack, deg",
        t.alpha_deg,
        low,
        high,
        "from the above",
    );
    // The line frame and the drone differ by 2° (−3.2° against −5.3°, 4.2° against 6.1°: our
    // readings of the line geometry, MODEL_NOTES.md); what holds is the shape: the lines lean
    // nose-down against the canopy and the drone nose-up against the lines, by degrees.
    for (k, name) in [(1, "θ_L/C"), (2, "θ_D/L")] {
        let (seed, ours) = (TABLE_6_1_PITCH_DEG[k], t.pitch_chain_deg[k]);
        assert!(
            seed.signum() == ours.signum() && (1.0..10.0).contains(&ours.abs()),
            "{name}: ours {ours:.2}°, the seed's {seed}°"
        );
    }
}

#[test]
fn regression_pin_trim_at_100_m() {
    let t = &at_100_m().0.trim;
    for (k, ours) in [-7.81, -3.17, 4.18, -7.33, 5.26].into_iter().enumerate() {
        assert_pinned("pitch chain, deg", t.pitch_chain_deg[k], ours, 0.02);
    }
    assert_pinned("u_C, m/s", t.u_c_mps, 6.39, 0.01);
    assert_pinned("w_C, m/s", t.w_c_mps, 2.11, 0.01);
    assert_pinned("angle of attack, deg", t.alpha_deg, 18.28, 0.02);
    assert_pinned("airspeed, m/s", t.airspeed_mps, 6.73, 0.01);
    assert_pinned("horizontal speed, m/s", t.horizontal_speed_mps, 6.04, 0.01);
    assert_pinned("sink rate, m/s", t.sink_rate_mps, 2.96, 0.01);
    assert_pinned("glide ratio", t.glide_ratio, 2.04, 0.01);
}

/// A mode of §6.2.1: the seed's eigenvalue, what moves in it, and a state that must dominate
/// our eigenvector for our eigenvalue to be the same mode.
struct SeedMode {
    seed: [f64; 2],
    motion: &'static str,
    dominant: &'static str,
}

const fn mode(re: f64, im: f64, motion: &'static str, dominant: &'static str) -> SeedMode {
    SeedMode {
        seed: [re, im],
        motion,
        dominant,
    }
}

/// The modes whose eigenvalues we reproduce: those the pendulum geometry and the masses set.
const AGREEING: [SeedMode; 9] = [
    mode(
        -0.26,
        1.53,
        "lateral swing of capsule and transponder",
        "phi_t",
    ),
    mode(-0.36, 1.64, "longitudinal swing", "theta_t"),
    mode(-0.40, 0.93, "phugoid", "z"),
    mode(-0.62, 0.0, "heading and drift subsidence", "y"),
    mode(-0.74, 3.85, "drone twist about its lines", "psi_d"),
    mode(-0.91, 5.34, "drone twist, second", "psi_d"),
    mode(-1.16, 22.98, "drone–capsule pitch", "theta_d"),
    mode(-1.32, 30.72, "drone–capsule roll", "phi_cap"),
    mode(-5.0, 0.0, "servo lags", "servo"),
];

/// The modes we do not: those the canopy's aerodynamic damping and apparent inertia set,
/// with our eigenvalue.
const DIFFERING: [(SeedMode, [f64; 2]); 5] = [
    (mode(-1.17, 4.45, "longitudinal", "u_c"), [-0.828, 4.576]),
    (
        mode(-1.88, 6.53, "canopy pitch against the lines", "theta_l"),
        [-2.980, 7.647],
    ),
    (mode(-2.03, 0.0, "roll subsidence", "psi_c"), [-3.268, 0.0]),
    (
        mode(-3.91, 5.50, "canopy yaw–roll", "psi_c"),
        [-5.249, 5.734],
    ),
    (
        mode(-15.30, 10.47, "canopy–line pitch", "theta_l"),
        [-17.786, 10.215],
    ),
];

/// Our eigenvalue paired with `m`'s (the report pairs each with the nearest seed value, each
/// used once), checked to be the same motion by its eigenvector.
fn ours_for(report: &AnalysisReport, m: &SeedMode) -> Vec<[f64; 2]> {
    let ours: Vec<[f64; 2]> = report
        .modes
        .iter()
        .filter(|x| x.seed == Some(m.seed))
        .inspect(|x| {
            assert!(
                x.dominant_states
                    .iter()
                    .any(|(s, _)| s.contains(m.dominant)),
                "{}: ours {:?} is moved by {:?}, not {}",
                m.motion,
                x.eigenvalue,
                x.dominant_states,
                m.dominant
            )
        })
        .map(|x| x.eigenvalue)
        .collect();
    assert!(!ours.is_empty(), "{}: no eigenvalue paired", m.motion);
    ours
}

#[test]
fn seed_6_2_1_eigenvalues_by_mode() {
    // The seed prints two decimals; our readings of its garbled equations move the modes. We
    // call a mode reproduced when its frequency is within 5 % and its decay rate within 12 %
    // of the seed's. The modes fall in two groups with nothing between: those set by the
    // pendulum geometry and the masses, all within 3.3 % in frequency and 10.7 % in decay
    // rate, and those set by the canopy's aerodynamic damping and apparent inertia, 16 % to
    // 61 % off in decay rate (pinned below; ANALYSIS_NOTES.md, "Eigenvalues").
    let (report, _) = at_100_m();
    assert_eq!(report.zero_eigenvalues, 4, "x, y, ψ and z");
    for m in &AGREEING {
        for ours in ours_for(report, m) {
            let decay = (ours[0] - m.seed[0]).abs() / m.seed[0].abs();
            let frequency = if m.seed[1] == 0.0 {
                ours[1].abs()
            } else {
                (ours[1] - m.seed[1]).abs() / m.seed[1]
            };
            assert!(
                decay <= 0.12 && frequency <= 0.05,
                "{}: ours {ours:?} against the seed's {:?}",
                m.motion,
                m.seed
            );
        }
    }
    // Every mode the seed lists is stable in ours too, and oscillates where the seed's does.
    for (m, _) in &DIFFERING {
        for ours in ours_for(report, m) {
            assert!(ours[0] < 0.0, "{}: {ours:?}", m.motion);
            assert_eq!(ours[1] == 0.0, m.seed[1] == 0.0, "{}", m.motion);
        }
    }
}

#[test]
fn regression_pin_canopy_modes() {
    let (report, _) = at_100_m();
    for (m, pinned) in &DIFFERING {
        let ours = ours_for(report, m);
        assert_eq!(ours.len(), 1, "{}", m.motion);
        for k in 0..2 {
            assert_pinned(m.motion, ours[0][k], pinned[k], 0.01 * pinned[0].abs());
        }
    }
}

/// A.12's entries of the canopy's position rows: ∂ẋ/∂θ, ∂ż/∂θ, ∂ẏ/∂ψ, ∂ẏ/∂φ, ∂ẋ/∂u, ∂ẋ/∂w,
/// ∂ż/∂u. In a straight glide they are ż, −ẋ, ẋ, −w, cos θ, sin θ, −sin θ.
const A12_POSITION_ROWS: [f64; 7] = [3.1, -6.1, 6.1, -3.7, 0.99, 0.11, -0.11];

/// The same entries of our A.
fn position_rows(lin: &LinearModel) -> [f64; 7] {
    let a = &lin.system.a;
    let (x, y, z) = (idx::POSITION, idx::POSITION + 1, idx::POSITION + 2);
    let (phi, theta, psi) = (
        idx::CANOPY_EULER,
        idx::CANOPY_EULER + 1,
        idx::CANOPY_EULER + 2,
    );
    let (u, w) = (idx::CANOPY_VELOCITY, idx::CANOPY_VELOCITY + 2);
    [
        a[(x, theta)],
        a[(z, theta)],
        a[(y, psi)],
        a[(y, phi)],
        a[(x, u)],
        a[(x, w)],
        a[(z, u)],
    ]
}

#[test]
fn seed_a12_position_rows_give_table_6_1_speeds_but_another_pitch() {
    // Appendix A.12 prints A to two significant figures (±0.05 here). Its position rows are
    // the canopy's ground speeds (ẋ = 6.1 m/s = 22 km/h, ż = 3.1 m/s = 11 km/h: Table 6.1 in
    // km/h) and its pitch: sin θ = +0.11, θ_C/I = +6.3° with w = 3.7 m/s (α ≈ 33°), not
    // Table 6.1's −8.1°. The pitch's cosine, 0.99, holds for both and for ours.
    let (report, lin) = at_100_m();
    let ours = position_rows(lin);
    let t = &report.trim;
    // Our rows are what they stand for, so comparing entries compares speeds and pitch.
    let theta = t.pitch_chain_deg[0].to_radians();
    let stands_for = [
        t.sink_rate_mps,
        -t.horizontal_speed_mps,
        t.horizontal_speed_mps,
        -t.w_c_mps,
        theta.cos(),
        theta.sin(),
        -theta.sin(),
    ];
    for (k, (o, s)) in ours.iter().zip(stands_for).enumerate() {
        assert!((o - s).abs() < 1e-6, "entry {k}: {o} against {s}");
    }
    let seed = A12_POSITION_ROWS[4];
    assert_within(
        "cos θ_C/I",
        ours[4],
        seed - 0.005,
        seed + 0.005,
        "two figures",
    );
    // At A.12's precision our ground speeds fall short, by 0.2 % forward (6.04 against
    // 6.05–6.15 m/s) and 3 % down (2.96 against 3.05–3.15): pinned in
    // regression_pin_trim_at_100_m. What holds is the reading of Table 6.1's units, which the
    // two readings put a factor 3.6 apart: ours and A.12's are its figures in km/h, moving
    // forwards and down, not in m/s.
    let kmh = TABLE_6_1_SPEEDS_KMH.map(|v| v / 3.6);
    for (k, table) in [(0, kmh[1]), (1, -kmh[0]), (2, kmh[0])] {
        let (seed, ours) = (A12_POSITION_ROWS[k], ours[k]);
        assert!((seed / table - 1.0).abs() < 0.05, "A.12 entry {k}: {seed}");
        assert!((ours / table - 1.0).abs() < 0.1, "our entry {k}: {ours}");
    }
    // The pitch is A.12's other point: ours has Table 6.1's sign and the seed's A.12 the
    // opposite, and a canopy-frame w 43 % below A.12's (pinned with the trim).
    assert!(ours[5] < 0.0 && A12_POSITION_ROWS[5] > 0.0);
}

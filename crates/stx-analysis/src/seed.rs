//! The seed thesis' published results of chapter 6 and appendix A.13, for side-by-side
//! comparison (flight-model.md item 4).

use serde::Serialize;

/// Eigenvalues of seed §6.2.1, `(re, im)`, conjugates written out.
pub const EIGENVALUES: [(f64, f64); 31] = [
    (0.0, 0.0),
    (0.0, 0.0),
    (0.0, 0.0),
    (0.0, 0.0),
    (-0.26, 1.53),
    (-0.26, -1.53),
    (-0.36, 1.64),
    (-0.36, -1.64),
    (-0.40, 0.93),
    (-0.40, -0.93),
    (-0.62, 0.0),
    (-0.74, 3.85),
    (-0.74, -3.85),
    (-0.91, 5.34),
    (-0.91, -5.34),
    (-1.16, 22.98),
    (-1.16, -22.98),
    (-1.17, 4.45),
    (-1.17, -4.45),
    (-1.32, 30.72),
    (-1.32, -30.72),
    (-1.88, 6.53),
    (-1.88, -6.53),
    (-2.03, 0.0),
    (-3.91, 5.50),
    (-3.91, -5.50),
    (-5.0, 0.0),
    (-5.0, 0.0),
    (-5.0, 0.0),
    (-15.30, 10.47),
    (-15.30, -10.47),
];

/// Controllability rank with the two inputs (seed §6.2.2): x and z uncontrollable.
pub const CONTROLLABILITY_RANK: usize = 29;
/// Observability rank with the drone's outputs (seed §6.2.3).
pub const OBSERVABILITY_RANK: usize = 31;

/// One of the seed's optimal gain vectors (appendix A.13), read as the gains of our laws.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct SeedGains {
    /// The vector's name in the seed.
    pub vector: &'static str,
    /// HK1 or VK1 as printed (the coefficient of ψ, or of θ for the vertical law).
    pub k1: f64,
    /// HK2 or VK2.
    pub k2: f64,
    /// HK3, where the law has one.
    pub k3: Option<f64>,
    /// How the numbers were read from the vector.
    pub reading: &'static str,
}

/// The seed's heading vector K_H1: non-zero entries 1.6e-2 on ψ and 2.1e-2 on r.
pub const HEADING: SeedGains = SeedGains {
    vector: "K_H1",
    k1: 0.016,
    k2: 0.021,
    k3: None,
    reading: "HK1 = K[ψ], HK2 = K[r] (ψ̇ ≈ r in a straight glide)",
};

/// The course vector K_H2: 1.8e-2 on ψ, 2.5e-2 on r, and the course's dependence on φ
/// (−6.3e-3) and v (2.9e-3), both HK1 times the course's partial derivatives.
pub const COURSE: SeedGains = SeedGains {
    vector: "K_H2",
    k1: 0.018,
    k2: 0.025,
    k3: None,
    reading: "HK1 = K[ψ], HK2 = K[r]; K[v]/K[ψ] = 1/V_h gives V_h ≈ 6.2 m/s",
};

/// The localizer's following-phase vector K_H3b: 5.6e-1 on ψ, 3.6e-1 on r, 2.2e-1 on y (the
/// approach phase K_H3a equals K_H2).
pub const LOCALIZER: SeedGains = SeedGains {
    vector: "K_H3b",
    k1: 0.56,
    k2: 0.36,
    k3: Some(0.22),
    reading: "HK1 = K[ψ], HK2 = K[r], HK3 = K[y] (course 0: CT = y)",
};

/// The vertical following-phase vector K_Vb: 5.1 on θ, 2.3e-1 on u, −7.0e-1 on w, −8.9e-1
/// on z and 2.2e-1 on x and y.
pub const VERTICAL: SeedGains = SeedGains {
    vector: "K_Vb",
    k1: 3.4,
    k2: 0.89,
    k3: None,
    reading: "K[θ] = VK1·(1 + GS²) with the seed's trim (GS ≈ 0.69) gives |VK1| ≈ 3.4; \
              VK2 = −K[z] (A = −z + …); the seed's brake sign is opposite to ours",
};

/// The seed's values in one object for the JSON report.
#[derive(Debug, Clone, Serialize)]
pub struct SeedReference {
    /// Eigenvalues `[re, im]`.
    pub eigenvalues: Vec<[f64; 2]>,
    /// How many are zero.
    pub zero_eigenvalues: usize,
    /// Largest real part among the others.
    pub max_real_part_nonzero: f64,
    /// Controllability rank.
    pub controllability_rank: usize,
    /// Observability rank.
    pub observability_rank: usize,
    /// States.
    pub n_states: usize,
    /// Seed Table 6.1 trim, as printed.
    pub trim_table_6_1: &'static str,
    /// Gain vectors of appendix A.13.
    pub gains: [SeedGains; 4],
    /// Where the numbers come from.
    pub source: &'static str,
}

/// The seed's chapter-6 values.
pub fn reference() -> SeedReference {
    SeedReference {
        eigenvalues: EIGENVALUES.iter().map(|&(re, im)| [re, im]).collect(),
        zero_eigenvalues: 4,
        max_real_part_nonzero: -0.26,
        controllability_rank: CONTROLLABILITY_RANK,
        observability_rank: OBSERVABILITY_RANK,
        n_states: 31,
        trim_table_6_1: "u = 22, w = 11 (printed m/s; the canopy's ground speeds forward and \
                         down in km/h, 6.1 and 3.1 m/s as A.12 prints them), θ_C/I = −8.1°, θ_L/C = −5.3°, θ_D/L = 6.1°, θ_CAP/D = −7.1°, \
                         θ_T/CAP = 5.4°",
        gains: [HEADING, COURSE, LOCALIZER, VERTICAL],
        source: "seed §6.1–6.3, Table 6.1, appendix A.13; shared/spec/flight-model.md item 4",
    }
}

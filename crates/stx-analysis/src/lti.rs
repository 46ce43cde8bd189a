//! Linear time-invariant systems `ẋ = A x + B u`, `y = C x + D u`: eigenvalues,
//! controllability and observability ranks, and exact discretisation for simulation.
//!
//! Ranks. The textbook test is the rank of the Kalman matrix `[B AB … A^{n−1}B]` (seed eq.
//! 6.8). For the flight model it is useless numerically: its eigenvalues span 0.2 to 35 rad/s,
//! so `A^{30}` is ~10^{46} times `A^0`, the columns become parallel and the rank depends on
//! the tolerance more than on the system. The same subspace is built here by the orthogonal
//! *staircase* (Krylov) iteration: start from an orthonormal basis of `range B`, multiply the
//! newest block by `A`, remove what the basis already spans, and keep the directions whose
//! singular values exceed the tolerance. Each step's singular values are reported, so the gap
//! between the smallest kept and the largest dropped — what the rank decision rests on — is
//! visible. Observability is controllability of `(Aᵀ, Cᵀ)`.
//!
//! The staircase still multiplies by `A` once per step, and a direction kept near the
//! tolerance is normalised and explored, so rounding in `A` (finite differences, ~10⁻⁹
//! relative) can be amplified into a spurious subspace when one input reaches little of the
//! space. The [`hautus`] test (Popov–Belevitch–Hautus) needs no powers: `(A, B)` loses one
//! controllable direction for every singular value of `[λI − A, B]` that vanishes at an
//! eigenvalue `λ`. Each mode's smallest singular value is a measure of how controllable it
//! is, which is what a person wants to see. It counts the uncontrollable eigenvalues with
//! their geometric multiplicity, exact when they are not defective (so for the flight model,
//! whose only repeated eigenvalues are the servo lags and the invariances). `stx analyze`
//! reports the Hautus ranks and the staircase as a cross-check.
//!
//! Scale. Both tests compare singular values with a tolerance, and singular values depend on
//! the units the states are written in: in SI units the flight model's `A` mixes metres with
//! radians and 80 m/s of glide at 35 km, its norm (≈ 5000) says more about units than about
//! dynamics, and a slow mode's eigenvector can be all `y` metres. [`balance`] first rescales
//! the states by powers of two (exact, a similarity: eigenvalues and ranks are unchanged) so
//! that every state's couplings in and out of `[A B]` are of one size — the system's own
//! units (Osborne's iteration, as SLICOT's TB01ID does before its staircase). Tolerances are
//! then relative to the balanced norms.

use nalgebra::{DMatrix, DVector};
use serde::Serialize;

/// A continuous-time LTI system.
#[derive(Debug, Clone, PartialEq)]
pub struct LinearSystem {
    /// State matrix, n×n.
    pub a: DMatrix<f64>,
    /// Input matrix, n×m.
    pub b: DMatrix<f64>,
    /// Output matrix, q×n.
    pub c: DMatrix<f64>,
    /// Feedthrough, q×m.
    pub d: DMatrix<f64>,
}

impl LinearSystem {
    /// Number of states.
    pub fn n_states(&self) -> usize {
        self.a.nrows()
    }

    /// Eigenvalues of `A`, sorted by real part, largest first (then by imaginary part).
    pub fn eigenvalues(&self) -> Vec<(f64, f64)> {
        eigenvalues(&self.a)
    }

    /// Rank of the controllable subspace of `(A, B)`.
    pub fn controllability(&self, relative_tolerance: f64) -> RankReport {
        staircase_rank(&self.a, &self.b, relative_tolerance)
    }

    /// Rank of the observable subspace of `(A, C)`.
    pub fn observability(&self, relative_tolerance: f64) -> RankReport {
        staircase_rank(&self.a.transpose(), &self.c.transpose(), relative_tolerance)
    }

    /// Controllable dimension by the Hautus test.
    pub fn controllability_hautus(&self, relative_tolerance: f64, cluster: f64) -> HautusReport {
        hautus(&self.a, &self.b, relative_tolerance, cluster)
    }

    /// Observable dimension by the Hautus test (`[λI − A; C]`, as `(Aᵀ, Cᵀ)`).
    pub fn observability_hautus(&self, relative_tolerance: f64, cluster: f64) -> HautusReport {
        hautus(
            &self.a.transpose(),
            &self.c.transpose(),
            relative_tolerance,
            cluster,
        )
    }
}

/// Eigenvalues `(re, im)` of a square matrix, sorted by real part (largest first), then by
/// imaginary part (positive first), so conjugate pairs sit together.
///
/// nalgebra's plain `complex_eigenvalues` iterates without a cap and was seen to spin on the
/// transpose of the flight model's `A`; the Schur form is computed with a cap here, and on
/// the transpose (same eigenvalues) if the matrix itself does not converge. NaN if neither.
pub fn eigenvalues(a: &DMatrix<f64>) -> Vec<(f64, f64)> {
    const MAX_ITERATIONS: usize = 100_000;
    let schur = a
        .clone()
        .try_schur(f64::EPSILON, MAX_ITERATIONS)
        .or_else(|| a.transpose().try_schur(f64::EPSILON, MAX_ITERATIONS));
    let mut ev: Vec<(f64, f64)> = match schur {
        Some(s) => s
            .complex_eigenvalues()
            .iter()
            .map(|c| (c.re, c.im))
            .collect(),
        None => vec![(f64::NAN, f64::NAN); a.nrows()],
    };
    ev.sort_by(|p, q| q.0.total_cmp(&p.0).then(q.1.total_cmp(&p.1)));
    ev
}

/// Diagonal state scaling `d` (powers of two) that balances the pair `(A, B)`: with
/// `A' = D⁻¹ A D` and `B' = D⁻¹ B`, each state's off-diagonal row of `[A' B']` and column of
/// `A'` have nearly equal 1-norms (Osborne's iteration; a state with no coupling in or out is
/// left alone). For observability pass `(Aᵀ, Cᵀ)`.
pub fn balance(a: &DMatrix<f64>, b: &DMatrix<f64>) -> DVector<f64> {
    const MAX_SWEEPS: usize = 100;
    let n = a.nrows();
    let mut d = DVector::from_element(n, 1.0);
    for _ in 0..MAX_SWEEPS {
        let mut changed = false;
        for i in 0..n {
            let mut column = 0.0;
            let mut row = 0.0;
            for j in (0..n).filter(|&j| j != i) {
                column += (a[(j, i)] * d[i] / d[j]).abs();
                row += (a[(i, j)] * d[j] / d[i]).abs();
            }
            row += b.row(i).iter().map(|v| (v / d[i]).abs()).sum::<f64>();
            if !(column > 0.0 && row > 0.0 && column.is_finite() && row.is_finite()) {
                continue;
            }
            let (mut c, mut r, mut f) = (column, row, 1.0);
            while c < r / 2.0 {
                (c, r, f) = (c * 2.0, r / 2.0, f * 2.0);
            }
            while c >= r * 2.0 {
                (c, r, f) = (c / 2.0, r * 2.0, f / 2.0);
            }
            if c + r < 0.95 * (column + row) {
                d[i] *= f;
                changed = true;
            }
        }
        if !changed {
            break;
        }
    }
    d
}

/// `(D⁻¹ A D, D⁻¹ B)` for the diagonal `d`.
pub fn scaled(
    a: &DMatrix<f64>,
    b: &DMatrix<f64>,
    d: &DVector<f64>,
) -> (DMatrix<f64>, DMatrix<f64>) {
    let a = DMatrix::from_fn(a.nrows(), a.ncols(), |i, j| a[(i, j)] * d[j] / d[i]);
    let b = DMatrix::from_fn(b.nrows(), b.ncols(), |i, j| b[(i, j)] / d[i]);
    (a, b)
}

/// A rank decided by singular values against a tolerance.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RankReport {
    /// Dimension of the subspace.
    pub rank: usize,
    /// Size of the whole space.
    pub n: usize,
    /// Tolerance relative to `max(‖A‖₂, ‖B‖₂)`.
    pub relative_tolerance: f64,
    /// The absolute tolerance singular values were compared with.
    pub absolute_tolerance: f64,
    /// Singular values of each staircase step, largest first; those above the tolerance were
    /// kept.
    pub step_singular_values: Vec<Vec<f64>>,
    /// Smallest singular value kept over all steps.
    pub smallest_kept: f64,
    /// Largest singular value dropped over all steps (0 if none was).
    pub largest_dropped: f64,
}

/// Dimension of the Krylov subspace `span[B, AB, A²B, …]` by the orthogonal staircase (see
/// the module doc). A direction is kept when its singular value exceeds
/// `relative_tolerance · max(‖A‖₂, ‖B‖₂)`.
pub fn staircase_rank(a: &DMatrix<f64>, b: &DMatrix<f64>, relative_tolerance: f64) -> RankReport {
    let n = a.nrows();
    let norm_a = a.clone().singular_values().max();
    let norm_b = b.clone().singular_values().max();
    let tolerance = relative_tolerance * norm_a.max(norm_b);
    let mut basis = DMatrix::<f64>::zeros(n, 0);
    let mut block = b.clone();
    let mut steps = Vec::new();
    let mut smallest_kept = f64::INFINITY;
    let mut largest_dropped = 0.0f64;
    while basis.ncols() < n {
        // Remove what the basis spans, twice (classical Gram–Schmidt loses orthogonality
        // once; the second pass restores it to rounding).
        for _ in 0..2 {
            if basis.ncols() > 0 {
                let projection = &basis * (basis.transpose() * &block);
                block -= projection;
            }
        }
        if block.ncols() == 0 {
            break;
        }
        let svd = block.clone().svd(true, false);
        let Some(u) = svd.u else { break };
        let mut order: Vec<usize> = (0..svd.singular_values.len()).collect();
        order.sort_by(|&i, &j| svd.singular_values[j].total_cmp(&svd.singular_values[i]));
        let values: Vec<f64> = order.iter().map(|&i| svd.singular_values[i]).collect();
        let keep: Vec<usize> = order
            .iter()
            .copied()
            .filter(|&i| svd.singular_values[i] > tolerance)
            .take(n - basis.ncols())
            .collect();
        for &v in &values {
            if v > tolerance {
                smallest_kept = smallest_kept.min(v);
            } else {
                largest_dropped = largest_dropped.max(v);
            }
        }
        steps.push(values);
        if keep.is_empty() {
            break;
        }
        let new = DMatrix::from_columns(&keep.iter().map(|&i| u.column(i)).collect::<Vec<_>>());
        basis = DMatrix::from_columns(
            &basis
                .column_iter()
                .chain(new.column_iter())
                .collect::<Vec<_>>(),
        );
        block = a * new;
    }
    RankReport {
        rank: basis.ncols(),
        n,
        relative_tolerance,
        absolute_tolerance: tolerance,
        step_singular_values: steps,
        smallest_kept: if smallest_kept.is_finite() {
            smallest_kept
        } else {
            0.0
        },
        largest_dropped,
    }
}

/// The Hautus test at one eigenvalue (or a cluster of nearly equal ones).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ModeRank {
    /// The cluster's mean eigenvalue `[re, im]` (upper half-plane for a conjugate pair).
    pub eigenvalue: [f64; 2],
    /// Eigenvalues in the cluster (a conjugate pair counts its upper member only).
    pub multiplicity: usize,
    /// The smallest `multiplicity + 1` singular values of `[λI − A, B]` (or `[λI − A; C]`),
    /// smallest first.
    pub smallest_singular_values: Vec<f64>,
    /// How many of them are below the tolerance: directions lost at this eigenvalue (twice
    /// as many states for a complex pair).
    pub deficiency: usize,
}

/// The Hautus (PBH) rank of a pair.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct HautusReport {
    /// `n` minus the states lost at every eigenvalue.
    pub rank: usize,
    /// Size of the space.
    pub n: usize,
    /// Tolerance relative to `max(‖A‖₂, ‖B‖₂)`.
    pub relative_tolerance: f64,
    /// The absolute tolerance.
    pub absolute_tolerance: f64,
    /// Eigenvalues within this of each other were tested together, s⁻¹.
    pub cluster_tolerance: f64,
    /// Every eigenvalue cluster with its singular values.
    pub modes: Vec<ModeRank>,
}

/// Eigenvalues grouped when within `cluster_tolerance` of the group's first, upper
/// half-plane only: `(mean, count)`.
fn clusters(eigenvalues: &[(f64, f64)], cluster_tolerance: f64) -> Vec<((f64, f64), usize)> {
    let mut upper: Vec<(f64, f64)> = eigenvalues.iter().copied().filter(|e| e.1 >= 0.0).collect();
    upper.sort_by(|p, q| q.0.total_cmp(&p.0).then(q.1.total_cmp(&p.1)));
    let mut groups: Vec<Vec<(f64, f64)>> = Vec::new();
    for e in upper {
        match groups.iter_mut().find(|g| {
            let f = g[0];
            (f.0 - e.0).hypot(f.1 - e.1) < cluster_tolerance
        }) {
            Some(g) => g.push(e),
            None => groups.push(vec![e]),
        }
    }
    groups
        .into_iter()
        .map(|g| {
            let k = g.len() as f64;
            let mean = (
                g.iter().map(|e| e.0).sum::<f64>() / k,
                g.iter().map(|e| e.1).sum::<f64>() / k,
            );
            // A real eigenvalue stays real.
            let mean = if mean.1.abs() < cluster_tolerance {
                (mean.0, 0.0)
            } else {
                mean
            };
            (mean, g.len())
        })
        .collect()
}

/// Singular values of `[λI − A, B]` for `λ = re + i·im`, ascending. A complex matrix
/// `M = X + iY` has the singular values of the real `[[X, −Y], [Y, X]]`, each twice, so the
/// real SVD (with an iteration cap, unlike nalgebra's complex one) does the work.
fn pbh_singular_values(a: &DMatrix<f64>, b: &DMatrix<f64>, re: f64, im: f64) -> Vec<f64> {
    let (n, m) = (a.nrows(), b.ncols());
    let mut x = DMatrix::<f64>::zeros(n, n + m);
    x.view_mut((0, 0), (n, n)).copy_from(&(-a));
    for i in 0..n {
        x[(i, i)] += re;
    }
    x.view_mut((0, n), (n, m)).copy_from(b);
    let (matrix, stride) = if im == 0.0 {
        (x, 1)
    } else {
        let mut y = DMatrix::<f64>::zeros(n, n + m);
        for i in 0..n {
            y[(i, i)] = im;
        }
        let mut big = DMatrix::<f64>::zeros(2 * n, 2 * (n + m));
        big.view_mut((0, 0), (n, n + m)).copy_from(&x);
        big.view_mut((n, n + m), (n, n + m)).copy_from(&x);
        big.view_mut((0, n + m), (n, n + m)).copy_from(&(-&y));
        big.view_mut((n, 0), (n, n + m)).copy_from(&y);
        (big, 2)
    };
    let values = match matrix.try_svd(false, false, f64::EPSILON, 10_000) {
        Some(svd) => svd.singular_values.iter().copied().collect(),
        None => vec![f64::NAN; n],
    };
    let mut values: Vec<f64> = values;
    values.sort_by(f64::total_cmp);
    values.into_iter().step_by(stride).collect()
}

/// Controllable dimension of `(A, B)` by the Hautus test (see the module doc). Eigenvalues
/// closer than `cluster_tolerance` are tested together at their mean.
pub fn hautus(
    a: &DMatrix<f64>,
    b: &DMatrix<f64>,
    relative_tolerance: f64,
    cluster_tolerance: f64,
) -> HautusReport {
    let n = a.nrows();
    let norm_a = a.clone().singular_values().max();
    let norm_b = b.clone().singular_values().max();
    let tolerance = relative_tolerance * norm_a.max(norm_b);
    let mut lost = 0usize;
    let mut modes = Vec::new();
    for ((re, im), count) in clusters(&eigenvalues(a), cluster_tolerance) {
        let mut sv = pbh_singular_values(a, b, re, im);
        sv.truncate(count + 1);
        let deficiency = sv.iter().filter(|&&s| s <= tolerance).count().min(count);
        lost += deficiency * if im != 0.0 { 2 } else { 1 };
        modes.push(ModeRank {
            eigenvalue: [re, im],
            multiplicity: count,
            smallest_singular_values: sv,
            deficiency,
        });
    }
    HautusReport {
        rank: n.saturating_sub(lost),
        n,
        relative_tolerance,
        absolute_tolerance: tolerance,
        cluster_tolerance,
        modes,
    }
}

/// Exact zero-order-hold discretisation over `dt`: `x⁺ = Φ x + Γ u` with `Φ = e^{A dt}`,
/// `Γ = ∫₀^dt e^{As} ds B`, both read from the exponential of `[[A, B], [0, 0]]·dt`.
pub fn discretize(a: &DMatrix<f64>, b: &DMatrix<f64>, dt: f64) -> (DMatrix<f64>, DMatrix<f64>) {
    let (n, m) = (a.nrows(), b.ncols());
    let mut big = DMatrix::zeros(n + m, n + m);
    big.view_mut((0, 0), (n, n)).copy_from(&(a * dt));
    big.view_mut((0, n), (n, m)).copy_from(&(b * dt));
    let e = big.exp();
    (
        e.view((0, 0), (n, n)).into_owned(),
        e.view((0, n), (n, m)).into_owned(),
    )
}

/// A discretised system stepping a state with a held input.
#[derive(Debug, Clone)]
pub struct DiscreteSystem {
    /// `e^{A dt}`.
    pub phi: DMatrix<f64>,
    /// Input matrix of the held input.
    pub gamma: DMatrix<f64>,
    /// Step, s.
    pub dt: f64,
}

impl DiscreteSystem {
    /// `(A, B)` discretised with step `dt`.
    pub fn new(a: &DMatrix<f64>, b: &DMatrix<f64>, dt: f64) -> Self {
        let (phi, gamma) = discretize(a, b, dt);
        Self { phi, gamma, dt }
    }

    /// One step with input `u` held.
    pub fn step(&self, x: &DVector<f64>, u: &DVector<f64>) -> DVector<f64> {
        &self.phi * x + &self.gamma * u
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn system(a: &[f64], b: &[f64], c: &[f64], n: usize, m: usize, q: usize) -> LinearSystem {
        LinearSystem {
            a: DMatrix::from_row_slice(n, n, a),
            b: DMatrix::from_row_slice(n, m, b),
            c: DMatrix::from_row_slice(q, n, c),
            d: DMatrix::zeros(q, m),
        }
    }

    #[test]
    fn double_integrator_with_force_input_and_position_output_is_controllable_and_observable() {
        let s = system(&[0.0, 1.0, 0.0, 0.0], &[0.0, 1.0], &[1.0, 0.0], 2, 1, 1);
        let c = s.controllability(1e-9);
        assert_eq!(c.rank, 2, "{c:?}");
        assert_eq!(s.observability(1e-9).rank, 2);
        assert_eq!(s.controllability_hautus(1e-9, 1e-6).rank, 2);
        assert_eq!(s.observability_hautus(1e-9, 1e-6).rank, 2);
        // Velocity output only: position is invisible.
        let v = system(&[0.0, 1.0, 0.0, 0.0], &[0.0, 1.0], &[0.0, 1.0], 2, 1, 1);
        assert_eq!(v.observability(1e-9).rank, 1);
        assert_eq!(v.observability_hautus(1e-9, 1e-6).rank, 1);
        assert_eq!(s.eigenvalues(), vec![(0.0, 0.0), (0.0, 0.0)]);
    }

    #[test]
    fn a_decoupled_mode_without_input_is_uncontrollable_and_one_without_output_unobservable() {
        // Mode 1 (−1) driven and seen; mode 2 (−2) neither driven nor seen; mode 3 (−3)
        // driven but not seen.
        let s = system(
            &[-1.0, 0.0, 0.0, 0.0, -2.0, 0.0, 0.0, 0.0, -3.0],
            &[1.0, 0.0, 1.0],
            &[1.0, 0.0, 0.0],
            3,
            1,
            1,
        );
        let c = s.controllability(1e-9);
        assert_eq!(c.rank, 2);
        assert!(c.largest_dropped < 1e-12 && c.smallest_kept > 0.1, "{c:?}");
        assert_eq!(s.observability(1e-9).rank, 1);
        let h = s.controllability_hautus(1e-9, 1e-6);
        assert_eq!(h.rank, 2, "{h:?}");
        // The lost direction is the −2 mode, and only it.
        for mode in &h.modes {
            let expected = usize::from(mode.eigenvalue[0] == -2.0);
            assert_eq!(mode.deficiency, expected, "{mode:?}");
        }
        assert_eq!(s.observability_hautus(1e-9, 1e-6).rank, 1);
    }

    #[test]
    fn two_integrators_with_one_input_cannot_both_be_steered() {
        // PBH: eigenvalue 0 with two independent eigenvectors and a single input.
        let s = system(&[0.0; 4], &[1.0, 1.0], &[1.0, 0.0, 0.0, 1.0], 2, 1, 2);
        assert_eq!(s.controllability(1e-9).rank, 1);
        assert_eq!(s.observability(1e-9).rank, 2);
        assert_eq!(s.controllability_hautus(1e-9, 1e-6).rank, 1);
        // Two inputs steer both.
        let two = LinearSystem {
            b: DMatrix::identity(2, 2),
            d: DMatrix::zeros(2, 2),
            ..s
        };
        assert_eq!(two.controllability_hautus(1e-9, 1e-6).rank, 2);
    }

    #[test]
    fn an_uncontrollable_oscillation_loses_two_states() {
        // Oscillator (±2j) not driven; lag −1 driven.
        let s = system(
            &[0.0, 2.0, 0.0, -2.0, 0.0, 0.0, 0.0, 0.0, -1.0],
            &[0.0, 0.0, 1.0],
            &[1.0, 0.0, 1.0],
            3,
            1,
            1,
        );
        assert_eq!(s.controllability_hautus(1e-9, 1e-6).rank, 1);
        assert_eq!(s.controllability(1e-9).rank, 1);
        assert_eq!(s.observability_hautus(1e-9, 1e-6).rank, 3);
    }

    #[test]
    fn staircase_finds_full_rank_where_the_kalman_matrix_is_numerically_singular() {
        // A chain of 16 lags with poles from 0.2 to 6500 s⁻¹: controllable, but the Kalman
        // matrix's columns are nearly parallel.
        let n = 16;
        let mut a = DMatrix::zeros(n, n);
        for i in 0..n {
            a[(i, i)] = -(2.0f64).powi(i as i32) * 0.2;
            if i + 1 < n {
                a[(i + 1, i)] = 1.0;
            }
        }
        let mut b = DMatrix::zeros(n, 1);
        b[(0, 0)] = 1.0;
        let r = staircase_rank(&a, &b, 1e-10);
        assert_eq!(r.rank, n, "{r:?}");
        let mut kalman = DMatrix::zeros(n, n);
        let mut col = b.clone();
        for k in 0..n {
            kalman.set_column(k, &col.column(0));
            col = &a * col;
        }
        // The same relative tolerance on the Kalman matrix's singular values loses states.
        let sv = kalman.singular_values();
        let kalman_rank = sv.iter().filter(|&&s| s > 1e-10 * sv.max()).count();
        assert!(kalman_rank < n, "Kalman rank {kalman_rank}: {sv}");
    }

    /// A controllable chain of three lags written in badly mixed units: the first state in
    /// km, the second in mm, the third in m, with a fast and a slow pole.
    fn badly_scaled_chain() -> (DMatrix<f64>, DMatrix<f64>) {
        let a = DMatrix::from_row_slice(
            3,
            3,
            &[
                -0.02,
                0.0,
                0.0,
                1e6 * 0.3,
                -0.05,
                0.0,
                0.0,
                1e-3 * 0.3,
                -3.0,
            ],
        );
        let b = DMatrix::from_row_slice(3, 1, &[1e-3, 0.0, 0.0]);
        (a, b)
    }

    #[test]
    fn balancing_keeps_the_eigenvalues_and_evens_out_the_units() {
        let (a, b) = badly_scaled_chain();
        let d = balance(&a, &b);
        let (ab, bb) = scaled(&a, &b, &d);
        // A similarity by powers of two: the eigenvalues are those of A to rounding.
        for (x, y) in eigenvalues(&a).iter().zip(eigenvalues(&ab)) {
            assert!((x.0 - y.0).abs() < 1e-9 * (1.0 + x.0.abs()), "{x:?} {y:?}");
            assert!((x.1 - y.1).abs() < 1e-9);
        }
        assert!(d.iter().all(|v| v.log2().fract() == 0.0), "{d}");
        // The couplings now sit within a factor of a few of each other.
        let couplings = [ab[(1, 0)].abs(), ab[(2, 1)].abs(), bb[(0, 0)].abs()];
        let (lo, hi) = couplings
            .iter()
            .fold((f64::INFINITY, 0.0_f64), |(lo, hi), v| {
                (lo.min(*v), hi.max(*v))
            });
        assert!(hi / lo < 16.0, "{couplings:?}");
    }

    #[test]
    fn both_rank_tests_agree_on_a_balanced_system_in_mixed_units() {
        // Controllable, and uncontrollable once the input's path is cut.
        let (a, b) = badly_scaled_chain();
        let (ab, bb) = scaled(&a, &b, &balance(&a, &b));
        let h = hautus(&ab, &bb, 1e-5, 1e-6);
        let s = staircase_rank(&ab, &bb, 1e-5);
        assert_eq!((h.rank, s.rank), (3, 3), "{h:?} {s:?}");
        let mut cut = a.clone();
        cut[(2, 1)] = 0.0;
        let (ab, bb) = scaled(&cut, &b, &balance(&cut, &b));
        let h = hautus(&ab, &bb, 1e-5, 1e-6);
        let s = staircase_rank(&ab, &bb, 1e-5);
        assert_eq!((h.rank, s.rank), (2, 2), "{h:?} {s:?}");
    }

    #[test]
    fn eigenvalues_of_a_damped_oscillator_come_in_a_sorted_conjugate_pair() {
        // ẍ + 2ζω ẋ + ω² x = 0 with ω = 2, ζ = 0.1.
        let a = DMatrix::from_row_slice(3, 3, &[0.0, 1.0, 0.0, -4.0, -0.4, 0.0, 0.0, 0.0, -5.0]);
        let ev = eigenvalues(&a);
        assert_eq!(ev.len(), 3);
        let im = (4.0f64 - 0.04).sqrt();
        assert!(
            (ev[0].0 + 0.2).abs() < 1e-12 && (ev[0].1 - im).abs() < 1e-12,
            "{ev:?}"
        );
        assert!((ev[1].0 + 0.2).abs() < 1e-12 && (ev[1].1 + im).abs() < 1e-12);
        assert!((ev[2].0 + 5.0).abs() < 1e-12);
    }

    #[test]
    fn zero_order_hold_discretisation_matches_the_closed_form() {
        // ẋ = −a x + u: Φ = e^{−a dt}, Γ = (1 − e^{−a dt}) / a.
        let a = DMatrix::from_element(1, 1, -2.0);
        let b = DMatrix::from_element(1, 1, 1.0);
        let (phi, gamma) = discretize(&a, &b, 0.1);
        assert!((phi[(0, 0)] - (-0.2f64).exp()).abs() < 1e-14);
        assert!((gamma[(0, 0)] - (1.0 - (-0.2f64).exp()) / 2.0).abs() < 1e-14);
        // A pure integrator: Γ = dt.
        let (_, g) = discretize(&DMatrix::zeros(1, 1), &b, 0.25);
        assert!((g[(0, 0)] - 0.25).abs() < 1e-15);
    }
}

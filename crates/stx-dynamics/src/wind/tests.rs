use super::*;

fn at_altitude(altitude_m: f64) -> Vector3<f64> {
    Vector3::new(120.0, -40.0, -altitude_m)
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() < 1e-12
}

fn gusts(seed: u64, components: usize) -> Turbulence {
    Turbulence::new(TurbulenceParams {
        sigma_horizontal_mps: 1.5,
        sigma_vertical_mps: 0.8,
        length_scale_horizontal_m: 200.0,
        length_scale_vertical_m: 50.0,
        reference_airspeed_mps: 5.0,
        seed,
        components,
    })
    .unwrap()
}

#[test]
fn turbulence_reproduces_bit_for_bit_for_a_seed_and_differs_between_seeds() {
    let times = [0.0, 0.125, 3.7, 1_000.0, -2.0];
    let a = gusts(42, 64);
    let b = gusts(42, 64);
    let c = gusts(43, 64);
    for t in times {
        let (va, vb, vc) = (a.gust_ned_mps(t), b.gust_ned_mps(t), c.gust_ned_mps(t));
        for i in 0..3 {
            assert_eq!(va[i].to_bits(), vb[i].to_bits());
            assert_ne!(va[i], vc[i]);
        }
        // Evaluating in another order, or again, gives the same value: no hidden state.
        assert_eq!(a.gust_ned_mps(t), va);
    }
}

#[test]
fn the_remembered_gust_is_the_one_asked_for() {
    let remembering = gusts(42, 64);
    // Times a step apart, repeated as RK4 repeats them, and returning to earlier ones.
    let times = [0.0, 0.025, 0.025, 0.05, 0.05, 0.025, 0.0, 1e-300, 0.0];
    for t in times {
        let fresh = gusts(42, 64).gust_ned_mps(t);
        let answer = remembering.gust_ned_mps(t);
        for i in 0..3 {
            assert_eq!(answer[i].to_bits(), fresh[i].to_bits(), "t = {t}");
        }
    }
    // From several threads at once, whoever holds the memory.
    let fresh = gusts(42, 64);
    let expected: Vec<_> = (0..7).map(|i| fresh.gust_ned_mps(i as f64 * 0.3)).collect();
    std::thread::scope(|scope| {
        for k in 0..4 {
            let (remembering, expected) = (&remembering, &expected);
            scope.spawn(move || {
                for j in 0..200 {
                    let i = (j + k) % 7;
                    assert_eq!(remembering.gust_ned_mps(i as f64 * 0.3), expected[i]);
                }
            });
        }
    });
}

/// Samples one axis of the gusts every `dt` seconds.
fn series(turbulence: &Turbulence, axis: usize, dt: f64, samples: usize) -> Vec<f64> {
    let terms = &turbulence.axes[axis];
    (0..samples)
        .map(|i| {
            let t = i as f64 * dt;
            terms
                .iter()
                .map(|s| s.amplitude_mps * (s.angular_frequency_rad_per_s * t + s.phase_rad).cos())
                .sum()
        })
        .collect()
}

/// Sample autocovariance at a lag of `lag` samples, about the sample mean.
fn autocovariance(x: &[f64], lag: usize) -> f64 {
    let mean = x.iter().sum::<f64>() / x.len() as f64;
    let n = x.len() - lag;
    (0..n)
        .map(|i| (x[i] - mean) * (x[i + lag] - mean))
        .sum::<f64>()
        / n as f64
}

/// Dryden's normalised autocorrelation at a separation of `xi` length scales.
fn dryden_correlation(transverse: bool, xi: f64) -> f64 {
    if transverse {
        (1.0 - 0.5 * xi) * (-xi).exp()
    } else {
        (-xi).exp()
    }
}

const AXES: [(usize, f64, f64, bool); 3] = [
    (0, 1.5, 200.0, false),
    (1, 1.5, 200.0, true),
    (2, 0.8, 50.0, true),
];
const LAGS_IN_LENGTH_SCALES: [f64; 3] = [0.5, 1.0, 2.0];
const SAMPLES_PER_CROSSING: usize = 20;
/// Record length, in crossings of the axis' length scale at the reference airspeed.
const CROSSINGS: usize = 4_000;

/// Variance and normalised autocorrelation at [`LAGS_IN_LENGTH_SCALES`] of one axis.
fn statistics(turbulence: &Turbulence, axis: usize, length_m: f64) -> (f64, [f64; 3]) {
    let dt = length_m / 5.0 / SAMPLES_PER_CROSSING as f64;
    let x = series(turbulence, axis, dt, SAMPLES_PER_CROSSING * CROSSINGS);
    let variance = autocovariance(&x, 0);
    let rho = LAGS_IN_LENGTH_SCALES
        .map(|xi| autocovariance(&x, (xi * SAMPLES_PER_CROSSING as f64) as usize) / variance);
    (variance, rho)
}

#[test]
fn turbulence_has_the_dryden_variance_and_autocorrelation_over_seeds() {
    // Twelve realisations with the default 64 sinusoids, 4000 length-scale crossings each.
    // - Variance: the construction gives exactly σ² over an infinite record; the slowest terms
    //   leave < 1 % over this one (measured), so each seed must be within the 15 % asked for.
    // - Autocorrelation: one realisation's differs from Dryden's by the spread of cos(Ωξ)
    //   within the top frequency bands and by the finite record; measured over 12 seeds its
    //   standard deviation is ≈ 0.03, so the 12-seed mean has ≈ 0.008, and the top band's cut
    //   biases it by ≲ 1/N ≈ 0.016. ±0.04 therefore holds with margin, while the wrong Dryden
    //   form would miss by 0.135 … 0.18 (the two forms differ by that at ξ = L and ξ = 2L).
    let seeds = 1..=12_u64;
    let count = seeds.clone().count() as f64;
    let mut mean_rho = [[0.0; 3]; 3];
    for seed in seeds {
        let turbulence = gusts(seed, DEFAULT_TURBULENCE_COMPONENTS);
        for (axis, sigma, length_m, _) in AXES {
            let (variance, rho) = statistics(&turbulence, axis, length_m);
            let ratio = variance / (sigma * sigma);
            assert!(
                (ratio - 1.0).abs() < 0.15,
                "seed {seed} axis {axis}: variance ratio {ratio}"
            );
            for (mean, r) in mean_rho[axis].iter_mut().zip(rho) {
                *mean += r / count;
            }
        }
    }
    let mut worst: f64 = 0.0;
    for (axis, _, _, transverse) in AXES {
        for (xi, rho) in LAGS_IN_LENGTH_SCALES.into_iter().zip(mean_rho[axis]) {
            let expected = dryden_correlation(transverse, xi);
            assert!(
                (rho - expected).abs() < 0.04,
                "axis {axis} ξ/L {xi}: mean ρ {rho} vs Dryden {expected}"
            );
            worst = worst.max((rho - expected).abs());
        }
    }
    eprintln!("Dryden autocorrelation, 12-seed mean, N = 64: worst deviation {worst:.4}");
}

#[test]
fn one_realisation_with_many_sinusoids_follows_the_dryden_shape() {
    // With 256 sinusoids one realisation's autocorrelation deviates by ≈ 0.01 (standard
    // deviation measured over 12 seeds, largest of 108 checks 0.033): ±0.05 allows that and
    // still rejects the wrong form.
    let turbulence = gusts(2024, 256);
    let mut worst: f64 = 0.0;
    for (axis, sigma, length_m, transverse) in AXES {
        let (variance, rho) = statistics(&turbulence, axis, length_m);
        assert!((variance / (sigma * sigma) - 1.0).abs() < 0.15);
        for (xi, rho) in LAGS_IN_LENGTH_SCALES.into_iter().zip(rho) {
            let expected = dryden_correlation(transverse, xi);
            assert!(
                (rho - expected).abs() < 0.05,
                "axis {axis} ξ/L {xi}: {rho} vs {expected}"
            );
            worst = worst.max((rho - expected).abs());
        }
    }
    eprintln!("Dryden autocorrelation, one realisation, N = 256: worst deviation {worst:.4}");
}

#[test]
fn turbulence_frequencies_are_bounded_so_gusts_stay_smooth() {
    // The top band is cut at the 1 − 1/(4N) quantile: the time derivative of a gust is bounded
    // by σ·√(2N)·ω_max, with ω_max of order N·V/L; check it numerically for the worst seed of a few.
    for seed in 0..20 {
        let turbulence = gusts(seed, 64);
        for axis in &turbulence.axes {
            let max_omega = axis
                .iter()
                .map(|s| s.angular_frequency_rad_per_s)
                .fold(0.0, f64::max);
            // Longitudinal: tan(π/2·(1 − 1/256))·V/L ≈ 163·V/L; transverse a little above.
            assert!(max_omega < 300.0 * 5.0 / 50.0, "seed {seed}: {max_omega}");
            assert!(axis.iter().all(|s| s.angular_frequency_rad_per_s >= 0.0));
        }
    }
}

#[test]
fn turbulence_parameters_are_validated() {
    let good = gusts(0, 8).params().clone();
    let cases: [(&str, TurbulenceParams); 5] = [
        (
            "sigma_horizontal_mps",
            TurbulenceParams {
                sigma_horizontal_mps: -0.1,
                ..good.clone()
            },
        ),
        (
            "length_scale_vertical_m",
            TurbulenceParams {
                length_scale_vertical_m: 0.0,
                ..good.clone()
            },
        ),
        (
            "reference_airspeed_mps",
            TurbulenceParams {
                reference_airspeed_mps: f64::NAN,
                ..good.clone()
            },
        ),
        (
            "components",
            TurbulenceParams {
                components: 0,
                ..good.clone()
            },
        ),
        (
            "components",
            TurbulenceParams {
                components: MAX_TURBULENCE_COMPONENTS + 1,
                ..good.clone()
            },
        ),
    ];
    for (name, params) in cases {
        match Turbulence::new(params).unwrap_err() {
            WindError::InvalidTurbulence { parameter, .. } => assert_eq!(parameter, name),
            other => panic!("unexpected {other:?}"),
        }
    }
    // Zero intensity is allowed and gives no gusts.
    let still = Turbulence::new(TurbulenceParams {
        sigma_horizontal_mps: 0.0,
        sigma_vertical_mps: 0.0,
        ..good
    })
    .unwrap();
    assert_eq!(still.gust_ned_mps(12.0), Vector3::zeros());
}

#[test]
fn config_parses_each_kind_and_builds_the_field_it_describes() {
    let calm: WindConfig = toml::from_str(r#"kind = "calm""#).unwrap();
    assert_eq!(calm.mean, MeanWindConfig::Calm {});
    assert_eq!(
        calm.build().unwrap().wind_ned_mps(0.0, &at_altitude(5.0)),
        Vector3::zeros()
    );

    let constant: WindConfig = toml::from_str(
        r#"
        kind = "constant"
        speed_mps = 4
        from_deg = 90.0
        "#,
    )
    .unwrap();
    let v = constant
        .build()
        .unwrap()
        .wind_ned_mps(0.0, &at_altitude(5.0));
    assert!(close(v.x, 0.0) && close(v.y, -4.0), "{v}");

    let with_gusts: WindConfig = toml::from_str(
        r#"
        kind = "profile"
        rows = [[0, 2.0, 270], [1000, 6.0, 270]]

        [turbulence]
        sigma_horizontal_mps = 1.5
        sigma_vertical_mps = 0.8
        length_scale_horizontal_m = 200
        length_scale_vertical_m = 50
        reference_airspeed_mps = 5
        seed = 42
        "#,
    )
    .unwrap();
    let params = with_gusts.turbulence.clone().unwrap();
    assert_eq!(params.components, DEFAULT_TURBULENCE_COMPONENTS);
    assert_eq!(params.seed, 42);
    let wind = with_gusts.build().unwrap();
    let gust = gusts(42, 64).gust_ned_mps(7.5);
    let v = wind.wind_ned_mps(7.5, &at_altitude(500.0));
    assert!(
        close(v.x, gust.x) && close(v.y, 4.0 + gust.y) && close(v.z, gust.z),
        "{v}"
    );
}

#[test]
fn config_refuses_unknown_keys_and_invalid_values() {
    for text in [
        r#"kind = "breeze""#,
        "speed_mps = 3",
        "kind = \"calm\"\nspeed_mps = 3",
        "kind = \"constant\"\nspeed_mps = 3\nfrom_deg = 0\nfrom = 10",
        "kind = \"calm\"\n[turbulence]\nsigma_horizontal_mps = 1\nsigma_vertical_mps = 1\nlength_scale_horizontal_m = 1\nlength_scale_vertical_m = 1\nreference_airspeed_mps = 1\nseed = 1\nsigma = 2",
        "kind = \"calm\"\nturbulance = 1",
    ] {
        assert!(
            toml::from_str::<WindConfig>(text).is_err(),
            "accepted: {text}"
        );
    }
    let bad_profile: WindConfig =
        toml::from_str("kind = \"profile\"\nrows = [[0, 1, 0], [-5, 1, 0]]").unwrap();
    assert!(matches!(
        bad_profile.build().err(),
        Some(WindError::ProfileAltitudeNotIncreasing { row: 1, .. })
    ));
    let bad_constant: WindConfig =
        toml::from_str("kind = \"constant\"\nspeed_mps = -3\nfrom_deg = 0").unwrap();
    assert!(matches!(
        bad_constant.build().err(),
        Some(WindError::InvalidConstantWind { .. })
    ));
}

//! The air the stack falls through: temperature, pressure, density and speed of sound over
//! altitude.
//!
//! Why it exists: the stack is released at 35–40 km, where the air is about 1/100 as dense as at
//! the ground, so every aerodynamic force in the model scales with a density that changes by two
//! orders of magnitude during one flight. The model asks an [`Atmosphere`] for the air at its
//! current altitude at every derivative evaluation.
//!
//! How the parts fit:
//! - [`Atmosphere`] is what the model depends on. It never fails and never panics, because the
//!   ODE solver may probe a state slightly outside the standard's range (below ground at the end
//!   of a flight) and must get a usable, continuous answer there.
//! - [`StandardAtmosphere`] is the US Standard Atmosphere 1976 (NOAA-S/T 76-1562) below 86 km;
//!   [`us76`] is the same table as a checked function that refuses altitudes outside it.
//! - [`Vacuum`] and [`UniformAir`] are test doubles: no air at all (so a model can be checked
//!   against free fall) and the same air everywhere (so a test can fix the density).
//!
//! Model notes (decisions, not oversights):
//! - Below 86 km the standard defines seven layers in geopotential altitude `H`, each with a
//!   linear molecular-scale temperature `T_M(H)`; pressure follows from hydrostatic balance and
//!   density from the ideal gas law with the sea-level molar mass `M0`.
//! - Between 80 and 86 km the standard's kinetic temperature is `T = T_M · M/M0`, with `M/M0`
//!   falling from 1 to 0.999579. We ignore that ratio and report `T = T_M`. Pressure, density
//!   and speed of sound are unaffected (the standard computes them from `T_M/M0`, which equals
//!   `T/M`); only the reported temperature is high, by at most 0.042 %, at 86 km.
//! - Outside −5 km … 86 km, [`StandardAtmosphere`] holds the temperature at the value of the
//!   nearest end and continues pressure hydrostatically at that constant temperature (an
//!   isothermal layer), using the geometric distance past the end. That keeps the ideal gas law
//!   and hydrostatic balance true, keeps every quantity continuous at the ends, and cannot reach a
//!   zero or negative temperature however far it is pushed (continuing the top layer's lapse rate
//!   would reach 0 K near 180 km). A not-a-number altitude gives a not-a-number air state, so the
//!   integrator's finiteness check reports it instead of the model silently using made-up air.

use thiserror::Error;

/// Universal gas constant as the 1976 standard defines it, J/(mol·K). (The standard's value,
/// not the current CODATA one, so the tables are reproduced.)
pub const GAS_CONSTANT_J_PER_MOL_K: f64 = 8.31432;
/// Mean molar mass of sea-level air, kg/mol.
pub const SEA_LEVEL_MOLAR_MASS_KG_PER_MOL: f64 = 28.9644e-3;
/// Standard gravity, which also defines the geopotential metre, m/s².
pub const STANDARD_GRAVITY_MPS2: f64 = 9.80665;
/// Ratio of specific heats of air, dimensionless.
pub const HEAT_CAPACITY_RATIO: f64 = 1.4;
/// Effective Earth radius the standard uses to convert geometric to geopotential altitude, m.
pub const EARTH_RADIUS_M: f64 = 6_356_766.0;
/// Lowest geometric altitude the standard tabulates, m above mean sea level.
pub const US76_MIN_ALTITUDE_M: f64 = -5_000.0;
/// Highest geometric altitude of the standard's lower (hydrostatic, well-mixed) part, m above
/// mean sea level.
pub const US76_MAX_ALTITUDE_M: f64 = 86_000.0;

/// The state of still air at one point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AirState {
    /// Kinetic temperature, K.
    pub temperature_k: f64,
    /// Static pressure, Pa.
    pub pressure_pa: f64,
    /// Density, kg/m³.
    pub density_kg_per_m3: f64,
    /// Speed of sound, m/s.
    pub speed_of_sound_mps: f64,
}

impl AirState {
    /// Air of the standard atmosphere at mean sea level (288.15 K, 101 325 Pa, 1.225 kg/m³).
    pub fn sea_level() -> Self {
        standard_air(0.0)
    }

    fn not_a_number() -> Self {
        Self {
            temperature_k: f64::NAN,
            pressure_pa: f64::NAN,
            density_kg_per_m3: f64::NAN,
            speed_of_sound_mps: f64::NAN,
        }
    }
}

/// A model of the air's state over altitude.
///
/// Implementations must not panic for any input, including altitudes far outside their range
/// and non-finite ones, because they are called from inside the integrator's trial steps.
pub trait Atmosphere: Send + Sync {
    /// The air at `altitude_m`, geometric altitude above mean sea level in metres.
    fn air_at(&self, altitude_m: f64) -> AirState;
}

impl<A: Atmosphere + ?Sized> Atmosphere for &A {
    fn air_at(&self, altitude_m: f64) -> AirState {
        (**self).air_at(altitude_m)
    }
}

impl<A: Atmosphere + ?Sized> Atmosphere for Box<A> {
    fn air_at(&self, altitude_m: f64) -> AirState {
        (**self).air_at(altitude_m)
    }
}

/// Why the checked standard atmosphere refused a request.
#[derive(Clone, Copy, Debug, Error, PartialEq)]
pub enum AtmosphereError {
    /// The altitude lies outside the range the 1976 standard's lower atmosphere defines (or is
    /// not a number).
    #[error(
        "altitude {altitude_m} m is outside the US Standard Atmosphere 1976 range \
         [{min_m} m, {max_m} m]"
    )]
    AltitudeOutOfRange {
        /// The altitude asked for, m above mean sea level.
        altitude_m: f64,
        /// Lowest altitude accepted, m above mean sea level.
        min_m: f64,
        /// Highest altitude accepted, m above mean sea level.
        max_m: f64,
    },
}

/// The US Standard Atmosphere 1976 below 86 km, extended beyond its ends as the module
/// documentation describes so that it never fails.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct StandardAtmosphere;

impl Atmosphere for StandardAtmosphere {
    fn air_at(&self, altitude_m: f64) -> AirState {
        if altitude_m.is_nan() {
            return AirState::not_a_number();
        }
        if altitude_m < US76_MIN_ALTITUDE_M {
            isothermal_extension(US76_MIN_ALTITUDE_M, altitude_m)
        } else if altitude_m > US76_MAX_ALTITUDE_M {
            isothermal_extension(US76_MAX_ALTITUDE_M, altitude_m)
        } else {
            standard_air(altitude_m)
        }
    }
}

/// The US Standard Atmosphere 1976 at `altitude_m` (geometric, m above mean sea level), or an
/// error if the altitude is outside [−5 000 m, 86 000 m] or not a number.
pub fn us76(altitude_m: f64) -> Result<AirState, AtmosphereError> {
    if (US76_MIN_ALTITUDE_M..=US76_MAX_ALTITUDE_M).contains(&altitude_m) {
        Ok(standard_air(altitude_m))
    } else {
        Err(AtmosphereError::AltitudeOutOfRange {
            altitude_m,
            min_m: US76_MIN_ALTITUDE_M,
            max_m: US76_MAX_ALTITUDE_M,
        })
    }
}

/// No air: zero pressure and density, so aerodynamic forces vanish and a model can be checked
/// against free fall. Temperature and speed of sound are those of sea level so that anything
/// dividing by them (Mach number) stays finite.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Vacuum;

impl Atmosphere for Vacuum {
    fn air_at(&self, _altitude_m: f64) -> AirState {
        AirState {
            pressure_pa: 0.0,
            density_kg_per_m3: 0.0,
            ..AirState::sea_level()
        }
    }
}

/// The same air at every altitude.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UniformAir(pub AirState);

impl Atmosphere for UniformAir {
    fn air_at(&self, _altitude_m: f64) -> AirState {
        self.0
    }
}

/// One layer of the standard: from its base up to the next layer's base the molecular-scale
/// temperature is linear in geopotential altitude.
struct Layer {
    /// Geopotential altitude of the layer's base, m′ (geopotential metres).
    base_geopotential_m: f64,
    /// Molecular-scale temperature at the base, K.
    base_temperature_k: f64,
    /// Temperature gradient, K per geopotential metre.
    lapse_k_per_m: f64,
    /// Pressure at the base, Pa. These are the standard's tabulated values, which follow from
    /// 101 325 Pa at sea level and the layers below; a test checks that they agree with
    /// integrating the layers upward, so a mistyped digit cannot hide here.
    base_pressure_pa: f64,
}

const LAYERS: [Layer; 7] = [
    Layer {
        base_geopotential_m: 0.0,
        base_temperature_k: 288.15,
        lapse_k_per_m: -6.5e-3,
        base_pressure_pa: 101_325.0,
    },
    Layer {
        base_geopotential_m: 11_000.0,
        base_temperature_k: 216.65,
        lapse_k_per_m: 0.0,
        base_pressure_pa: 22_632.06,
    },
    Layer {
        base_geopotential_m: 20_000.0,
        base_temperature_k: 216.65,
        lapse_k_per_m: 1.0e-3,
        base_pressure_pa: 5_474.889,
    },
    Layer {
        base_geopotential_m: 32_000.0,
        base_temperature_k: 228.65,
        lapse_k_per_m: 2.8e-3,
        base_pressure_pa: 868.0187,
    },
    Layer {
        base_geopotential_m: 47_000.0,
        base_temperature_k: 270.65,
        lapse_k_per_m: 0.0,
        base_pressure_pa: 110.9063,
    },
    Layer {
        base_geopotential_m: 51_000.0,
        base_temperature_k: 270.65,
        lapse_k_per_m: -2.8e-3,
        base_pressure_pa: 66.938_87,
    },
    Layer {
        base_geopotential_m: 71_000.0,
        base_temperature_k: 214.65,
        lapse_k_per_m: -2.0e-3,
        base_pressure_pa: 3.956_420,
    },
];

/// `g0·M0/R*`, the hydrostatic constant, K per geopotential metre.
const HYDROSTATIC_K_PER_M: f64 =
    STANDARD_GRAVITY_MPS2 * SEA_LEVEL_MOLAR_MASS_KG_PER_MOL / GAS_CONSTANT_J_PER_MOL_K;

fn geopotential_m(altitude_m: f64) -> f64 {
    EARTH_RADIUS_M * altitude_m / (EARTH_RADIUS_M + altitude_m)
}

/// Temperature and pressure at a geopotential altitude, using the layer whose base lies below
/// it (the lowest layer also covers negative altitudes, as the standard does down to −5 km).
fn temperature_pressure(geopotential_m: f64) -> (f64, f64) {
    let layer = LAYERS
        .iter()
        .rev()
        .find(|layer| geopotential_m >= layer.base_geopotential_m)
        .unwrap_or(&LAYERS[0]);
    let height_in_layer_m = geopotential_m - layer.base_geopotential_m;
    if layer.lapse_k_per_m == 0.0 {
        let pressure_pa = layer.base_pressure_pa
            * (-HYDROSTATIC_K_PER_M * height_in_layer_m / layer.base_temperature_k).exp();
        (layer.base_temperature_k, pressure_pa)
    } else {
        let temperature_k = layer.base_temperature_k + layer.lapse_k_per_m * height_in_layer_m;
        let pressure_pa = layer.base_pressure_pa
            * (layer.base_temperature_k / temperature_k)
                .powf(HYDROSTATIC_K_PER_M / layer.lapse_k_per_m);
        (temperature_k, pressure_pa)
    }
}

fn air_from(temperature_k: f64, pressure_pa: f64) -> AirState {
    AirState {
        temperature_k,
        pressure_pa,
        density_kg_per_m3: pressure_pa * SEA_LEVEL_MOLAR_MASS_KG_PER_MOL
            / (GAS_CONSTANT_J_PER_MOL_K * temperature_k),
        speed_of_sound_mps: (HEAT_CAPACITY_RATIO * GAS_CONSTANT_J_PER_MOL_K * temperature_k
            / SEA_LEVEL_MOLAR_MASS_KG_PER_MOL)
            .sqrt(),
    }
}

/// The standard inside its range; callers guarantee the range.
fn standard_air(altitude_m: f64) -> AirState {
    let (temperature_k, pressure_pa) = temperature_pressure(geopotential_m(altitude_m));
    air_from(temperature_k, pressure_pa)
}

/// The air past an end of the table: temperature held at the end's value, pressure continued
/// hydrostatically at that temperature over the geometric distance past the end.
fn isothermal_extension(end_altitude_m: f64, altitude_m: f64) -> AirState {
    let end = standard_air(end_altitude_m);
    let pressure_pa = end.pressure_pa
        * (-HYDROSTATIC_K_PER_M * (altitude_m - end_altitude_m) / end.temperature_k).exp();
    air_from(end.temperature_k, pressure_pa)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Rows of the US Standard Atmosphere 1976 (NOAA-S/T 76-1562, NOAA/NASA/USAF, Washington
    /// D.C., 1976), Part 4, metric tables: geometric altitude Z (m), kinetic temperature (K),
    /// pressure (Pa), density (kg/m³), speed of sound (m/s). Rows at 32 162, 47 350, 51 412 and
    /// 71 802 m are the standard's rows at the geopotential layer bases 32, 47, 51 and 71 km′,
    /// with the geometric altitude the standard gives for them (rounded to the metre, which moves
    /// pressure by < 0.01 %). Typed in from the published table; not computed here.
    const PUBLISHED: [(f64, f64, f64, f64, f64); 17] = [
        (-5_000.0, 320.676, 1.77762e5, 1.93113, 358.986),
        (0.0, 288.150, 1.01325e5, 1.22500, 340.294),
        (1_000.0, 281.651, 8.98763e4, 1.11166, 336.435),
        (5_000.0, 255.676, 5.4048e4, 7.3643e-1, 320.55),
        (11_000.0, 216.774, 2.26999e4, 3.64801e-1, 295.154),
        (15_000.0, 216.650, 1.21118e4, 1.94755e-1, 295.069),
        (20_000.0, 216.650, 5.52929e3, 8.89097e-2, 295.069),
        (25_000.0, 221.552, 2.54921e3, 4.00837e-2, 298.389),
        (32_162.0, 228.650, 8.68014e2, 1.32249e-2, 303.131),
        (40_000.0, 250.350, 2.8714e2, 3.9957e-3, 317.19),
        (47_350.0, 270.650, 1.10906e2, 1.42752e-3, 329.799),
        (50_000.0, 270.650, 7.9779e1, 1.0269e-3, 329.80),
        (51_412.0, 270.650, 6.69384e1, 8.61600e-4, 329.799),
        (60_000.0, 247.021, 2.1958e1, 3.0968e-4, 315.07),
        (71_802.0, 214.650, 3.95639, 6.42105e-5, 293.704),
        (80_000.0, 198.639, 1.0524, 1.8458e-5, 282.54),
        (86_000.0, 186.87, 3.7338e-1, 6.958e-6, 274.10),
    ];

    fn relative_error(computed: f64, published: f64) -> f64 {
        (computed - published).abs() / published.abs()
    }

    #[test]
    fn us76_matches_the_published_table_within_a_tenth_of_a_percent() {
        let mut worst = [0.0_f64; 4];
        for &(altitude_m, t, p, rho, a) in &PUBLISHED {
            let air = us76(altitude_m).unwrap();
            let errors = [
                relative_error(air.temperature_k, t),
                relative_error(air.pressure_pa, p),
                relative_error(air.density_kg_per_m3, rho),
                relative_error(air.speed_of_sound_mps, a),
            ];
            for (name, error) in ["T", "p", "rho", "a"].iter().zip(errors) {
                assert!(
                    error < 1e-3,
                    "{name} at {altitude_m} m: relative error {error:.2e} ({air:?})"
                );
            }
            eprintln!(
                "{altitude_m:>8} m: relative deviation T {:.1e}, p {:.1e}, rho {:.1e}, a {:.1e}",
                errors[0], errors[1], errors[2], errors[3]
            );
            for (w, e) in worst.iter_mut().zip(errors) {
                *w = w.max(e);
            }
        }
        eprintln!(
            "worst relative deviation from the 1976 table: T {:.1e}, p {:.1e}, rho {:.1e}, a {:.1e}",
            worst[0], worst[1], worst[2], worst[3]
        );
    }

    #[test]
    fn layer_base_pressures_agree_with_integrating_the_layers_upward() {
        // Each tabulated base pressure must equal the pressure the layer below gives at its
        // top, so a mistyped constant shows up as a discontinuity.
        for pair in LAYERS.windows(2) {
            let (below, above) = (&pair[0], &pair[1]);
            let h = above.base_geopotential_m - below.base_geopotential_m;
            let top_pressure_pa = if below.lapse_k_per_m == 0.0 {
                below.base_pressure_pa * (-HYDROSTATIC_K_PER_M * h / below.base_temperature_k).exp()
            } else {
                let t_top = below.base_temperature_k + below.lapse_k_per_m * h;
                assert!((t_top - above.base_temperature_k).abs() < 1e-9);
                below.base_pressure_pa
                    * (below.base_temperature_k / t_top)
                        .powf(HYDROSTATIC_K_PER_M / below.lapse_k_per_m)
            };
            assert!(
                relative_error(top_pressure_pa, above.base_pressure_pa) < 2e-6,
                "base at {} m′: tabulated {} Pa, integrated {} Pa",
                above.base_geopotential_m,
                above.base_pressure_pa,
                top_pressure_pa
            );
        }
    }

    #[test]
    fn us76_refuses_altitudes_outside_its_range_and_names_them() {
        for altitude_m in [-5_000.1, 86_000.1, f64::NAN, f64::INFINITY] {
            let error = us76(altitude_m).unwrap_err();
            let AtmosphereError::AltitudeOutOfRange {
                altitude_m: reported,
                min_m,
                max_m,
            } = error;
            assert!(reported.to_bits() == altitude_m.to_bits());
            assert_eq!((min_m, max_m), (-5_000.0, 86_000.0));
            let message = error.to_string();
            assert!(
                message.contains("-5000") && message.contains("86000"),
                "{message}"
            );
        }
        assert!(us76(-5_000.0).is_ok() && us76(86_000.0).is_ok());
    }

    #[test]
    fn standard_atmosphere_is_continuous_and_decreasing_through_every_layer_boundary() {
        let boundaries_m = [
            0.0, 11_019.1, 20_063.1, 32_161.9, 47_350.1, 51_412.5, 71_802.0,
        ];
        for z in boundaries_m {
            let below = StandardAtmosphere.air_at(z - 1e-3);
            let above = StandardAtmosphere.air_at(z + 1e-3);
            assert!(relative_error(below.temperature_k, above.temperature_k) < 1e-6);
            assert!(above.pressure_pa < below.pressure_pa);
            assert!(relative_error(below.pressure_pa, above.pressure_pa) < 1e-6);
        }
    }

    #[test]
    fn outside_the_range_temperature_is_held_and_pressure_continues_hydrostatically() {
        let atmosphere = StandardAtmosphere;
        for (end_m, outside_m) in [(-5_000.0, -5_500.0), (86_000.0, 90_000.0)] {
            let end = atmosphere.air_at(end_m);
            let out = atmosphere.air_at(outside_m);
            assert_eq!(out.temperature_k, end.temperature_k);
            assert_eq!(out.speed_of_sound_mps, end.speed_of_sound_mps);
            // Hydrostatic balance at constant temperature: p = p_end·exp(−Δz/H_scale).
            let scale_height_m = end.temperature_k / HYDROSTATIC_K_PER_M;
            let expected = end.pressure_pa * (-(outside_m - end_m) / scale_height_m).exp();
            assert!(relative_error(out.pressure_pa, expected) < 1e-12);
            // Ideal gas law still holds.
            let rho = out.pressure_pa * SEA_LEVEL_MOLAR_MASS_KG_PER_MOL
                / (GAS_CONSTANT_J_PER_MOL_K * out.temperature_k);
            assert!(relative_error(out.density_kg_per_m3, rho) < 1e-12);
        }
        // Just past the ends the values join the table continuously.
        let inside = atmosphere.air_at(-5_000.0);
        let outside = atmosphere.air_at(-5_000.0 - 1e-6);
        assert!(relative_error(outside.density_kg_per_m3, inside.density_kg_per_m3) < 1e-9);
        // Below ground, where the integrator may probe, air is denser than at the ground.
        assert!(atmosphere.air_at(-10.0).density_kg_per_m3 > 1.225);
    }

    #[test]
    fn standard_atmosphere_never_panics_and_stays_physical_for_wild_altitudes() {
        for altitude_m in [
            -1e12,
            -6.4e6,
            -1e5,
            1e5,
            1e6,
            1e9,
            f64::MAX,
            f64::MIN,
            f64::INFINITY,
            f64::NEG_INFINITY,
        ] {
            let air = StandardAtmosphere.air_at(altitude_m);
            assert!(air.temperature_k > 180.0 && air.temperature_k < 330.0);
            assert!(air.pressure_pa >= 0.0 && air.density_kg_per_m3 >= 0.0);
        }
        let nan = StandardAtmosphere.air_at(f64::NAN);
        assert!(nan.density_kg_per_m3.is_nan() && nan.temperature_k.is_nan());
    }

    #[test]
    fn vacuum_has_no_air_and_uniform_air_is_the_same_everywhere() {
        for altitude_m in [-100.0, 0.0, 35_000.0] {
            let v = Vacuum.air_at(altitude_m);
            assert_eq!((v.pressure_pa, v.density_kg_per_m3), (0.0, 0.0));
            assert!(relative_error(v.speed_of_sound_mps, 340.294) < 1e-5);
            assert_eq!(v.temperature_k, 288.15);
        }
        let fixed = AirState {
            temperature_k: 250.0,
            pressure_pa: 5.0e4,
            density_kg_per_m3: 0.7,
            speed_of_sound_mps: 317.0,
        };
        let uniform = UniformAir(fixed);
        assert_eq!(uniform.air_at(-3.0), fixed);
        assert_eq!(uniform.air_at(40_000.0), fixed);
        let boxed: Box<dyn Atmosphere> = Box::new(uniform);
        assert_eq!(boxed.air_at(1.0), fixed);
    }
}

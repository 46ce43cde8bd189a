//! The vehicle file's rules: every field checked in the file's order, the first broken rule
//! named with its field, and the validated file turned into a [`Vehicle`].

use stx_types::validate::{Invalid, check};

use super::{Vehicle, VehicleConfig, VehicleError};

/// Field names of the capsule's and the transponder's rules, in [`PendantConfig`]'s order.
const PENDANT_FIELDS: [[&str; 6]; 2] = [
    [
        "capsule.mass_kg",
        "capsule.width_m",
        "capsule.length_m",
        "capsule.height_m",
        "capsule.area_m2",
        "capsule.cd",
    ],
    [
        "transponder.mass_kg",
        "transponder.width_m",
        "transponder.length_m",
        "transponder.height_m",
        "transponder.area_m2",
        "transponder.cd",
    ],
];

/// Every rule's verdict, in the file's order: the first broken one is the error.
struct Rules(Vec<Result<(), Invalid>>);

impl Rules {
    fn check(&mut self, field: &'static str, value: f64, rule: &'static str, ok: bool) {
        self.0.push(check(field, value, ok, rule));
    }
    fn positive(&mut self, field: &'static str, value: f64) {
        self.check(field, value, "must be a finite number > 0", value > 0.0);
    }
    fn non_negative(&mut self, field: &'static str, value: f64) {
        self.check(field, value, "must be a finite number ≥ 0", value >= 0.0);
    }
    fn finite(&mut self, field: &'static str, value: f64) {
        self.check(field, value, "must be a finite number", true);
    }
    fn first_broken(self) -> Result<(), VehicleError> {
        Ok(self.0.into_iter().collect::<Result<(), Invalid>>()?)
    }
}

crate::invalid_into!(VehicleError);

impl VehicleConfig {
    /// Parses a vehicle file (it is not validated yet).
    pub fn from_toml_str(text: &str) -> Result<Self, VehicleError> {
        Ok(toml::from_str(text)?)
    }

    /// Checks every rule and builds the vehicle; the error names the first field that breaks one.
    pub fn validate(self) -> Result<Vehicle, VehicleError> {
        let mut rules = Rules(Vec::new());
        rules.positive("gravity_mps2", self.gravity_mps2);
        let c = &self.canopy;
        rules.positive("canopy.mass_kg", c.mass_kg);
        rules.positive("canopy.span_m", c.span_m);
        rules.positive("canopy.chord_m", c.chord_m);
        rules.positive("canopy.thickness_m", c.thickness_m);
        rules.check(
            "canopy.thickness_m",
            c.thickness_m,
            "must be less than canopy.chord_m",
            c.thickness_m < c.chord_m,
        );
        rules.non_negative("canopy.arc_height_m", c.arc_height_m);
        rules.check(
            "canopy.arc_height_m",
            c.arc_height_m,
            "must be less than half of canopy.span_m",
            c.arc_height_m < 0.5 * c.span_m,
        );
        rules.positive("canopy.area_m2", c.area_m2);
        rules.positive("canopy.main_line_length_m", c.main_line_length_m);
        rules.positive("canopy.beam_length_m", c.beam_length_m);
        let a = &c.aero;
        rules.non_negative("canopy.aero.cd0", a.cd0);
        rules.non_negative("canopy.aero.cd_alpha2", a.cd_alpha2);
        rules.finite("canopy.aero.cy_beta", a.cy_beta);
        rules.finite("canopy.aero.cl0", a.cl0);
        rules.finite("canopy.aero.cl_alpha", a.cl_alpha);
        rules.non_negative("canopy.aero.clp", a.clp);
        rules.non_negative("canopy.aero.cmq", a.cmq);
        rules.non_negative("canopy.aero.cnr", a.cnr);
        rules.finite("canopy.aero.cn_beta", a.cn_beta);
        let [alpha_low, alpha_high] = a.alpha_range_deg;
        rules.check(
            "canopy.aero.alpha_range_deg",
            alpha_low,
            "the lower end must lie in [-90, 90) degrees",
            (-90.0..90.0).contains(&alpha_low),
        );
        rules.check(
            "canopy.aero.alpha_range_deg",
            alpha_high,
            "the upper end must lie in (lower end, 90] degrees",
            alpha_high > alpha_low && alpha_high <= 90.0,
        );
        let b = &c.brakes;
        rules.finite("canopy.brakes.cl_ds", b.cl_ds);
        rules.non_negative("canopy.brakes.cd_ds", b.cd_ds);
        rules.finite("canopy.brakes.cl_da", b.cl_da);
        rules.finite("canopy.brakes.cn_da", b.cn_da);
        let d = &self.drone;
        rules.positive("drone.mass_kg", d.mass_kg);
        rules.positive("drone.length_m", d.length_m);
        rules.positive("drone.width_m", d.width_m);
        rules.positive("drone.height_m", d.height_m);
        rules.non_negative("drone.area_m2", d.area_m2);
        rules.non_negative("drone.cd", d.cd);
        rules.non_negative("drone.clp", d.clp);
        rules.non_negative("drone.cmq", d.cmq);
        rules.non_negative("drone.cnr", d.cnr);
        for (fields, p) in [
            (PENDANT_FIELDS[0], &self.capsule),
            (PENDANT_FIELDS[1], &self.transponder),
        ] {
            let [mass, width, length, height, area, cd] = fields;
            rules.positive(mass, p.mass_kg);
            rules.positive(width, p.width_m);
            rules.positive(length, p.length_m);
            rules.positive(height, p.height_m);
            rules.non_negative(area, p.area_m2);
            rules.non_negative(cd, p.cd);
        }
        let g = &self.geometry;
        let vectors: [(&'static str, [f64; 3]); 9] = [
            (
                "geometry.canopy_pressure_centre_m",
                g.canopy_pressure_centre_m,
            ),
            ("geometry.right_line_on_canopy_m", g.right_line_on_canopy_m),
            ("geometry.left_line_on_canopy_m", g.left_line_on_canopy_m),
            ("geometry.right_line_m", g.right_line_m),
            ("geometry.left_line_m", g.left_line_m),
            (
                "geometry.drone_pressure_centre_m",
                g.drone_pressure_centre_m,
            ),
            ("geometry.right_line_on_drone_m", g.right_line_on_drone_m),
            ("geometry.left_line_on_drone_m", g.left_line_on_drone_m),
            (
                "geometry.capsule_line_on_drone_m",
                g.capsule_line_on_drone_m,
            ),
        ];
        for (field, v) in vectors {
            for component in v {
                rules.finite(field, component);
            }
        }
        for (field, v) in [
            ("geometry.right_line_m", g.right_line_m),
            ("geometry.left_line_m", g.left_line_m),
        ] {
            rules.check(
                field,
                v[2],
                "the line must hang down (z component > 0 in the line frame)",
                v[2] > 0.0,
            );
        }
        rules.positive("geometry.capsule_line_length_m", g.capsule_line_length_m);
        rules.positive(
            "geometry.transponder_line_length_m",
            g.transponder_line_length_m,
        );
        let s = &self.servos;
        rules.positive("servos.main_line_rate_per_s", s.main_line_rate_per_s);
        rules.positive("servos.brake_right_rate_per_s", s.brake_right_rate_per_s);
        rules.positive("servos.brake_left_rate_per_s", s.brake_left_rate_per_s);
        rules.positive("servos.main_line_travel_m", s.main_line_travel_m);
        rules.check(
            "servos.main_line_travel_m",
            s.main_line_travel_m,
            "must be less than half of canopy.beam_length_m (the lines would cross)",
            s.main_line_travel_m < 0.5 * c.beam_length_m,
        );
        rules.first_broken()?;
        Ok(Vehicle::derive(self))
    }
}

//! The control laws of seed §5.1–5.2: PD laws on measured quantities that command the
//! differential main line (horizontal control, `HU`) and the symmetric brakes (vertical
//! control, `VU`).
//!
//! Every angle error is wrapped to (−π, π] before it is used, so a heading of 179° against a
//! target of −179° is a 2° error, not 358°; a turn of more than 150° keeps the side it
//! started on until less than 90° is left ([`TurnLatch`], `turn_latch.rs`), so a reversal
//! is flown one way. Outputs saturate to the servos' range. Signs: a
//! positive main-line command turns right; more brake steepens the glide.

use serde::{Deserialize, Serialize};
use stx_types::rotation::wrap_pi;

mod turn_latch;
pub use turn_latch::{LATCH_RAD, RELEASE_RAD, RETARGET_RAD, TurnLatch};

/// Gains and limits of the control laws, with units. The station can read and write each one
/// as a named parameter.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ControlGains {
    /// HK1: main line per radian of heading, course or bearing error, m/rad.
    pub hk1_m_per_rad: f64,
    /// HK2: main line per rad/s of heading rate (damping), m·s/rad.
    pub hk2_m_s_per_rad: f64,
    /// HK3: main line per metre of cross-track error in the localizer's following phase, m/m.
    pub hk3_m_per_m: f64,
    /// CD: convergence distance of the localizer and of the glide slope, m. The approach
    /// phase runs while the error exceeds CD/5.
    pub convergence_distance_m: f64,
    /// VK1: brake per unit of glide-slope error (sink over ground speed), 1.
    pub vk1: f64,
    /// VK2: brake per metre of altitude error in the following phase, 1/m.
    pub vk2_per_m: f64,
    /// Symmetric brake held when the vertical law is centred (room to correct both ways), 0…1.
    pub brake_trim: f64,
    /// Largest main-line command, m.
    pub main_line_limit_m: f64,
}

impl Default for ControlGains {
    /// Gains tuned by `stx tune` on the 14-DOF model's linearised closed loop and checked on
    /// the nonlinear model, controller by controller (heading, course, localizer, vertical;
    /// heading and course share HK1/HK2, so the course's values are the ones kept), the same
    /// as `config/gains.toml`. They replaced hand-set gains (HK1 0.012, HK2 0.012, HK3 0.0004,
    /// VK1 3, VK2 0.05) after the Monte Carlo of 100 spiral landings improved with them; the
    /// figures and the seed's appendix A.13 vectors are compared in
    /// `crates/stx-analysis/ANALYSIS_NOTES.md`. HK1/HK2 are three quarters of what the tuner
    /// gave: the dispersed stacks with the estimator land closer and fail less with them (the
    /// Monte Carlo gate in the same notes).
    fn default() -> Self {
        Self {
            hk1_m_per_rad: 0.00661,
            hk2_m_s_per_rad: 0.0126,
            hk3_m_per_m: 0.000226,
            convergence_distance_m: 40.0,
            vk1: 1.67,
            vk2_per_m: 0.466,
            brake_trim: 0.4,
            main_line_limit_m: 0.015,
        }
    }
}

/// Why a gains file was refused.
#[derive(Debug, thiserror::Error)]
pub enum GainsError {
    /// Not TOML, an unknown field, or a value of the wrong type.
    #[error("gains are not valid TOML for ControlGains: {0}")]
    Parse(#[from] toml::de::Error),
    /// A value breaks a rule; names the field.
    #[error("gain `{field}` = {value} breaks the rule: {rule}")]
    Invalid {
        /// Field name as written in the file.
        field: &'static str,
        /// The value found.
        value: f64,
        /// What it must be.
        rule: &'static str,
    },
}

impl ControlGains {
    /// The gains for a canopy that turns `turn_scale` times as fast per main-line command as
    /// the one they were tuned for: the main-line gains divided by it, so the heading loop
    /// keeps the gain it was tuned with (a canopy drawn with 30 % more turn authority
    /// otherwise flies the same laws with 30 % more loop gain, and overshoots).
    pub fn for_turn_scale(&self, turn_scale: f64) -> Self {
        let k = if turn_scale.is_finite() && turn_scale > 0.0 {
            turn_scale
        } else {
            1.0
        };
        Self {
            hk1_m_per_rad: self.hk1_m_per_rad / k,
            hk2_m_s_per_rad: self.hk2_m_s_per_rad / k,
            hk3_m_per_m: self.hk3_m_per_m / k,
            ..*self
        }
    }

    /// Reads gains from TOML text (the format `stx tune` writes: the fields of this struct at
    /// the top level; missing fields take their defaults) and validates them.
    pub fn from_toml_str(text: &str) -> Result<Self, GainsError> {
        let gains: ControlGains = toml::from_str(text)?;
        gains.validate()
    }

    /// The gains as TOML, one field per line.
    pub fn to_toml_string(&self) -> String {
        // Serialising a struct of plain floats cannot fail; fall back to Debug just in case.
        toml::to_string(self).unwrap_or_else(|_| format!("# {self:?}\n"))
    }

    /// The gains if every one is finite and in its range, else the first that is not.
    pub fn validate(self) -> Result<Self, GainsError> {
        let checks: [(&'static str, f64, bool, &'static str); 8] = [
            (
                "hk1_m_per_rad",
                self.hk1_m_per_rad,
                self.hk1_m_per_rad >= 0.0,
                "finite and ≥ 0",
            ),
            (
                "hk2_m_s_per_rad",
                self.hk2_m_s_per_rad,
                self.hk2_m_s_per_rad >= 0.0,
                "finite and ≥ 0",
            ),
            (
                "hk3_m_per_m",
                self.hk3_m_per_m,
                self.hk3_m_per_m >= 0.0,
                "finite and ≥ 0",
            ),
            (
                "convergence_distance_m",
                self.convergence_distance_m,
                self.convergence_distance_m > 0.0,
                "finite and > 0",
            ),
            ("vk1", self.vk1, self.vk1 >= 0.0, "finite and ≥ 0"),
            (
                "vk2_per_m",
                self.vk2_per_m,
                self.vk2_per_m >= 0.0,
                "finite and ≥ 0",
            ),
            (
                "brake_trim",
                self.brake_trim,
                (0.0..1.0).contains(&self.brake_trim),
                "in [0, 1): room to brake more",
            ),
            (
                "main_line_limit_m",
                self.main_line_limit_m,
                self.main_line_limit_m > 0.0 && self.main_line_limit_m < 0.5,
                "in (0, 0.5) m",
            ),
        ];
        for (field, value, ok, rule) in checks {
            if !(ok && value.is_finite()) {
                return Err(GainsError::Invalid { field, value, rule });
            }
        }
        Ok(self)
    }
}

/// Which phase of a two-phase law is active (seed §5.1.3, §5.2).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LawPhase {
    /// Converging on the line at an intercept angle.
    Approach,
    /// On the line, holding it.
    Following,
}

/// The main-line command of a PD law on the angle from `wanted_rad` to `actual_rad`
/// (resolved by `latch`), saturated.
fn pd(
    gains: &ControlGains,
    latch: &mut TurnLatch,
    actual_rad: f64,
    wanted_rad: f64,
    rate_rad_s: f64,
    extra_m: f64,
) -> f64 {
    let command = -gains.hk1_m_per_rad * latch.resolve(actual_rad, wanted_rad)
        - gains.hk2_m_s_per_rad * rate_rad_s
        - extra_m;
    command.clamp(-gains.main_line_limit_m, gains.main_line_limit_m)
}

/// Heading hold (eqs. 5.1–5.3): `HU = −HK1·(ψ − H0) − HK2·ψ̇`.
pub fn heading(
    gains: &ControlGains,
    latch: &mut TurnLatch,
    heading_rad: f64,
    heading_rate_rad_s: f64,
    target_rad: f64,
) -> f64 {
    pd(
        gains,
        latch,
        heading_rad,
        target_rad,
        heading_rate_rad_s,
        0.0,
    )
}

/// Course hold (eqs. 5.4–5.6): the course over the ground replaces the heading, so the
/// vehicle crabs into a crosswind; the heading rate stands in for the course rate.
pub fn course(
    gains: &ControlGains,
    latch: &mut TurnLatch,
    course_rad: f64,
    heading_rate_rad_s: f64,
    target_rad: f64,
) -> f64 {
    pd(
        gains,
        latch,
        course_rad,
        target_rad,
        heading_rate_rad_s,
        0.0,
    )
}

/// A localizer: the line through `point_ne_m` (north, east) with course `course_rad`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Localizer {
    /// A point of the line, north and east, m.
    pub point_ne_m: [f64; 2],
    /// The line's course, rad.
    pub course_rad: f64,
}

impl Localizer {
    /// The line from one point through another (the seed's two-point localizer).
    pub fn through(from_ne_m: [f64; 2], to_ne_m: [f64; 2]) -> Self {
        Self {
            point_ne_m: from_ne_m,
            course_rad: (to_ne_m[1] - from_ne_m[1]).atan2(to_ne_m[0] - from_ne_m[0]),
        }
    }

    /// Cross-track error (eq. 5.7), m: positive right of the line.
    pub fn cross_track_m(&self, position_ne_m: [f64; 2]) -> f64 {
        let (dn, de) = (
            position_ne_m[0] - self.point_ne_m[0],
            position_ne_m[1] - self.point_ne_m[1],
        );
        de * self.course_rad.cos() - dn * self.course_rad.sin()
    }

    /// Distance along the line from its point, m: positive ahead.
    pub fn along_track_m(&self, position_ne_m: [f64; 2]) -> f64 {
        let (dn, de) = (
            position_ne_m[0] - self.point_ne_m[0],
            position_ne_m[1] - self.point_ne_m[1],
        );
        dn * self.course_rad.cos() + de * self.course_rad.sin()
    }
}

/// Output of the localizer law.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LocalizerOutput {
    /// Main-line command, m.
    pub main_line_m: f64,
    /// Phase of the law.
    pub phase: LawPhase,
    /// Cross-track error, m.
    pub cross_track_m: f64,
    /// Course the law asked for, rad.
    pub desired_course_rad: f64,
}

/// One-point localizer and course (eqs. 5.7–5.11). Approach while |CT| > CD/5: fly the line's
/// course offset by the intercept angle `α = atan(min(|CT|, CD)/CD)·sign(CT)` (at most 45°).
/// Following: hold the line's course with an added cross-track term.
pub fn localizer(
    gains: &ControlGains,
    latch: &mut TurnLatch,
    line: &Localizer,
    position_ne_m: [f64; 2],
    course_rad: f64,
    heading_rate_rad_s: f64,
) -> LocalizerOutput {
    let cd = gains.convergence_distance_m;
    let ct = line.cross_track_m(position_ne_m);
    if ct.abs() > cd / 5.0 {
        let intercept = (ct.abs().min(cd) / cd).atan() * ct.signum();
        let desired = line.course_rad - intercept;
        LocalizerOutput {
            main_line_m: pd(gains, latch, course_rad, desired, heading_rate_rad_s, 0.0),
            phase: LawPhase::Approach,
            cross_track_m: ct,
            desired_course_rad: wrap_pi(desired),
        }
    } else {
        LocalizerOutput {
            main_line_m: pd(
                gains,
                latch,
                course_rad,
                line.course_rad,
                heading_rate_rad_s,
                gains.hk3_m_per_m * ct,
            ),
            phase: LawPhase::Following,
            cross_track_m: ct,
            desired_course_rad: wrap_pi(line.course_rad),
        }
    }
}

/// A glide path: descending along a localizer to `aim_height_m` above the ground at the
/// localizer's point, at `slope` (metres down per metre over the ground).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct GlidePath {
    /// The horizontal line flown.
    pub line: Localizer,
    /// Height above ground to be at when over the line's point, m.
    pub aim_height_m: f64,
    /// Glide slope, sink over ground speed (the seed's GS0).
    pub slope: f64,
}

impl GlidePath {
    /// Height above the path, m (positive: too high). The seed's eq. 5.12 measures it
    /// perpendicular to the path; this is the vertical distance, a factor cos γ apart.
    pub fn altitude_error_m(&self, position_ne_m: [f64; 2], height_m: f64) -> f64 {
        let to_go = -self.line.along_track_m(position_ne_m);
        height_m - (self.aim_height_m + to_go * self.slope)
    }
}

/// Output of the vertical law.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VerticalOutput {
    /// Symmetric brake command, 0…1.
    pub brake: f64,
    /// Phase of the law.
    pub phase: LawPhase,
    /// Height above the path, m.
    pub altitude_error_m: f64,
}

/// Vertical glide-slope control (eqs. 5.12–5.17) with the symmetric brakes: flies localizer
/// mode's glide path, and the spiral's final only with `FinalLaw::GlideSlope` (its default
/// final inverts the glide performance instead; see the spiral module). The measured slope
/// is the sink rate over the ground speed along the path; more brake steepens it. Approach
/// while |A| > CD/5: aim for a slope offset by `tan β`, `β = atan(min(|A|, CD)/CD)·sign(A)`.
/// Following: the slope error plus `VK2·A`.
pub fn vertical(
    gains: &ControlGains,
    path: &GlidePath,
    position_ne_m: [f64; 2],
    height_m: f64,
    velocity_ne_mps: [f64; 2],
    sink_rate_mps: f64,
) -> VerticalOutput {
    vertical_about(
        gains,
        path,
        position_ne_m,
        height_m,
        velocity_ne_mps,
        sink_rate_mps,
        gains.brake_trim,
    )
}

/// The vertical law of [`vertical`] centred on the brake `trim` (0…1) instead of the gains'
/// fixed trim: a feed-forward, the brake expected to hold the path's slope, so the feedback
/// only corrects what that expectation got wrong.
pub fn vertical_about(
    gains: &ControlGains,
    path: &GlidePath,
    position_ne_m: [f64; 2],
    height_m: f64,
    velocity_ne_mps: [f64; 2],
    sink_rate_mps: f64,
    trim: f64,
) -> VerticalOutput {
    let cd = gains.convergence_distance_m;
    let a = path.altitude_error_m(position_ne_m, height_m);
    let along = velocity_ne_mps[0] * path.line.course_rad.cos()
        + velocity_ne_mps[1] * path.line.course_rad.sin();
    // Going backwards or hovering over the ground: the slope is as steep as it gets.
    let measured = if along > 0.1 {
        sink_rate_mps / along
    } else {
        10.0
    };
    let (brake, phase) = if a.abs() > cd / 5.0 {
        let beta = (a.abs().min(cd) / cd).atan() * a.signum();
        let desired = path.slope + beta.tan();
        (trim + gains.vk1 * (desired - measured), LawPhase::Approach)
    } else {
        (
            trim + gains.vk1 * (path.slope - measured) + gains.vk2_per_m * a,
            LawPhase::Following,
        )
    };
    VerticalOutput {
        brake: brake.clamp(0.0, 1.0),
        phase,
        altitude_error_m: a,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    fn gains() -> ControlGains {
        ControlGains::default()
    }

    #[test]
    fn gains_round_trip_through_toml_and_defaults_fill_missing_fields() {
        let g = ControlGains {
            hk1_m_per_rad: 0.0123,
            vk2_per_m: 0.07,
            ..ControlGains::default()
        };
        let text = format!("# produced by a test\n{}", g.to_toml_string());
        assert_eq!(ControlGains::from_toml_str(&text).expect("valid"), g);
        let partial = ControlGains::from_toml_str("hk3_m_per_m = 0.001\n").expect("valid");
        assert_eq!(partial.hk3_m_per_m, 0.001);
        assert_eq!(partial.hk1_m_per_rad, ControlGains::default().hk1_m_per_rad);
    }

    #[test]
    fn the_shipped_gains_file_holds_the_defaults() {
        // config/gains.toml is documented as the built-in defaults: keep them one.
        let shipped = ControlGains::from_toml_str(include_str!("../../../../config/gains.toml"))
            .expect("valid");
        assert_eq!(shipped, ControlGains::default());
    }

    #[test]
    fn invalid_gains_name_the_field() {
        let err = ControlGains::from_toml_str("vk1 = -1.0\n").unwrap_err();
        assert!(
            matches!(err, GainsError::Invalid { field: "vk1", .. }),
            "{err}"
        );
        assert!(err.to_string().contains("vk1"));
        let err = ControlGains::from_toml_str("brake_trim = 1.0\n").unwrap_err();
        assert!(err.to_string().contains("brake_trim"), "{err}");
        let err = ControlGains::from_toml_str("main_line_limit_m = nan\n").unwrap_err();
        assert!(err.to_string().contains("main_line_limit_m"), "{err}");
        // Unknown fields are refused rather than ignored (a typo would silently keep a
        // default).
        let err = ControlGains::from_toml_str("hk_1 = 0.1\n").unwrap_err();
        assert!(
            matches!(err, GainsError::Parse(_)) && err.to_string().contains("hk_1"),
            "{err}"
        );
    }

    #[test]
    fn heading_error_turns_the_short_way_round_through_180_degrees() {
        let g = gains();
        // Heading 179°, wanted −179°: 2° to the right, so turn right (positive).
        let u = heading(
            &g,
            &mut TurnLatch::default(),
            179f64.to_radians(),
            0.0,
            (-179f64).to_radians(),
        );
        assert!(u > 0.0, "{u}");
        assert!((u - g.hk1_m_per_rad * 2f64.to_radians()).abs() < 1e-12);
        // And the mirror case turns left.
        assert!(
            heading(
                &g,
                &mut TurnLatch::default(),
                (-179f64).to_radians(),
                0.0,
                179f64.to_radians()
            ) < 0.0
        );
        // A rate towards the target damps the command.
        let damped = heading(
            &g,
            &mut TurnLatch::default(),
            179f64.to_radians(),
            0.1,
            (-179f64).to_radians(),
        );
        assert!(damped < u);
    }

    #[test]
    fn commands_saturate_at_the_main_line_limit() {
        let g = gains();
        assert_eq!(
            heading(&g, &mut TurnLatch::default(), 0.0, -100.0, 0.0),
            g.main_line_limit_m
        );
        assert_eq!(
            course(&g, &mut TurnLatch::default(), 0.0, 100.0, 0.0),
            -g.main_line_limit_m
        );
    }

    #[test]
    fn course_law_uses_the_course_not_the_heading() {
        let g = gains();
        assert_eq!(course(&g, &mut TurnLatch::default(), 0.5, 0.0, 0.5), 0.0);
        assert!(course(&g, &mut TurnLatch::default(), 0.4, 0.0, 0.5) > 0.0);
    }

    #[test]
    fn cross_track_is_positive_right_of_the_line() {
        // Line due east through the origin: a point to the south is right of it.
        let line = Localizer {
            point_ne_m: [0.0, 0.0],
            course_rad: PI / 2.0,
        };
        assert!((line.cross_track_m([-10.0, 5.0]) - 10.0).abs() < 1e-12);
        assert!((line.along_track_m([-10.0, 5.0]) - 5.0).abs() < 1e-12);
        let two_point = Localizer::through([0.0, 0.0], [0.0, 100.0]);
        assert!((two_point.course_rad - PI / 2.0).abs() < 1e-12);
    }

    #[test]
    fn localizer_intercepts_at_up_to_45_degrees_then_follows() {
        let g = gains();
        let cd = g.convergence_distance_m;
        // The seed's Fig. 5.2 geometry: localizer at x = 100, y = 200 with course 90°.
        let line = Localizer {
            point_ne_m: [100.0, 200.0],
            course_rad: PI / 2.0,
        };
        // Flying the line's course from `position`.
        let at = |position| {
            localizer(
                &g,
                &mut TurnLatch::default(),
                &line,
                position,
                PI / 2.0,
                0.0,
            )
        };
        // Far to the left of the line (north of it): intercept course 90° + 45°, to the right.
        let far = at([100.0 + 5.0 * cd, 0.0]);
        assert_eq!(far.phase, LawPhase::Approach);
        assert!((far.desired_course_rad - 135f64.to_radians()).abs() < 1e-9);
        assert!(far.main_line_m > 0.0, "turns right towards the line");
        // Close: following phase, cross-track term pulls back towards the line.
        let near = at([100.0 + 0.1 * cd, 150.0]);
        assert_eq!(near.phase, LawPhase::Following);
        assert!(near.main_line_m > 0.0 && near.cross_track_m < 0.0);
        // On the line, on course: nothing to do.
        let on = at([100.0, 150.0]);
        assert!(on.main_line_m.abs() < 1e-12);
    }

    #[test]
    fn glide_slope_law_brakes_more_when_high_or_shallow() {
        let g = gains();
        let path = GlidePath {
            line: Localizer {
                point_ne_m: [0.0, 0.0],
                course_rad: 0.0,
            },
            aim_height_m: 0.0,
            slope: 0.5,
        };
        // 100 m before the target on a 0.5 slope the path is 50 m up.
        let on = vertical(&g, &path, [-100.0, 0.0], 50.0, [6.0, 0.0], 3.0);
        assert_eq!(on.phase, LawPhase::Following);
        assert!(on.altitude_error_m.abs() < 1e-12);
        assert!((on.brake - g.brake_trim).abs() < 1e-12);
        let high = vertical(&g, &path, [-100.0, 0.0], 60.0, [6.0, 0.0], 3.0);
        assert!(high.brake > on.brake);
        let shallow = vertical(&g, &path, [-100.0, 0.0], 50.0, [7.0, 0.0], 3.0);
        assert!(shallow.brake > on.brake);
        let far_low = vertical(&g, &path, [-100.0, 0.0], 0.0, [6.0, 0.0], 3.0);
        assert_eq!(far_low.phase, LawPhase::Approach);
        assert_eq!(far_low.brake, 0.0, "far below the path: no brake at all");
        // Blown backwards: as steep as it gets, so release the brakes.
        let backwards = vertical(&g, &path, [-100.0, 0.0], 50.0, [-1.0, 0.0], 3.0);
        assert_eq!(backwards.brake, 0.0);
    }
}

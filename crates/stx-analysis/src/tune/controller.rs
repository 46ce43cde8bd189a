//! The controllers `stx tune` knows, and what each one's tuning is made of: the gains it
//! tunes, the seed's values of them, the size and length of its step experiments, and the
//! labels of its plots.

use serde::Serialize;
use stx_gnc::control::ControlGains;

use crate::seed;

/// The controllers `stx tune` knows.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Controller {
    /// Heading hold (seed eqs. 5.1–5.3): tunes HK1, HK2.
    Heading,
    /// Course hold (eqs. 5.4–5.6): tunes HK1, HK2 (shared with heading: one set of gains).
    Course,
    /// Localizer following phase (eq. 5.11): tunes HK3 with HK1, HK2 held.
    Localizer,
    /// Glide slope (eqs. 5.12–5.17): tunes VK1, VK2.
    Vertical,
}

impl Controller {
    /// All of them.
    pub const ALL: [Controller; 4] = [
        Controller::Heading,
        Controller::Course,
        Controller::Localizer,
        Controller::Vertical,
    ];

    /// Lower-case name.
    pub fn name(self) -> &'static str {
        match self {
            Controller::Heading => "heading",
            Controller::Course => "course",
            Controller::Localizer => "localizer",
            Controller::Vertical => "vertical",
        }
    }

    /// The gains it tunes, by their field names in [`ControlGains`].
    pub fn gain_names(self) -> &'static [&'static str] {
        match self {
            Controller::Heading | Controller::Course => &["hk1_m_per_rad", "hk2_m_s_per_rad"],
            Controller::Localizer => &["hk3_m_per_m"],
            Controller::Vertical => &["vk1", "vk2_per_m"],
        }
    }

    /// Current values of the tuned gains.
    pub fn get(self, g: &ControlGains) -> Vec<f64> {
        match self {
            Controller::Heading | Controller::Course => vec![g.hk1_m_per_rad, g.hk2_m_s_per_rad],
            Controller::Localizer => vec![g.hk3_m_per_m],
            Controller::Vertical => vec![g.vk1, g.vk2_per_m],
        }
    }

    /// `g` with the tuned gains replaced by `values`.
    pub fn with(self, g: &ControlGains, values: &[f64]) -> ControlGains {
        let mut out = *g;
        match self {
            Controller::Heading | Controller::Course => {
                out.hk1_m_per_rad = values[0];
                out.hk2_m_s_per_rad = values[1];
            }
            Controller::Localizer => out.hk3_m_per_m = values[0],
            Controller::Vertical => {
                out.vk1 = values[0];
                out.vk2_per_m = values[1];
            }
        }
        out
    }

    /// The seed's appendix A.13 gains read into ours (see [`seed`]).
    pub fn seed_gains(self, g: &ControlGains) -> ControlGains {
        let mut out = *g;
        match self {
            Controller::Heading => {
                out.hk1_m_per_rad = seed::HEADING.k1;
                out.hk2_m_s_per_rad = seed::HEADING.k2;
            }
            Controller::Course => {
                out.hk1_m_per_rad = seed::COURSE.k1;
                out.hk2_m_s_per_rad = seed::COURSE.k2;
            }
            Controller::Localizer => {
                out.hk1_m_per_rad = seed::LOCALIZER.k1;
                out.hk2_m_s_per_rad = seed::LOCALIZER.k2;
                out.hk3_m_per_m = seed::LOCALIZER.k3.unwrap_or(out.hk3_m_per_m);
            }
            Controller::Vertical => {
                out.vk1 = seed::VERTICAL.k1;
                out.vk2_per_m = seed::VERTICAL.k2;
            }
        }
        out
    }

    /// Step size of its experiment, in the response's unit.
    pub fn step(self) -> f64 {
        match self {
            Controller::Heading | Controller::Course => 30f64.to_radians(),
            Controller::Localizer => 6.0,
            Controller::Vertical => 5.0,
        }
    }

    /// Size of its large experiment: a 90° turn (a spiral corner, the law saturated), a
    /// 40 m offset (the convergence distance: the localizer's approach phase, then its
    /// following phase), 10 m above the glide path (its approach phase, the brake saturated).
    pub fn large_step(self) -> f64 {
        match self {
            Controller::Heading | Controller::Course => 90f64.to_radians(),
            Controller::Localizer => 40.0,
            Controller::Vertical => 10.0,
        }
    }

    /// Length of its experiment, s.
    pub fn duration_s(self) -> f64 {
        match self {
            Controller::Heading | Controller::Course => 40.0,
            Controller::Localizer => 60.0,
            Controller::Vertical => 80.0,
        }
    }

    /// What the response is, for plots.
    pub fn response_label(self) -> &'static str {
        match self {
            Controller::Heading => "canopy heading, deg",
            Controller::Course => "course over ground, deg",
            Controller::Localizer => "cross-track error, m",
            Controller::Vertical => "height above the glide path, m",
        }
    }

    /// The actuator it drives, for plots.
    pub fn command_label(self) -> &'static str {
        match self {
            Controller::Vertical => "symmetric brake, 0..1",
            _ => "main line, cm",
        }
    }
}

impl std::str::FromStr for Controller {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Controller::ALL
            .into_iter()
            .find(|c| c.name() == s)
            .ok_or_else(|| {
                format!("unknown controller `{s}`: heading, course, localizer or vertical")
            })
    }
}

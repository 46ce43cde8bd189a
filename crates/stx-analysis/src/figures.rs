//! The figures `stx analyze` and `stx tune` write, as SVG text ([`crate::svg`]): the
//! eigenvalues beside the seed's and the open-loop steps of the nonlinear model against its
//! linearisation ([`analysis_figures`]), and a tuning's step responses ([`tune_figure`]).
//! The binary writes them to files.

use stx_dynamics::state::idx;
use stx_dynamics::vehicle::Vehicle;

use crate::analysis::AnalysisReport;
use crate::linearize::LinearModel;
use crate::svg::{COLORS, Corner, Panel, Series, Style, render};
use crate::tune::{Candidate, Controller, Trial, TuneReport, forced_responses};

/// One figure and the file it goes to.
#[derive(Debug, Clone, PartialEq)]
pub struct Figure {
    /// File name, in the output directory.
    pub file_name: &'static str,
    /// The SVG document.
    pub svg: String,
}

/// The figures of an analysis, and what could not be drawn.
#[derive(Debug, Clone, PartialEq)]
pub struct AnalysisFigures {
    /// `eigenvalues.svg`, `step-main-line.svg`, `step-brake.svg`.
    pub figures: Vec<Figure>,
    /// Panels left empty, and why.
    pub warnings: Vec<String>,
}

/// The analysis' figures. High up, a large step can take the nonlinear stack where its model
/// ends (a dive through the Euler angles' singularity): that panel says so and stays empty,
/// with a warning, instead of the whole analysis failing.
pub fn analysis_figures(
    vehicle: &Vehicle,
    r: &AnalysisReport,
    lin: &LinearModel,
) -> AnalysisFigures {
    let mut figures = Vec::new();
    let mut warnings = Vec::new();
    let ours: Vec<(f64, f64)> = r.eigenvalues.iter().map(|e| (e[0], e[1])).collect();
    let seed: Vec<(f64, f64)> = r.seed.eigenvalues.iter().map(|e| (e[0], e[1])).collect();
    let series = |label: &str| {
        vec![
            Series {
                label: format!("stx ({label})"),
                points: ours.clone(),
                color: COLORS[0],
                style: Style::Circles,
            },
            Series {
                label: "seed §6.2.1".into(),
                points: seed.clone(),
                color: COLORS[1],
                style: Style::Crosses,
            },
        ]
    };
    let panels = [
        Panel {
            title: "all eigenvalues".into(),
            x_label: "real part, 1/s".into(),
            y_label: "imaginary part, rad/s".into(),
            series: series("31 states"),
            x_range: Some((-20.0, 1.0)),
            y_range: Some((-36.0, 36.0)),
            legend: Corner::TopLeft,
            ..Default::default()
        },
        Panel {
            title: "slow modes".into(),
            x_label: "real part, 1/s".into(),
            y_label: "imaginary part, rad/s".into(),
            series: series("zoom"),
            x_range: Some((-6.0, 0.5)),
            y_range: Some((-9.0, 9.0)),
            legend: Corner::TopLeft,
            ..Default::default()
        },
    ];
    let title = format!(
        "Eigenvalues of the linearised model at {:.0} m (trim airspeed {:.2} m/s)",
        r.trim.altitude_m, r.trim.airspeed_mps
    );
    figures.push(Figure {
        file_name: "eigenvalues.svg",
        svg: render(&title, &panels, 2, 520.0, 460.0),
    });

    // Open-loop steps: linear against nonlinear, small and large.
    let deg = 180.0 / std::f64::consts::PI;
    let mut step_panel = |du: [f64; 2], state: usize, scale: f64, label: &str, title: String| {
        // High up, a large step can take the nonlinear stack where its model ends (a dive
        // through the Euler angles' singularity): the panel says so instead of the whole
        // analysis failing.
        let responses = match forced_responses(vehicle, lin, &[], du, 20.0, 0.1) {
            Ok(responses) => responses,
            Err(e) => {
                warnings.push(format!(
                    "{title}: the nonlinear flight failed ({e}); panel left empty"
                ));
                return Panel {
                    title: format!("{title}: nonlinear flight failed"),
                    x_label: "time, s".into(),
                    y_label: label.into(),
                    ..Default::default()
                };
            }
        };
        Panel {
            title,
            x_label: "time, s".into(),
            y_label: label.into(),
            series: vec![
                Series {
                    label: "nonlinear".into(),
                    points: responses
                        .iter()
                        .map(|(t, n, _)| (*t, n[state] * scale))
                        .collect(),
                    color: COLORS[0],
                    style: Style::Line,
                },
                Series {
                    label: "linear".into(),
                    points: responses
                        .iter()
                        .map(|(t, _, l)| (*t, l[state] * scale))
                        .collect(),
                    color: COLORS[1],
                    style: Style::Dashed,
                },
            ],
            // Bottom right for a response that rises, top right for one that falls.
            legend: if responses.last().is_some_and(|(_, n, _)| n[state] > 0.0) {
                Corner::BottomRight
            } else {
                Corner::TopRight
            },
            ..Default::default()
        }
    };
    let psi = idx::CANOPY_EULER + 2;
    let phi = idx::CANOPY_EULER;
    let main_line = [
        step_panel(
            [0.002, 0.0],
            psi,
            deg,
            "Δψ canopy, deg",
            "main line +2 mm: heading".into(),
        ),
        step_panel(
            [0.002, 0.0],
            phi,
            deg,
            "Δφ canopy, deg",
            "main line +2 mm: roll".into(),
        ),
        step_panel(
            [0.015, 0.0],
            psi,
            deg,
            "Δψ canopy, deg",
            "main line +15 mm (full): heading".into(),
        ),
        step_panel(
            [0.015, 0.0],
            phi,
            deg,
            "Δφ canopy, deg",
            "main line +15 mm (full): roll".into(),
        ),
    ];
    figures.push(Figure {
        file_name: "step-main-line.svg",
        svg: render(
            "Open-loop main-line step from the trim: nonlinear model against its linearisation",
            &main_line,
            2,
            520.0,
            340.0,
        ),
    });
    let w = idx::CANOPY_VELOCITY + 2;
    let u = idx::CANOPY_VELOCITY;
    let brake = [
        step_panel(
            [0.0, 0.1],
            u,
            1.0,
            "Δu canopy, m/s",
            "brake 0.1: forward speed".into(),
        ),
        step_panel(
            [0.0, 0.1],
            w,
            1.0,
            "Δw canopy, m/s",
            "brake 0.1: normal speed".into(),
        ),
        step_panel(
            [0.0, 1.0],
            u,
            1.0,
            "Δu canopy, m/s",
            "brake 1.0 (full): forward speed".into(),
        ),
        step_panel(
            [0.0, 1.0],
            w,
            1.0,
            "Δw canopy, m/s",
            "brake 1.0 (full): normal speed".into(),
        ),
    ];
    figures.push(Figure {
        file_name: "step-brake.svg",
        svg: render(
            "Open-loop brake step from the trim: nonlinear model against its linearisation",
            &brake,
            2,
            520.0,
            340.0,
        ),
    });
    AnalysisFigures { figures, warnings }
}

/// The step responses of a tuning: each candidate's small and large step, linear and 14-DOF,
/// and the actuator in the large step.
pub fn tune_figure(r: &TuneReport) -> String {
    let c = r.controller;
    let (scale, command_scale) = match c {
        Controller::Heading | Controller::Course => (180.0 / std::f64::consts::PI, 100.0),
        Controller::Localizer => (1.0, 100.0),
        Controller::Vertical => (1.0, 1.0),
    };
    let pts = |t: &[f64], y: &[f64], s: f64| -> Vec<(f64, f64)> {
        t.iter().zip(y).map(|(t, y)| (*t, y * s)).collect()
    };
    let candidates = [&r.current, &r.tuned, &r.seed];
    let response_panel = |pick: fn(&Candidate) -> &Trial, title: String| {
        let mut series = Vec::new();
        for (k, cand) in candidates.iter().enumerate() {
            let (linear, nonlinear) = &pick(cand).responses;
            if let Some(n) = nonlinear {
                series.push(Series {
                    label: format!("{} 14-DOF", cand.label),
                    points: pts(&n.time_s, &n.output, scale),
                    color: COLORS[k],
                    style: Style::Line,
                });
            }
            series.push(Series {
                label: format!("{} linear", cand.label),
                points: pts(&linear.time_s, &linear.output, scale),
                color: COLORS[k],
                style: Style::Dashed,
            });
        }
        let first = &pick(&r.current).responses.0;
        Panel {
            title,
            x_label: "time, s".into(),
            y_label: c.response_label().into(),
            series,
            h_lines: vec![first.reference * scale],
            legend: if first.reference > first.initial {
                Corner::BottomRight
            } else {
                Corner::TopRight
            },
            ..Default::default()
        }
    };
    let commands = candidates
        .iter()
        .enumerate()
        .filter_map(|(k, cand)| {
            cand.large.responses.1.as_ref().map(|n| Series {
                label: format!("{} 14-DOF", cand.label),
                points: pts(&n.time_s, &n.command, command_scale),
                color: COLORS[k],
                style: Style::Line,
            })
        })
        .collect();
    let unit = |step: f64| match c {
        Controller::Heading | Controller::Course => format!("{:.0}°", step * scale),
        _ => format!("{step:.0} m"),
    };
    let panels = [
        response_panel(
            |c| &c.small,
            format!("small step ({})", unit(r.current.small.step)),
        ),
        response_panel(
            |c| &c.large,
            format!("large step ({})", unit(r.current.large.step)),
        ),
        Panel {
            title: "actuator in the large step (nonlinear runs)".into(),
            x_label: "time, s".into(),
            y_label: c.command_label().into(),
            series: commands,
            ..Default::default()
        },
    ];
    render(
        &format!("stx tune --controller {}: step responses", c.name()),
        &panels,
        1,
        900.0,
        340.0,
    )
}

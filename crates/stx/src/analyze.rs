//! `stx analyze`: trim, linearise, eigenvalues and ranks beside the seed's; writes the report
//! and its plots.

use std::fs;
use std::path::{Path, PathBuf};

use anyhow::{Context, anyhow};
use clap::Args;
use stx_analysis::analysis::{AnalysisReport, analyze};
use stx_analysis::linearize::LinearModel;
use stx_analysis::svg::{COLORS, Corner, Panel, Series, Style, render};
use stx_analysis::tune::forced_responses;
use stx_dynamics::state::idx;
use stx_dynamics::vehicle::Vehicle;

use crate::BadInput;
use crate::sim::load_vehicle;

#[derive(Args)]
pub struct AnalyzeArgs {
    /// Vehicle file (default: the shipped STRAPLEX vehicle).
    #[arg(long)]
    vehicle: Option<PathBuf>,
    /// Altitude of the trim, m above sea level (−5000 … 86000).
    #[arg(long, default_value_t = 100.0)]
    altitude: f64,
    /// Print the report as one JSON object on stdout instead of tables.
    #[arg(long)]
    json: bool,
    /// Where report.json and the plots are written.
    #[arg(long, default_value = "target/analysis")]
    out_dir: PathBuf,
}

pub fn run(args: AnalyzeArgs) -> anyhow::Result<()> {
    let vehicle = load_vehicle(args.vehicle.as_deref())?;
    let (report, lin) = analyze(&vehicle, args.altitude)
        .map_err(|e| BadInput(anyhow!(e).context(format!("trim at {} m", args.altitude))))?;
    fs::create_dir_all(&args.out_dir)
        .with_context(|| format!("creating {}", args.out_dir.display()))?;
    let path = args.out_dir.join("report.json");
    fs::write(&path, serde_json::to_string_pretty(&report)?)
        .with_context(|| format!("writing {}", path.display()))?;
    write_plots(&args.out_dir, &vehicle, &report, &lin)?;
    if args.json {
        println!("{}", serde_json::to_string(&report)?);
        for warning in &report.warnings {
            eprintln!("warning: {warning}");
        }
    } else {
        print_tables(&report);
        println!(
            "\nwrote {0}/report.json, {0}/eigenvalues.svg, {0}/step-main-line.svg, \
             {0}/step-brake.svg",
            args.out_dir.display()
        );
    }
    Ok(())
}

fn print_tables(r: &AnalysisReport) {
    let t = &r.trim;
    println!(
        "Trim at {:.0} m (ρ = {:.4} kg/m³), servos neutral, calm air; residual {:.1e} after {} \
         iterations",
        t.altitude_m, t.density_kg_per_m3, t.residual, t.iterations
    );
    println!("{:<28} {:>12} {:>26}", "", "stx", "seed Table 6.1");
    println!(
        "{:<28} {:>12.2} {:>26}",
        "u_C, m/s", t.u_c_mps, "22 (read km/h: 6.1)"
    );
    println!(
        "{:<28} {:>12.2} {:>26}",
        "w_C, m/s", t.w_c_mps, "11 (read km/h: 3.1)"
    );
    let names = ["θ_C/I", "θ_L/C", "θ_D/L", "θ_CAP/D", "θ_T/CAP"];
    let seed = [-8.1, -5.3, 6.1, -7.1, 5.4];
    for ((n, ours), s) in names.iter().zip(t.pitch_chain_deg).zip(seed) {
        println!("{:<28} {:>12.2} {:>26.1}", format!("{n}, deg"), ours, s);
    }
    println!("{:<28} {:>12.2}", "airspeed, m/s", t.airspeed_mps);
    println!("{:<28} {:>12.2}", "angle of attack, deg", t.alpha_deg);
    println!(
        "{:<28} {:>12.2} {:>26}",
        "horizontal speed, m/s", t.horizontal_speed_mps, "≈5 (18 km/h, flight tests)"
    );
    println!(
        "{:<28} {:>12.2} {:>26}",
        "sink rate, m/s", t.sink_rate_mps, "≈2.8 (10 km/h)"
    );
    println!("{:<28} {:>12.2} {:>26}", "glide ratio", t.glide_ratio, "≈2");
    println!(
        "{:<28} {:>12}",
        "line tensions, N",
        t.tensions_n.map(|v| format!("{v:.1}")).join(" / ")
    );

    println!("\nEigenvalues of A (one per pair), paired with the seed's nearest (§6.2.1)");
    println!(
        "{:>22} {:>18} {:>8} {:>8}  dominant states",
        "stx", "seed", "ζ", "ω rad/s"
    );
    for m in &r.modes {
        let seed = m
            .seed
            .map(|s| format!("{:.2} {:+.2}j", s[0], s[1]))
            .unwrap_or_default();
        let dominant = m
            .dominant_states
            .iter()
            .map(|(n, w)| format!("{n} {:.0}%", 100.0 * w))
            .collect::<Vec<_>>()
            .join(", ");
        let zeta = if m.natural_frequency_rad_s < r.zero_tolerance {
            "-".to_string()
        } else {
            format!("{:.3}", m.damping_ratio)
        };
        println!(
            "{:>22} {:>18} {:>8} {:>8.3}  {dominant}",
            format!("{:.4} {:+.4}j", m.eigenvalue[0], m.eigenvalue[1]),
            seed,
            zeta,
            m.natural_frequency_rad_s
        );
    }
    println!(
        "zero eigenvalues (|λ| < {:.2e} 1/s, {}): {} (seed: {}); largest other real part \
         {:.3} 1/s (seed: {:.2})",
        r.zero_tolerance,
        r.zero_tolerance_basis,
        r.zero_eigenvalues,
        r.seed.zero_eigenvalues,
        r.max_real_part_nonzero,
        r.seed.max_real_part_nonzero
    );
    println!(
        "\n{:<44} {:>6} {:>6}",
        "rank (Hautus test, SVD)", "stx", "seed"
    );
    println!(
        "{:<44} {:>6} {:>6}",
        "controllability, U_L and U_S", r.controllability_rank, r.seed.controllability_rank
    );
    println!(
        "{:<44} {:>6} {:>6}",
        "controllability, U_L alone (staircase)", r.controllability_rank_main_line_only, "-"
    );
    println!(
        "{:<44} {:>6} {:>6}",
        "controllability, U_S alone (staircase)", r.controllability_rank_brake_only, "-"
    );
    println!(
        "{:<44} {:>6} {:>6}",
        "observability, drone x y z u v w φ θ ψ", r.observability_rank, r.seed.observability_rank
    );
    println!(
        "{:<44} {:>6} {:>6}",
        "cross-check: staircase controllability", r.controllability_staircase.rank, ""
    );
    println!(
        "{:<44} {:>6} {:>6}",
        "cross-check: staircase observability", r.observability_staircase.rank, ""
    );
    println!(
        "states balanced to the system's own scales; tolerance {:.0e} × max(‖A‖, ‖B‖) = {:.2e} \
         (observability {:.2e}); smallest singular value of [λI − A, B] per mode:",
        r.rank_relative_tolerance,
        r.controllability.absolute_tolerance,
        r.observability.absolute_tolerance
    );
    for (c, o) in r.controllability.modes.iter().zip(&r.observability.modes) {
        println!(
            "  λ = {:>20}  ×{}  controllability {:>9.2e}{}  observability {:>9.2e}{}",
            format!("{:.4} {:+.4}j", c.eigenvalue[0], c.eigenvalue[1]),
            c.multiplicity,
            c.smallest_singular_values[0],
            if c.deficiency > 0 {
                format!(" (lost {})", c.deficiency)
            } else {
                String::new()
            },
            o.smallest_singular_values[0],
            if o.deficiency > 0 {
                format!(" (lost {})", o.deficiency)
            } else {
                String::new()
            },
        );
    }
    if r.warnings.is_empty() {
        println!("every zero and rank decision is clear of its threshold by a factor 3 or more");
    }
    for warning in &r.warnings {
        println!("warning: {warning}");
    }
}

fn write_plots(
    dir: &Path,
    vehicle: &Vehicle,
    r: &AnalysisReport,
    lin: &LinearModel,
) -> anyhow::Result<()> {
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
    write(
        dir,
        "eigenvalues.svg",
        &render(&title, &panels, 2, 520.0, 460.0),
    )?;

    // Open-loop steps: linear against nonlinear, small and large.
    let deg = 180.0 / std::f64::consts::PI;
    let step_panel = |du: [f64; 2], state: usize, scale: f64, label: &str, title: String| {
        // High up, a large step can take the nonlinear stack where its model ends (a dive
        // through the Euler angles' singularity): the panel says so instead of the whole
        // analysis failing.
        let responses = match forced_responses(vehicle, lin, &[], du, 20.0, 0.1) {
            Ok(responses) => responses,
            Err(e) => {
                eprintln!("warning: {title}: the nonlinear flight failed ({e}); panel left empty");
                return Ok(Panel {
                    title: format!("{title}: nonlinear flight failed"),
                    x_label: "time, s".into(),
                    y_label: label.into(),
                    ..Default::default()
                });
            }
        };
        Ok::<Panel, anyhow::Error>(Panel {
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
        })
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
        )?,
        step_panel(
            [0.002, 0.0],
            phi,
            deg,
            "Δφ canopy, deg",
            "main line +2 mm: roll".into(),
        )?,
        step_panel(
            [0.015, 0.0],
            psi,
            deg,
            "Δψ canopy, deg",
            "main line +15 mm (full): heading".into(),
        )?,
        step_panel(
            [0.015, 0.0],
            phi,
            deg,
            "Δφ canopy, deg",
            "main line +15 mm (full): roll".into(),
        )?,
    ];
    write(
        dir,
        "step-main-line.svg",
        &render(
            "Open-loop main-line step from the trim: nonlinear model against its linearisation",
            &main_line,
            2,
            520.0,
            340.0,
        ),
    )?;
    let w = idx::CANOPY_VELOCITY + 2;
    let u = idx::CANOPY_VELOCITY;
    let brake = [
        step_panel(
            [0.0, 0.1],
            u,
            1.0,
            "Δu canopy, m/s",
            "brake 0.1: forward speed".into(),
        )?,
        step_panel(
            [0.0, 0.1],
            w,
            1.0,
            "Δw canopy, m/s",
            "brake 0.1: normal speed".into(),
        )?,
        step_panel(
            [0.0, 1.0],
            u,
            1.0,
            "Δu canopy, m/s",
            "brake 1.0 (full): forward speed".into(),
        )?,
        step_panel(
            [0.0, 1.0],
            w,
            1.0,
            "Δw canopy, m/s",
            "brake 1.0 (full): normal speed".into(),
        )?,
    ];
    write(
        dir,
        "step-brake.svg",
        &render(
            "Open-loop brake step from the trim: nonlinear model against its linearisation",
            &brake,
            2,
            520.0,
            340.0,
        ),
    )?;
    Ok(())
}

fn write(dir: &Path, name: &str, text: &str) -> anyhow::Result<()> {
    let path = dir.join(name);
    fs::write(&path, text).with_context(|| format!("writing {}", path.display()))
}

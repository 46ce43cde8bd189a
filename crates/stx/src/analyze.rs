//! `stx analyze`: trim, linearise, eigenvalues and ranks beside the seed's; writes the report
//! and its plots.

use std::fs;
use std::path::PathBuf;

use anyhow::{Context, anyhow};
use clap::Args;
use stx_analysis::analysis::{AnalysisReport, analyze};
use stx_analysis::figures::analysis_figures;

use crate::BadInput;
use crate::inputs::load_vehicle;

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
    let figures = analysis_figures(&vehicle, &report, &lin);
    for warning in &figures.warnings {
        eprintln!("warning: {warning}");
    }
    for figure in &figures.figures {
        let path = args.out_dir.join(figure.file_name);
        fs::write(&path, &figure.svg).with_context(|| format!("writing {}", path.display()))?;
    }
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
    // Table 6.1's `u = 22, w = 11` are the canopy's forward and downward speeds over the ground
    // in km/h (A.12 prints them as 6.1 and 3.1 m/s; MODEL_NOTES.md), so they sit beside our
    // horizontal speed and sink rate below, not beside the body-axis u_C and w_C.
    println!("{:<28} {:>12.2}", "u_C (body axis), m/s", t.u_c_mps);
    println!("{:<28} {:>12.2}", "w_C (body axis), m/s", t.w_c_mps);
    let names = ["θ_C/I", "θ_L/C", "θ_D/L", "θ_CAP/D", "θ_T/CAP"];
    let seed = [-8.1, -5.3, 6.1, -7.1, 5.4];
    for ((n, ours), s) in names.iter().zip(t.pitch_chain_deg).zip(seed) {
        println!("{:<28} {:>12.2} {:>26.1}", format!("{n}, deg"), ours, s);
    }
    println!("{:<28} {:>12.2}", "airspeed, m/s", t.airspeed_mps);
    println!("{:<28} {:>12.2}", "angle of attack, deg", t.alpha_deg);
    println!(
        "{:<28} {:>12.2} {:>26}",
        "horizontal speed, m/s", t.horizontal_speed_mps, "6.1 (u = 22 km/h)"
    );
    println!(
        "{:<28} {:>12.2} {:>26}",
        "sink rate, m/s", t.sink_rate_mps, "3.1 (w = 11 km/h)"
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

//! `stx polar FILE`: the glide and turn guidance plans with, for a vehicle file (one `stx
//! identify` or the Lab wrote), as the drone's `PL_*` parameters — what one flight learned,
//! sent to the drone for the next. Written as a parameter file (`NAME VALUE` lines, `#`
//! comments: what MAVProxy's `param load` and QGroundControl's loaders read), or with `--json`
//! as the body of the station's `POST /api/lab/gains/send`, which sends them to the drone.

use std::io::Write;
use std::path::PathBuf;

use anyhow::Context;
use clap::Args;
use stx_gnc::params::polar_params;

#[derive(Args, Debug)]
pub struct PolarArgs {
    /// The vehicle file whose steady glide is trimmed at each of the table's brake settings
    /// (0, 0.2 … 1). The turn terms are the shipped table's: a trim identifies none of them.
    vehicle: PathBuf,
    /// Print `{"gains": {NAME: VALUE, …}, "confirm": false}` for `POST /api/lab/gains/send`
    /// (set `confirm` to true to send) instead of a parameter file.
    #[arg(long)]
    json: bool,
}

pub fn run(args: PolarArgs) -> anyhow::Result<()> {
    let polar = crate::inputs::load_polar("vehicle file", &args.vehicle)?;
    let params = polar_params(&polar);
    let mut out = std::io::stdout().lock();
    if args.json {
        let gains: serde_json::Map<String, serde_json::Value> = params
            .iter()
            .map(|(name, value)| ((*name).to_string(), serde_json::json!(value)))
            .collect();
        let body = serde_json::json!({ "gains": gains, "confirm": false });
        writeln!(out, "{}", serde_json::to_string_pretty(&body)?).context("stdout")?;
        return Ok(());
    }
    writeln!(
        out,
        "# The planning polar of {} (stx polar): airspeed and sink at brakes 0, 0.2 … 1,\n\
         # at {:.4} kg/m³; the turn terms are the shipped table's.",
        args.vehicle.display(),
        polar.reference_density_kg_per_m3
    )
    .context("stdout")?;
    for (name, value) in params {
        // Six decimals: the wire's f32 carries about seven digits.
        writeln!(out, "{name:<16} {value:.6}").context("stdout")?;
    }
    Ok(())
}

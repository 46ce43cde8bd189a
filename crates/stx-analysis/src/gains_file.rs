//! The gains file `stx tune` writes: the tuned gains as TOML (what `ControlGains::from_toml_str`
//! reads back) under a header saying how they were found and how they compare.

use crate::tune::{Candidate, TuneReport};

/// The gains file of `r`: its gains, headed by the controller, the trim, the experiments, the
/// verdict and the costs; `source` names where the other controllers' gains came from.
pub fn gains_file(r: &TuneReport, source: &str) -> String {
    let cost = |c: &Candidate| c.nonlinear_cost.unwrap_or(f64::NAN);
    format!(
        "# Control gains read by guidance (`stx sim --gains`, `stx montecarlo --gains`).\n\
         # They become the built-in defaults (config/gains.toml) only after the Monte Carlo \
         gate of crates/stx-analysis/ANALYSIS_NOTES.md.\n\
         # Written by `stx tune --controller {}` at a {:.0} m trim ({}).\n\
         # {}: nonlinear step cost {:.3} before, {:.3} tuned, {:.3} with the seed's A.13 gains.\n\
         # Gains of the other controllers carried over from {source}.\n{}",
        r.controller.name(),
        r.altitude_m,
        r.experiment,
        r.verdict,
        cost(&r.current),
        cost(&r.tuned),
        cost(&r.seed),
        r.gains_out.to_toml_string()
    )
}

//! The Lab's identification of vehicle parameters from a recording (issue 16 item 3): the
//! station has checked the recording (a plain name of its recordings directory, holding a
//! flight) and the parameter names; this reads its flight log as `stx identify` does, fits
//! with `stx_analysis::identify` from the vehicle as edited, reporting each iteration as
//! progress and cancelling the fit after the current iteration when the job is cancelled or
//! over its cap (the library's cancel flag), and hands the page the estimates.

use std::sync::atomic::{AtomicBool, Ordering};

use stx_analysis::flight_log::window::Window;
use stx_analysis::identify::{IdentifyOptions, IdentifyReport, Param, identify};
use stx_station::lab::{
    IdentifiedParam, IdentifySummary, JobControl, JobInputs, LabResult, VehicleEdits,
};

use crate::recording::{flight_log, vehicle_changes, watcher};

/// Fits `params` to the recording `name`, from the vehicle of `inputs` (edited from the
/// seed's by `edits`).
pub fn run(
    name: &str,
    params: &[String],
    inputs: &JobInputs,
    window: &Window,
    edits: &VehicleEdits,
    control: &dyn JobControl,
) -> Result<LabResult, String> {
    let params = params
        .iter()
        .map(|p| Param::parse(p))
        .collect::<Result<Vec<_>, _>>()
        .map_err(|e| e.to_string())?;
    let log = flight_log(name, inputs, window).map_err(|e| e.to_string())?;
    let options = IdentifyOptions::default();
    let total = options.max_iterations;
    control.progress(0, total);
    let cancel = AtomicBool::new(false);
    let mut go_on = watcher(control);
    let report = identify(
        &[log],
        &params,
        &inputs.vehicle.config,
        &options,
        &cancel,
        &mut |p| {
            if !go_on(p.iteration.min(total), total) {
                cancel.store(true, Ordering::Relaxed);
            }
        },
    )
    .map_err(|e| format!("identifying from {name}: {e}"))?;
    Ok(LabResult::Identify(summary(name, edits, &report)))
}

/// `report` as the Lab shows it.
pub fn summary(name: &str, edits: &VehicleEdits, report: &IdentifyReport) -> IdentifySummary {
    IdentifySummary {
        recording: name.to_string(),
        vehicle_changes: vehicle_changes(edits),
        params: report
            .params
            .iter()
            .map(|p| IdentifiedParam {
                name: p.name.clone(),
                nominal: p.initial,
                fitted: p.estimate,
                std_error: p.std_error,
                interval95_low: p.interval95.map(|i| i[0]),
                interval95_high: p.interval95.map(|i| i[1]),
            })
            .collect(),
        correlation: report.correlation.clone(),
        residual_rms_before: report.residual_rms_before,
        residual_rms_after: report.residual_rms_after,
        iterations: u32::try_from(report.iterations).unwrap_or(u32::MAX),
        stop: serde_json::to_value(report.stop)
            .ok()
            .and_then(|v| v.as_str().map(str::to_string))
            .unwrap_or_else(|| format!("{:?}", report.stop)),
        vehicle_toml: report.vehicle_toml.clone(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use stx_dynamics::vehicle::Vehicle;
    use stx_station::lab::identify::IDENTIFY_PARAMS;

    use crate::recording::tests::{control, inputs, recorded_flight, temp};

    #[test]
    fn the_station_knows_the_library_s_parameters() {
        let library: Vec<&str> = Param::ALL.map(Param::name).to_vec();
        assert_eq!(library, IDENTIFY_PARAMS.to_vec());
    }

    /// A flight of a vehicle whose lift slope is 10 % above the seed's, recorded through the
    /// station's channels: the fit from the seed's finds it within its interval.
    #[test]
    fn a_recorded_flight_s_lift_slope_is_found() {
        let seed = Vehicle::straplex();
        let mut truth = seed.config.clone();
        let nominal = Param::ClAlpha.get(&truth);
        Param::ClAlpha.set(&mut truth, nominal * 1.1);
        let truth = truth.validate().unwrap();
        let (_, path) = recorded_flight(&truth, 3, "flight.mcap");
        let c = control(usize::MAX);
        let params = vec!["cl_alpha".to_string()];
        let result = run(
            "flight.mcap",
            &params,
            &inputs(&seed, &path),
            &Window::WHOLE,
            &VehicleEdits::new(),
            &c,
        )
        .unwrap();
        let LabResult::Identify(s) = result else {
            panic!("not an identification");
        };
        assert_eq!(s.recording, "flight.mcap");
        let p = &s.params[0];
        assert_eq!((p.name.as_str(), p.nominal), ("cl_alpha", nominal));
        let (lo, hi) = (p.interval95_low.unwrap(), p.interval95_high.unwrap());
        assert!(
            (p.fitted - nominal * 1.1).abs() < 0.02 * nominal && lo < p.fitted && p.fitted < hi,
            "{p:?}"
        );
        assert!(p.std_error.is_some_and(|e| e > 0.0 && e.is_finite()));
        assert_eq!(s.correlation, Some(vec![vec![1.0]]));
        assert!(s.residual_rms_after < s.residual_rms_before, "{s:?}");
        let seen = c.seen.lock().unwrap();
        assert_eq!(seen.first(), Some(&(0, 30)));
        assert!(seen.len() > 1, "{seen:?}");
    }

    #[test]
    fn a_cancel_stops_after_the_first_iteration() {
        let seed = Vehicle::straplex();
        let (_, path) = recorded_flight(&seed, 4, "cancelled.mcap");
        let c = control(0);
        let params = vec!["cl_alpha".to_string(), "cd0".to_string()];
        let LabResult::Identify(s) = run(
            "cancelled.mcap",
            &params,
            &inputs(&seed, &path),
            &Window::WHOLE,
            &VehicleEdits::new(),
            &c,
        )
        .unwrap() else {
            panic!("not an identification");
        };
        assert_eq!((s.stop.as_str(), s.iterations), ("cancelled", 1), "{s:?}");
    }

    #[test]
    fn an_unknown_parameter_or_a_junk_file_fails_with_its_name() {
        let path = temp("junk.mcap");
        std::fs::write(&path, b"not a recording").unwrap();
        let c = control(usize::MAX);
        let seed = Vehicle::straplex();
        let e = run(
            "junk.mcap",
            &["cl_alpha".into()],
            &inputs(&seed, &path),
            &Window::WHOLE,
            &VehicleEdits::new(),
            &c,
        )
        .unwrap_err();
        assert!(e.contains("junk.mcap"), "{e}");
        let e = run(
            "junk.mcap",
            &["span".into()],
            &inputs(&seed, &path),
            &Window::WHOLE,
            &VehicleEdits::new(),
            &c,
        )
        .unwrap_err();
        assert!(e.contains("unknown parameter `span`"), "{e}");
    }
}

//! The Lab's comparison of a recording with the model (issue 16 item 3): the station has
//! checked the recording (a plain name of its recordings directory, holding a flight); this
//! reads its flight log as `stx compare` does, flies the model through it with
//! `stx_analysis::compare`, stopping when the job is cancelled or over its cap, and hands the
//! page both series thinned for plotting beside each channel's error figures over every sample.

use stx_analysis::compare::{CompareReport, DEFAULT_STEP_S, fly_watched, report};
use stx_analysis::flight_log::window::Window;
use stx_station::lab::compare::{MAX_COMPARE_POINTS, plotted};
use stx_station::lab::{
    CompareChannel, CompareSeries, JobControl, JobInputs, LabResult, VehicleEdits,
};

use crate::recording::{flight_log, vehicle_changes, watcher};

/// Compares the recording `name` with the vehicle of `inputs` (edited from the seed's by
/// `edits`).
pub fn run(
    name: &str,
    inputs: &JobInputs,
    window: &Window,
    edits: &VehicleEdits,
    control: &dyn JobControl,
) -> Result<LabResult, String> {
    let log = flight_log(name, inputs, window).map_err(|e| e.to_string())?;
    control.progress(0, log.samples().len());
    let flown = fly_watched(&log, &inputs.vehicle, DEFAULT_STEP_S, watcher(control))
        .map_err(|e| format!("flying the model through {name}: {e}"))?;
    let compared = report(&log, &flown);
    Ok(LabResult::Compare(series(
        name,
        edits,
        &compared,
        MAX_COMPARE_POINTS,
    )))
}

/// `report` as the Lab draws it: at most `max_points` instants of each series, the error
/// figures as computed over every sample.
pub fn series(
    name: &str,
    edits: &VehicleEdits,
    report: &CompareReport,
    max_points: usize,
) -> CompareSeries {
    let keep = plotted(report.time_s.len(), max_points);
    let finite = |v: f64| v.is_finite().then_some(v);
    CompareSeries {
        recording: name.to_string(),
        vehicle_changes: vehicle_changes(edits),
        duration_s: report.duration_s,
        parafoil_stage_s: report.part.map(|p| [p.from_s, p.to_s]),
        recorded_s: report.part.map_or(report.duration_s, |p| p.recorded_s),
        samples: u32::try_from(report.time_s.len()).unwrap_or(u32::MAX),
        time_s: keep.iter().map(|&i| report.time_s[i]).collect(),
        channels: report
            .channels
            .iter()
            .map(|c| CompareChannel {
                name: c.name.clone(),
                unit: c.unit.clone(),
                recorded: keep
                    .iter()
                    .map(|&i| c.recorded.get(i).copied().flatten().and_then(finite))
                    .collect(),
                model: keep
                    .iter()
                    .map(|&i| c.simulated.get(i).copied().and_then(finite))
                    .collect(),
                rms: c.error.rms,
                max_abs: c.error.max_abs,
                bias: c.error.bias,
                count: u32::try_from(c.error.count).unwrap_or(u32::MAX),
            })
            .collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use stx_analysis::compare::{CompareOptions, compare};
    use stx_analysis::flight_log::synthetic::{SyntheticFlight, simulate};
    use stx_dynamics::vehicle::Vehicle;

    use crate::recording::tests::{control, inputs, recorded_flight, temp};

    #[test]
    fn a_recorded_flight_is_compared_as_stx_compare_compares_it() {
        let vehicle = Vehicle::straplex();
        let (log, path) = recorded_flight(&vehicle, 3, "flight.mcap");
        let c = control(usize::MAX);
        let edits = VehicleEdits::from([("canopy.mass_kg".to_string(), 0.8)]);
        let LabResult::Compare(s) = run(
            "flight.mcap",
            &inputs(&vehicle, &path),
            &Window::WHOLE,
            &edits,
            &c,
        )
        .unwrap() else {
            panic!("not a comparison");
        };
        let n = log.samples().len();
        assert_eq!((s.samples as usize, s.time_s.len()), (n, n));
        assert_eq!(s.vehicle_changes, vec!["canopy.mass_kg = 0.8"]);
        assert_eq!(c.seen.lock().unwrap().last(), Some(&(n, n)));
        // The recording read back is the log (its JSON keeps 7 digits, MAVLink's f32): the
        // figures are the library's on the log itself, within what the rounding moves the
        // differenced turn rate (4 % measured).
        let direct = compare(&log, &vehicle, &CompareOptions::default()).unwrap();
        assert_eq!(s.channels.len(), 9);
        for (ours, theirs) in s.channels.iter().zip(&direct.channels) {
            assert_eq!((&ours.name, &ours.unit), (&theirs.name, &theirs.unit));
            assert_eq!(ours.count as usize, theirs.error.count);
            let within = 0.08 * theirs.error.rms.max(0.05);
            assert!(
                (ours.rms - theirs.error.rms).abs() <= within
                    && (ours.bias - theirs.error.bias).abs() <= within,
                "{}: rms {} bias {} vs rms {} bias {}",
                ours.name,
                ours.rms,
                ours.bias,
                theirs.error.rms,
                theirs.error.bias
            );
            assert!(ours.model.iter().all(|v| v.is_some_and(f64::is_finite)));
        }
        // The model stays with its own vehicle's flight: metres, not tens of metres.
        let north = &s.channels[0];
        assert!(north.name == "north_m" && north.rms < 10.0, "{north:?}");
    }

    #[test]
    fn a_long_flight_is_thinned_for_the_plots_but_its_figures_are_over_every_sample() {
        let vehicle = Vehicle::straplex();
        let log = simulate(&vehicle, &SyntheticFlight::manoeuvres(4)).unwrap();
        let report = compare(&log, &vehicle, &CompareOptions::default()).unwrap();
        let n = report.time_s.len();
        let s = series("f.mcap", &VehicleEdits::new(), &report, 50);
        assert_eq!(s.time_s.len(), 50);
        assert_eq!(s.time_s[0], 0.0);
        assert_eq!(s.time_s[49], report.time_s[n - 1]);
        for (c, full) in s.channels.iter().zip(&report.channels) {
            assert_eq!((c.recorded.len(), c.model.len()), (50, 50));
            assert_eq!(
                (c.count as usize, c.rms),
                (full.error.count, full.error.rms)
            );
        }
    }

    #[test]
    fn a_cancel_stops_the_model_part_way() {
        let vehicle = Vehicle::straplex();
        let (_, path) = recorded_flight(&vehicle, 5, "cancelled.mcap");
        let c = control(10);
        let e = run(
            "cancelled.mcap",
            &inputs(&vehicle, &path),
            &Window::WHOLE,
            &VehicleEdits::new(),
            &c,
        )
        .unwrap_err();
        assert!(
            e.contains("cancelled.mcap") && e.contains("stopped at"),
            "{e}"
        );
        assert_eq!(c.seen.lock().unwrap().last().map(|p| p.0), Some(10));
    }

    #[test]
    fn a_file_that_is_no_recording_fails_with_its_name() {
        let path = temp("junk.mcap");
        std::fs::write(&path, b"not a recording").unwrap();
        let e = run(
            "junk.mcap",
            &inputs(&Vehicle::straplex(), &path),
            &Window::WHOLE,
            &VehicleEdits::new(),
            &control(usize::MAX),
        )
        .unwrap_err();
        assert!(e.contains("junk.mcap"), "{e}");
    }
}

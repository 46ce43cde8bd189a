//! What the Lab's jobs on a recording ([`crate::compare`], [`crate::identify`]) share: the
//! recording the station checked before the job started, read as a flight log as the command
//! line reads it ([`crate::flight_file`]); a job's progress and cancel in the form the
//! analysis' loops take; and the vehicle edits as the results list them.

use stx_analysis::flight_log::FlightLog;
use stx_analysis::flight_log::window::{Window, WindowEnd};
use stx_station::lab::{JobControl, JobInputs, LabJobBody, VehicleEdits};

use crate::flight_file::{chain, read_log};

/// Why a job on a recording cannot run.
#[derive(Debug, Clone, PartialEq)]
pub enum Refused {
    /// The recording does not read as a flight log (or the station handed none: a bug).
    Recording(String),
    /// The flight does not reach the window asked for: the request's field names, and why.
    Window { field: &'static str, reason: String },
}

impl std::fmt::Display for Refused {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Refused::Recording(reason) => f.write_str(reason),
            Refused::Window { field, reason } => write!(f, "{field}: {reason}"),
        }
    }
}

/// The flight log of the recording `name`, which the station checked (a file of its
/// recordings directory holding a flight) and put in `inputs`, cut to `window` (whose ends
/// the station checked too: what is left to refuse is a window the flight does not reach).
pub fn flight_log(name: &str, inputs: &JobInputs, window: &Window) -> Result<FlightLog, Refused> {
    let path = inputs.recording.as_deref().ok_or_else(|| {
        Refused::Recording(format!(
            "the station gave the job on {name} no recording (a bug)"
        ))
    })?;
    let log = read_log(path).map_err(|e| Refused::Recording(chain(&e)))?;
    log.cut(window).map_err(|e| Refused::Window {
        field: match e.end() {
            WindowEnd::From => "from_s",
            WindowEnd::To => "to_s",
            WindowEnd::Both => "from_s, to_s",
        },
        reason: format!("{e} (in {name})"),
    })
}

/// The station's question before a job on a recording starts
/// ([`stx_station::lab::LabWorker::check_window`]): does its flight reach the window asked?
/// A recording that reads as no flight log passes: the job then fails saying why.
pub fn check_window(job: &LabJobBody, inputs: &JobInputs) -> Result<(), (String, String)> {
    let (name, window) = match job {
        LabJobBody::Compare {
            recording,
            from_s,
            to_s,
            ..
        }
        | LabJobBody::Identify {
            recording,
            from_s,
            to_s,
            ..
        } => (recording, Window::new(*from_s, *to_s)),
        _ => return Ok(()),
    };
    match flight_log(name, inputs, &window) {
        Err(Refused::Window { field, reason }) => Err((field.to_string(), reason)),
        Ok(_) | Err(Refused::Recording(_)) => Ok(()),
    }
}

/// A loop's watcher for `control`: told `done` of `total`, reports it and answers whether to
/// go on (not once the job is cancelled or over its time cap).
pub fn watcher(control: &dyn JobControl) -> impl FnMut(usize, usize) -> bool + '_ {
    |done, total| {
        control.progress(done, total);
        !control.should_stop()
    }
}

/// `edits` as a result lists them: `name = value`.
pub fn vehicle_changes(edits: &VehicleEdits) -> Vec<String> {
    edits.iter().map(|(k, v)| format!("{k} = {v}")).collect()
}

#[cfg(test)]
pub(crate) mod tests {
    use std::path::{Path, PathBuf};
    use std::sync::Mutex;
    use std::sync::atomic::{AtomicUsize, Ordering};
    use std::time::Duration;

    use nalgebra::Vector3;
    use stx_analysis::flight_log::FlightLog;
    use stx_analysis::flight_log::synthetic::{SyntheticFlight, simulate};
    use stx_analysis::flight_log::window::{Window, WindowEnd};
    use stx_dynamics::vehicle::Vehicle;
    use stx_gnc::geo::LocalFrame;
    use stx_link::telemetry::{Actuators, Attitude, GlobalPosition, Hud, Telemetry, Wind};
    use stx_record::{CoreOptions, Output, RecorderCore, RecordingInfo};
    use stx_station::lab::compare;
    use stx_station::lab::{JobControl, JobInputs, LabJobBody, LabResult, VehicleEdits};
    use stx_station::recording::telemetry::TelemetryChannels;

    use super::{check_window, flight_log};

    /// `log` as the station records a drone's telemetry (the same channels, the same JSON), at
    /// one position, attitude, airspeed, command and wind message per sample.
    pub(crate) fn recording_of(log: &FlightLog, path: &Path) {
        let info = RecordingInfo::new("test", "straplex-2", "lab compare");
        let mut core = RecorderCore::new(CoreOptions::default(), info, Duration::ZERO).unwrap();
        let channels = TelemetryChannels::register(&mut core, Duration::ZERO).unwrap();
        let frame = LocalFrame {
            lat_deg: 41.0,
            lon_deg: -8.0,
            alt_msl_m: 0.0,
        };
        let t0_ns = 1_767_225_600_000_000_000u64;
        for s in log.samples() {
            let t_ns = t0_ns + (s.time_s * 1e9).round() as u64;
            let (lat_deg, lon_deg, alt_msl_m) = frame.to_geodetic(&Vector3::from(s.position_ned_m));
            let [v_north_mps, v_east_mps, v_down_mps] = s.velocity_ned_mps;
            let [roll_rad, pitch_rad, yaw_rad] = s.euler_rad;
            let [wn, we, wd] = s.wind_ned_mps;
            let messages = [
                Telemetry::Attitude(Attitude {
                    time_boot_ms: 0,
                    roll_rad,
                    pitch_rad,
                    yaw_rad,
                    roll_rate_radps: 0.0,
                    pitch_rate_radps: 0.0,
                    yaw_rate_radps: 0.0,
                }),
                Telemetry::Actuators(Actuators {
                    time_usec: 0,
                    main_line: s.main_line,
                    brake_right: s.brake_right,
                    brake_left: s.brake_left,
                }),
                Telemetry::Hud(Hud {
                    airspeed_mps: s.airspeed_mps.unwrap_or(0.0),
                    groundspeed_mps: v_north_mps.hypot(v_east_mps),
                    heading_deg: yaw_rad.to_degrees().rem_euclid(360.0),
                    climb_mps: -v_down_mps,
                    alt_msl_m,
                }),
                Telemetry::Wind(Wind {
                    time_usec: 0,
                    wind_north_mps: Some(wn),
                    wind_east_mps: Some(we),
                    wind_down_mps: Some(wd),
                    var_horiz_mps: None,
                    var_vert_mps: None,
                    alt_msl_m: None,
                    horiz_accuracy_mps: 0.0,
                    vert_accuracy_mps: 0.0,
                }),
                Telemetry::Position(GlobalPosition {
                    time_boot_ms: 0,
                    lat_deg,
                    lon_deg,
                    alt_msl_m,
                    alt_rel_m: alt_msl_m,
                    v_north_mps,
                    v_east_mps,
                    v_down_mps,
                    heading_deg: None,
                }),
            ];
            let now = Duration::from_nanos(t_ns - t0_ns);
            for m in &messages {
                for (ch, data) in channels.records(t_ns, m) {
                    core.write(now, ch, t_ns, t_ns, &data).unwrap();
                }
            }
        }
        core.finish().unwrap();
        let mut bytes = Vec::new();
        while let Some(out) = core.poll_output() {
            if let Output::Bytes { data, .. } = out {
                bytes.extend(data);
            }
        }
        std::fs::write(path, bytes).unwrap();
    }

    /// A synthetic flight of `vehicle` (`SyntheticFlight::manoeuvres(seed)`) recorded as the
    /// station records it, in a file called `name` of a directory of its own.
    pub(crate) fn recorded_flight(
        vehicle: &Vehicle,
        seed: u64,
        name: &str,
    ) -> (FlightLog, PathBuf) {
        let log = simulate(vehicle, &SyntheticFlight::manoeuvres(seed)).unwrap();
        let path = temp(name);
        recording_of(&log, &path);
        (log, path)
    }

    /// A job's control: its progress kept, told to stop once `stop_after` steps are done
    /// (0: from the start; `usize::MAX`: never).
    pub(crate) struct Control {
        pub(crate) seen: Mutex<Vec<(usize, usize)>>,
        stop_after: usize,
    }

    impl JobControl for Control {
        fn progress(&self, done: usize, total: usize) {
            self.seen.lock().unwrap().push((done, total));
        }
        fn should_stop(&self) -> bool {
            self.seen.lock().unwrap().last().map_or(0, |p| p.0) >= self.stop_after
        }
    }

    pub(crate) fn control(stop_after: usize) -> Control {
        Control {
            seen: Mutex::new(Vec::new()),
            stop_after,
        }
    }

    /// `name` in a directory of its own (tests run in parallel and reuse names).
    pub(crate) fn temp(name: &str) -> PathBuf {
        static NEXT: AtomicUsize = AtomicUsize::new(0);
        let n = NEXT.fetch_add(1, Ordering::Relaxed);
        let dir = std::env::temp_dir().join(format!("stx-lab-{}-{n}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        dir.join(name)
    }

    /// A window of a recording: the samples within it from the window's first, the model
    /// started there; one the flight does not reach is refused naming the request's fields.
    #[test]
    fn a_window_of_the_recording_is_cut_and_one_past_its_flight_refused() {
        let vehicle = Vehicle::straplex();
        let (_, path) = recorded_flight(&vehicle, 3, "flight.mcap");
        let inputs = inputs(&vehicle, &path);
        let whole = flight_log("flight.mcap", &inputs, &Window::WHOLE).unwrap();
        let t0 = whole.samples()[0].time_s;
        let cut = flight_log("flight.mcap", &inputs, &Window::new(Some(30.0), Some(40.0))).unwrap();
        let inside: Vec<f64> = whole
            .samples()
            .iter()
            .map(|s| s.time_s)
            .filter(|t| (30.0..=40.0).contains(&(t - t0)))
            .collect();
        let times: Vec<f64> = cut.samples().iter().map(|s| s.time_s).collect();
        assert_eq!(times, inside);
        assert!(
            (cut.duration_s() - 10.0).abs() <= 0.2 + 1e-9,
            "{}",
            cut.duration_s()
        );
        let LabResult::Compare(s) = crate::compare::run(
            "flight.mcap",
            &inputs,
            &Window::new(Some(30.0), Some(40.0)),
            &VehicleEdits::new(),
            &control(usize::MAX),
        )
        .unwrap() else {
            panic!("not a comparison");
        };
        assert_eq!(
            (s.samples as usize, s.duration_s),
            (inside.len(), cut.duration_s())
        );
        assert_eq!(s.time_s[0], 0.0);
        let e = flight_log("flight.mcap", &inputs, &Window::new(Some(500.0), None))
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("from_s, to_s: ")
                && e.contains("holds 0 samples")
                && e.contains("flight.mcap"),
            "{e}"
        );
        // The station asks the same before the job starts.
        let job = |from_s, to_s| LabJobBody::Compare {
            recording: "flight.mcap".into(),
            vehicle: VehicleEdits::new(),
            from_s,
            to_s,
        };
        assert_eq!(check_window(&job(Some(30.0), Some(40.0)), &inputs), Ok(()));
        let (field, reason) = check_window(&job(Some(500.0), None), &inputs).unwrap_err();
        assert_eq!(field, "from_s, to_s");
        assert!(reason.contains("holds 0 samples"), "{reason}");
        let identify = LabJobBody::Identify {
            recording: "flight.mcap".into(),
            params: vec!["cd0".into()],
            vehicle: VehicleEdits::new(),
            from_s: None,
            to_s: Some(0.3),
        };
        assert_eq!(
            check_window(&identify, &inputs).unwrap_err().0,
            "from_s, to_s"
        );
    }

    /// The station refuses before a job starts the windows the library would refuse, and no
    /// others (it sits below stx-analysis and keeps its own copy of the rule).
    #[test]
    fn the_station_checks_a_window_s_ends_as_the_library_does() {
        let ends = [
            None,
            Some(0.0),
            Some(2.5),
            Some(7.0),
            Some(-1.0),
            Some(f64::NAN),
            Some(f64::INFINITY),
        ];
        for from_s in ends {
            for to_s in ends {
                let library = Window::new(from_s, to_s).check();
                let station = compare::check_window(from_s, to_s);
                assert_eq!(station.is_ok(), library.is_ok(), "{from_s:?} … {to_s:?}");
                if let (Err((field, _)), Err(e)) = (station, library) {
                    let end = if field == "from_s" {
                        WindowEnd::From
                    } else {
                        WindowEnd::To
                    };
                    assert_eq!(end, e.end(), "{from_s:?} … {to_s:?}");
                }
            }
        }
    }

    /// What the station hands a job on the recording at `path`, with `vehicle`.
    pub(crate) fn inputs(vehicle: &Vehicle, path: &Path) -> JobInputs {
        JobInputs {
            vehicle: vehicle.clone(),
            recording: Some(path.to_path_buf()),
        }
    }
}

//! A GFS forecast's winds as a 4-D field over (forecast time, pressure level, latitude,
//! longitude), read from GRIB2 files, and the wind profile at a place and time.
//!
//! What is read: `UGRD`, `VGRD` and `HGT` (discipline 0; category 2 numbers 2 and 3, category
//! 3 number 5) on isobaric levels (surface type 100), forecasts at a point in time (product
//! templates 0 and 1), on one latitude/longitude grid, from one model run. Several files (one
//! per forecast hour, as NOMADS serves them) make one field. Every other message is skipped;
//! every level must carry all three variables at every forecast hour, or the field is refused
//! naming the first message missing.
//!
//! Interpolation ([`GfsField::profile`]): on each level, bilinear in latitude and longitude
//! between the four grid points around the place (longitudes taken modulo 360, and across the
//! date line on a global grid); linear in time between the two forecast hours around the
//! instant; winds by component, heights as geopotential, then turned into geometric height.
//! A place outside the grid's box or an instant outside its hours is refused, not
//! extrapolated.

use std::collections::BTreeMap;
use std::sync::Arc;

use time::OffsetDateTime;

use crate::decode::{DecodeError, GridPoints, Message, decode};
use crate::{WindLevel, format_time, geometric_height_m};

/// The variables read, in the order the field keeps them.
const VARIABLES: [Variable; 3] = [
    Variable {
        name: "UGRD",
        category: 2,
        number: 2,
    },
    Variable {
        name: "VGRD",
        category: 2,
        number: 3,
    },
    Variable {
        name: "HGT",
        category: 3,
        number: 5,
    },
];

struct Variable {
    name: &'static str,
    category: u8,
    number: u8,
}

/// Isobaric surface (GRIB2 code table 4.5), its value in Pa.
const ISOBARIC: u8 = 100;

/// Why GRIB2 files do not make a wind field, or a profile cannot be taken from it.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum GfsError {
    /// A file could not be decoded.
    #[error("{file}: {source}")]
    Decode {
        /// The file, as the caller named it.
        file: String,
        /// Why.
        #[source]
        source: DecodeError,
    },
    /// A variable is in no file at all.
    #[error(
        "no {variable} on isobaric levels in the file(s): a GFS wind field needs UGRD, VGRD \
         and HGT (select them, with the levels, in the NOMADS filter)"
    )]
    MissingVariable {
        /// `UGRD`, `VGRD` or `HGT`.
        variable: &'static str,
    },
    /// A variable lacks one level at one forecast hour that the others have.
    #[error(
        "no {variable} at {level_hpa} hPa for forecast hour {hour}: every level needs UGRD, VGRD and HGT at every hour"
    )]
    MissingMessage {
        /// `UGRD`, `VGRD` or `HGT`.
        variable: &'static str,
        /// The level, hPa.
        level_hpa: f64,
        /// The forecast hour after the model run.
        hour: f64,
    },
    /// Two messages hold the same variable, level and hour.
    #[error(
        "{file}: a second {variable} at {level_hpa} hPa for forecast hour {hour} (a file given \
         twice, or several ensemble members?)"
    )]
    Duplicate {
        /// The file of the second message.
        file: String,
        /// `UGRD`, `VGRD` or `HGT`.
        variable: &'static str,
        /// The level, hPa.
        level_hpa: f64,
        /// The forecast hour.
        hour: f64,
    },
    /// A message has missing points (a bitmap) where the field needs every one.
    #[error(
        "{variable} at {level_hpa} hPa, forecast hour {hour}: {missing} grid points have no value"
    )]
    MissingValues {
        /// `UGRD`, `VGRD` or `HGT`.
        variable: &'static str,
        /// The level, hPa.
        level_hpa: f64,
        /// The forecast hour.
        hour: f64,
        /// How many points lack a value.
        missing: usize,
    },
    /// The messages are on different grids, or the grid is not a regular latitude/longitude
    /// one of at least 2 × 2 points.
    #[error("{0}")]
    Grid(String),
    /// The messages come from different model runs, or a run's time cannot be read.
    #[error("{0}")]
    Run(String),
    /// The place is outside the grid.
    #[error(
        "{lat_deg}° N {lon_deg}° E is outside the file's box (latitudes {lat_min_deg}…{lat_max_deg}°, \
         longitudes {lon_min_deg}…{lon_max_deg}°)"
    )]
    OutsideBox {
        /// The place's latitude, degrees.
        lat_deg: f64,
        /// The place's longitude, degrees.
        lon_deg: f64,
        /// The grid's southernmost latitude, degrees.
        lat_min_deg: f64,
        /// Its northernmost.
        lat_max_deg: f64,
        /// Its westernmost longitude, degrees.
        lon_min_deg: f64,
        /// Its easternmost.
        lon_max_deg: f64,
    },
    /// The instant is outside the forecast hours.
    #[error("{time} is outside the forecast: its hours cover {first} to {last}")]
    OutsideHours {
        /// The instant asked for, RFC 3339.
        time: String,
        /// The first forecast time, RFC 3339.
        first: String,
        /// The last.
        last: String,
    },
}

/// Winds and geopotential heights over (forecast time, pressure level, latitude, longitude).
#[derive(Debug, Clone, PartialEq)]
pub struct GfsField {
    /// The model run (GRIB's reference time).
    reference_time: OffsetDateTime,
    /// Forecast times after the run, s, ascending.
    forecast_s: Vec<i64>,
    /// Pressure levels, Pa, descending (lowest level first).
    levels_pa: Vec<f64>,
    /// Latitude of each grid row j, degrees (ascending or descending, as the file scans).
    lat_deg: Vec<f64>,
    /// Longitude of each grid column i, degrees, ascending (a file's 0–360 or −180–180).
    lon_deg: Vec<f64>,
    /// Whether the columns go round the Earth (the last one a step short of the first + 360).
    global: bool,
    /// Per variable in [`VARIABLES`]' order, values at `((t·levels + k)·nj + j)·ni + i`.
    values: [Vec<f32>; 3],
}

/// The messages of one variable, keyed by (forecast s, level Pa in mPa for an exact key).
type Slices = BTreeMap<(i64, i64), Vec<f32>>;

impl GfsField {
    /// The field of one or more GRIB2 files, each `(name for messages, bytes)`.
    pub fn from_files<'a>(
        files: impl IntoIterator<Item = (&'a str, &'a [u8])>,
    ) -> Result<Self, GfsError> {
        let mut grid: Option<Grid> = None;
        let mut reference_time = None;
        let mut slices: [Slices; 3] = Default::default();
        for (file, bytes) in files {
            let messages = decode(bytes).map_err(|source| GfsError::Decode {
                file: file.to_string(),
                source,
            })?;
            let mut file_grid: Option<(Arc<GridPoints>, Grid)> = None;
            for m in messages {
                let Some(v) = variable_of(&m) else { continue };
                if !file_grid
                    .as_ref()
                    .is_some_and(|(p, _)| Arc::ptr_eq(p, &m.points))
                {
                    let g = Grid::of(&m)?;
                    if let Some(first) = &grid
                        && *first != g
                    {
                        return Err(GfsError::Grid(format!(
                            "{file}: {} is on a different grid from the messages before it",
                            VARIABLES[v].name
                        )));
                    }
                    if grid.is_none() {
                        grid = Some(g.clone());
                    }
                    file_grid = Some((Arc::clone(&m.points), g));
                }
                let (_, g) = file_grid.as_ref().expect("set above");
                let run = m.reference_time.ok_or_else(|| {
                    GfsError::Run(format!("{file}: a message's reference time is not a date"))
                })?;
                match reference_time {
                    None => reference_time = Some(run),
                    Some(t) if t != run => {
                        return Err(GfsError::Run(format!(
                            "{file}: messages of two model runs ({} and {}); give one run's files",
                            format_time(t),
                            format_time(run)
                        )));
                    }
                    Some(_) => {}
                }
                let forecast_s = m.forecast_s.ok_or_else(|| {
                    GfsError::Run(format!("{file}: a forecast time in an unknown unit"))
                })?;
                let key = (forecast_s, (m.surface_value * 1000.0).round() as i64);
                // A second message for the same slot (a file given twice, or two ensemble
                // members) would silently replace the first.
                if slices[v].insert(key, g.reorder(&m)).is_some() {
                    return Err(GfsError::Duplicate {
                        file: file.to_string(),
                        variable: VARIABLES[v].name,
                        level_hpa: m.surface_value / 100.0,
                        hour: forecast_s as f64 / 3600.0,
                    });
                }
            }
        }
        for (v, s) in slices.iter().enumerate() {
            if s.is_empty() {
                return Err(GfsError::MissingVariable {
                    variable: VARIABLES[v].name,
                });
            }
        }
        let (Some(grid), Some(reference_time)) = (grid, reference_time) else {
            unreachable!("a variable was found, so a grid and a run were")
        };
        let mut forecast_s: Vec<i64> = slices.iter().flat_map(|s| s.keys().map(|k| k.0)).collect();
        forecast_s.sort_unstable();
        forecast_s.dedup();
        let mut levels: Vec<i64> = slices.iter().flat_map(|s| s.keys().map(|k| k.1)).collect();
        levels.sort_unstable_by(|a, b| b.cmp(a));
        levels.dedup();
        let mut values: [Vec<f32>; 3] = Default::default();
        for (v, s) in slices.iter_mut().enumerate() {
            for &t in &forecast_s {
                for &level in &levels {
                    let hour = t as f64 / 3600.0;
                    let level_hpa = level as f64 / 1e5;
                    let slice = s.remove(&(t, level)).ok_or(GfsError::MissingMessage {
                        variable: VARIABLES[v].name,
                        level_hpa,
                        hour,
                    })?;
                    let missing = slice.iter().filter(|x| x.is_nan()).count();
                    if missing > 0 {
                        return Err(GfsError::MissingValues {
                            variable: VARIABLES[v].name,
                            level_hpa,
                            hour,
                            missing,
                        });
                    }
                    values[v].extend_from_slice(&slice);
                }
            }
        }
        Ok(Self {
            reference_time,
            forecast_s,
            levels_pa: levels.iter().map(|&l| l as f64 / 1000.0).collect(),
            global: grid.global,
            lat_deg: grid.lat_deg,
            lon_deg: grid.lon_deg,
            values,
        })
    }

    /// The model run.
    pub fn reference_time(&self) -> OffsetDateTime {
        self.reference_time
    }

    /// The forecast times, earliest first.
    pub fn valid_times(&self) -> Vec<OffsetDateTime> {
        self.forecast_s
            .iter()
            .map(|&s| self.reference_time + time::Duration::seconds(s))
            .collect()
    }

    /// The pressure levels, Pa, lowest level (highest pressure) first.
    pub fn levels_pa(&self) -> &[f64] {
        &self.levels_pa
    }

    /// Grid rows and columns: (latitudes, longitudes), degrees.
    pub fn shape(&self) -> (usize, usize) {
        (self.lat_deg.len(), self.lon_deg.len())
    }

    /// `UGRD`, `VGRD` and `HGT` at forecast time `t`, level `k`, row `j`, column `i`
    /// (indices as [`Self::valid_times`], [`Self::levels_pa`] and the file's grid order): m/s,
    /// m/s and geopotential metres.
    pub fn at_grid_point(&self, t: usize, k: usize, j: usize, i: usize) -> [f32; 3] {
        let at = self.index(t, k, j, i);
        [self.values[0][at], self.values[1][at], self.values[2][at]]
    }

    /// Latitude and longitude of row `j`, column `i`, degrees.
    pub fn grid_point_deg(&self, j: usize, i: usize) -> (f64, f64) {
        (self.lat_deg[j], self.lon_deg[i])
    }

    fn index(&self, t: usize, k: usize, j: usize, i: usize) -> usize {
        let (nj, ni) = self.shape();
        ((t * self.levels_pa.len() + k) * nj + j) * ni + i
    }

    /// The wind at `lat_deg`, `lon_deg` (degrees) and instant `at`, one level per pressure
    /// level, lowest first (module doc: how it is interpolated). Levels whose height does not
    /// rise above the one below (never in a real forecast) are left out, so the heights
    /// strictly increase.
    pub fn profile(
        &self,
        lat_deg: f64,
        lon_deg: f64,
        at: OffsetDateTime,
    ) -> Result<Vec<WindLevel>, GfsError> {
        let (rows, cols) = self.horizontal_weights(lat_deg, lon_deg)?;
        let times = self.time_weights(at)?;
        let mut out: Vec<WindLevel> = Vec::with_capacity(self.levels_pa.len());
        for (k, &pressure_pa) in self.levels_pa.iter().enumerate() {
            let mut sum = [0.0f64; 3];
            for &(t, wt) in &times {
                for &(j, wj) in &rows {
                    for &(i, wi) in &cols {
                        let at = self.index(t, k, j, i);
                        let w = wt * wj * wi;
                        for (v, s) in sum.iter_mut().enumerate() {
                            *s += w * f64::from(self.values[v][at]);
                        }
                    }
                }
            }
            let alt_msl_m = geometric_height_m(sum[2]);
            if out.last().is_some_and(|below| alt_msl_m <= below.alt_msl_m) {
                continue;
            }
            out.push(WindLevel {
                alt_msl_m,
                north_mps: sum[1],
                east_mps: sum[0],
                pressure_pa: Some(pressure_pa),
            });
        }
        Ok(out)
    }

    /// The two rows and two columns around the place, with their weights.
    #[allow(clippy::type_complexity)]
    fn horizontal_weights(
        &self,
        lat_deg: f64,
        lon_deg: f64,
    ) -> Result<([(usize, f64); 2], [(usize, f64); 2]), GfsError> {
        let lat_min = self.lat_deg.iter().copied().fold(f64::INFINITY, f64::min);
        let lat_max = self
            .lat_deg
            .iter()
            .copied()
            .fold(f64::NEG_INFINITY, f64::max);
        let (lon_first, lon_last) = (self.lon_deg[0], self.lon_deg[self.lon_deg.len() - 1]);
        let outside = || GfsError::OutsideBox {
            lat_deg,
            lon_deg,
            lat_min_deg: lat_min,
            lat_max_deg: lat_max,
            lon_min_deg: lon_first,
            lon_max_deg: lon_last,
        };
        let rows = bracket(&self.lat_deg, lat_deg).ok_or_else(outside)?;
        // The place's longitude moved by whole turns into the columns' span.
        let lon = lon_first + (lon_deg - lon_first).rem_euclid(360.0);
        let cols = match bracket(&self.lon_deg, lon) {
            Some(c) => c,
            None if self.global && lon > lon_last => {
                let step = 360.0 - (lon_last - lon_first);
                let f = (lon - lon_last) / step;
                [(self.lon_deg.len() - 1, 1.0 - f), (0, f)]
            }
            None => return Err(outside()),
        };
        Ok((rows, cols))
    }

    /// The one or two forecast times around `at`, with their weights.
    fn time_weights(&self, at: OffsetDateTime) -> Result<Vec<(usize, f64)>, GfsError> {
        let s = (at - self.reference_time).as_seconds_f64();
        let times: Vec<f64> = self.forecast_s.iter().map(|&t| t as f64).collect();
        if let Some(k) = times.iter().position(|&t| t == s) {
            return Ok(vec![(k, 1.0)]);
        }
        bracket(&times, s).map(|b| b.to_vec()).ok_or_else(|| {
            let valid = self.valid_times();
            GfsError::OutsideHours {
                time: format_time(at),
                first: format_time(valid[0]),
                last: format_time(valid[valid.len() - 1]),
            }
        })
    }
}

/// The two neighbouring entries of a monotonic `axis` around `x` with linear weights; `None`
/// outside it (or for an axis of one entry, unless `x` is on it).
fn bracket(axis: &[f64], x: f64) -> Option<[(usize, f64); 2]> {
    let n = axis.len();
    if n == 1 {
        return (axis[0] == x).then_some([(0, 1.0), (0, 0.0)]);
    }
    let ascending = axis[n - 1] > axis[0];
    // First index whose value is past x in the axis' direction.
    let past = axis.partition_point(|&a| if ascending { a <= x } else { a >= x });
    let k = match past {
        0 => return None,
        p if p == n => {
            if axis[n - 1] == x {
                n - 1
            } else {
                return None;
            }
        }
        p => p,
    }
    .max(1);
    let (a0, a1) = (axis[k - 1], axis[k]);
    let f = (x - a0) / (a1 - a0);
    Some([(k - 1, 1.0 - f), (k, f)])
}

/// Which of [`VARIABLES`] a message holds, if it is one of them on an isobaric level.
fn variable_of(m: &Message) -> Option<usize> {
    if m.discipline != 0 || m.surface_type != Some(ISOBARIC) || m.product_template > 1 {
        return None;
    }
    VARIABLES
        .iter()
        .position(|v| m.category == Some(v.category) && m.number == Some(v.number))
}

/// A latitude/longitude grid as the field keeps it, and where each of a message's values goes.
#[derive(Debug, Clone, PartialEq)]
struct Grid {
    lat_deg: Vec<f64>,
    lon_deg: Vec<f64>,
    global: bool,
    /// Per value of a message in file order, its index `j·ni + i` in the field.
    to_field: Vec<usize>,
}

impl Grid {
    fn of(m: &Message) -> Result<Self, GfsError> {
        let (ni, nj) = (m.ni, m.nj);
        let GridPoints {
            ij,
            lat_lon_deg: ll,
        } = &*m.points;
        if ni < 2 || nj < 2 || ij.len() != ni * nj || ll.len() != ni * nj {
            return Err(GfsError::Grid(format!(
                "the grid is {ni} × {nj} points: a wind field needs a latitude/longitude grid \
                 of at least 2 × 2"
            )));
        }
        let mut lat_deg = vec![f64::NAN; nj];
        let mut lon_deg = vec![f64::NAN; ni];
        let mut to_field = Vec::with_capacity(ni * nj);
        for (&(i, j), &(lat, lon)) in ij.iter().zip(ll) {
            if i >= ni || j >= nj {
                return Err(GfsError::Grid(format!(
                    "grid point ({i}, {j}) outside {ni} × {nj}"
                )));
            }
            lat_deg[j] = lat;
            lon_deg[i] = lon;
            to_field.push(j * ni + i);
        }
        let monotonic =
            |a: &[f64]| a.windows(2).all(|w| w[1] > w[0]) || a.windows(2).all(|w| w[1] < w[0]);
        // A regular latitude/longitude grid: each row one latitude, each column one
        // longitude, both monotonic. Longitudes made ascending through the date line.
        for k in 1..ni {
            while lon_deg[k] <= lon_deg[k - 1] {
                lon_deg[k] += 360.0;
            }
        }
        let regular = ij.iter().zip(ll).all(|(&(i, j), &(lat, lon))| {
            lat == lat_deg[j] && ((lon - lon_deg[i]) / 360.0).fract().abs() < 1e-9
        });
        if !regular || !monotonic(&lat_deg) || lon_deg.iter().any(|x| !x.is_finite()) {
            return Err(GfsError::Grid(
                "the grid is not a regular latitude/longitude one (GFS' is)".into(),
            ));
        }
        let step = lon_deg[1] - lon_deg[0];
        let global = (lon_deg[ni - 1] - lon_deg[0] + step - 360.0).abs() < 1e-6;
        Ok(Self {
            lat_deg,
            lon_deg,
            global,
            to_field,
        })
    }

    /// The message's values in the field's order.
    fn reorder(&self, m: &Message) -> Vec<f32> {
        let mut out = vec![f32::NAN; m.values.len()];
        for (&to, &v) in self.to_field.iter().zip(&m.values) {
            out[to] = v;
        }
        out
    }
}

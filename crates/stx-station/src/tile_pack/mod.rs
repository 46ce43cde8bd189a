//! Offline map tile packs: one file, prepared at home, that holds the map of the field (fields,
//! roads, water) for a laptop with no internet. The station opens it at start and serves its
//! tiles under `/tiles/{z}/{x}/{y}`, which the dashboard's map draws.
//!
//! Two formats, told apart by the file's extension:
//! - MBTiles (`.mbtiles`, [`mbtiles`]): SQLite, what most tile tools export;
//! - PMTiles v3 (`.pmtiles`, [`pmtiles_v3`]): one file of directories and tiles, what the
//!   Protomaps tools make.
//!
//! Opening reads the pack's description ([`PackInfo`]) and checks that a tile can be looked up,
//! so a missing or corrupt file is found at start, named in one message ([`TilePackError`]),
//! and the station runs on without it ([`LoadedPack`]): the map then shows that message and its
//! metric grid.

pub mod mbtiles;
pub mod pmtiles_v3;

use std::path::{Path, PathBuf};
use std::sync::Arc;

use thiserror::Error;

/// Why a pack could not be opened or a tile not read.
#[derive(Debug, Error)]
pub enum TilePackError {
    /// No file at the configured path.
    #[error("tile pack {path}: no such file")]
    Missing {
        /// The configured path.
        path: PathBuf,
    },
    /// Neither `.mbtiles` nor `.pmtiles`.
    #[error("tile pack {path}: not an .mbtiles or .pmtiles file")]
    UnknownKind {
        /// The configured path.
        path: PathBuf,
    },
    /// The file is there but is not a readable pack of its kind.
    #[error("tile pack {path} is not a usable {kind} file: {reason}")]
    Corrupt {
        /// The configured path.
        path: PathBuf,
        /// `MBTiles` or `PMTiles`.
        kind: &'static str,
        /// What the reader found.
        reason: String,
    },
    /// A tile could not be read from a pack that opened.
    #[error("tile pack {path}: reading tile {coord}: {reason}")]
    Read {
        /// The configured path.
        path: PathBuf,
        /// The tile.
        coord: TileCoord,
        /// What went wrong.
        reason: String,
    },
}

/// Deepest zoom a tile address may ask for: beyond any map's detail, and `2^z` fits a `u32`.
pub const MAX_ZOOM: u8 = 30;

/// A tile's address in the XYZ scheme the dashboard's map uses (y from the north).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TileCoord {
    /// Zoom level.
    pub z: u8,
    /// Column, from the west.
    pub x: u32,
    /// Row, from the north.
    pub y: u32,
}

impl std::fmt::Display for TileCoord {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}/{}", self.z, self.x, self.y)
    }
}

impl TileCoord {
    /// Reads `z/x/y` or `z/x/y.ext` (the extension is ignored: a pack has one format, and
    /// `tile_url = "/tiles/{z}/{x}/{y}.png"` must keep working). `Err` says what is wrong.
    pub fn parse(path: &str) -> Result<Self, String> {
        let parts: Vec<&str> = path.trim_start_matches('/').split('/').collect();
        let [z, x, y] = parts[..] else {
            return Err(format!("`{path}` is not a tile address z/x/y"));
        };
        let y = y.split_once('.').map_or(y, |(stem, _)| stem);
        let number = |what: &str, text: &str| {
            // `u32::from_str` takes a leading `+`; an address is digits only.
            if text.is_empty() || !text.bytes().all(|b| b.is_ascii_digit()) {
                return Err(format!("{what} `{text}` is not a whole number"));
            }
            text.parse::<u32>()
                .map_err(|_| format!("{what} `{text}` is too large"))
        };
        let z = number("zoom", z)?;
        if z > u32::from(MAX_ZOOM) {
            return Err(format!("zoom {z} is beyond {MAX_ZOOM}"));
        }
        let (x, y) = (number("column", x)?, number("row", y)?);
        let side = 1u64 << z;
        if u64::from(x) >= side || u64::from(y) >= side {
            return Err(format!(
                "tile {z}/{x}/{y} is outside the {side}×{side} grid of zoom {z}"
            ));
        }
        Ok(Self { z: z as u8, x, y })
    }

    /// The row counted from the south, as MBTiles (the TMS scheme) stores it.
    pub fn tms_row(&self) -> u32 {
        ((1u64 << self.z) - 1 - u64::from(self.y)) as u32
    }
}

/// What a pack's tiles are.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TileFormat {
    /// PNG images.
    Png,
    /// JPEG images.
    Jpeg,
    /// WebP images.
    Webp,
    /// AVIF images.
    Avif,
    /// Mapbox vector tiles (protobuf): data, not pictures.
    Pbf,
    /// MapLibre vector tiles: data, not pictures.
    Mlt,
}

impl TileFormat {
    /// The MBTiles `format` text (`jpeg` is taken for `jpg`, `mvt` for `pbf`).
    pub fn from_name(name: &str) -> Option<Self> {
        Some(match name.trim().to_ascii_lowercase().as_str() {
            "png" => Self::Png,
            "jpg" | "jpeg" => Self::Jpeg,
            "webp" => Self::Webp,
            "avif" => Self::Avif,
            "pbf" | "mvt" => Self::Pbf,
            "mlt" => Self::Mlt,
            _ => return None,
        })
    }

    /// Guessed from a tile's first bytes, for a pack that does not say.
    pub fn sniff(data: &[u8]) -> Option<Self> {
        Some(match data {
            [0x89, b'P', b'N', b'G', ..] => Self::Png,
            [0xFF, 0xD8, 0xFF, ..] => Self::Jpeg,
            [
                b'R',
                b'I',
                b'F',
                b'F',
                _,
                _,
                _,
                _,
                b'W',
                b'E',
                b'B',
                b'P',
                ..,
            ] => Self::Webp,
            [
                _,
                _,
                _,
                _,
                b'f',
                b't',
                b'y',
                b'p',
                b'a',
                b'v',
                b'i',
                b'f',
                ..,
            ] => Self::Avif,
            // Vector tiles are nearly always stored gzipped.
            [0x1F, 0x8B, ..] => Self::Pbf,
            _ => return None,
        })
    }

    /// The HTTP `Content-Type`.
    pub fn content_type(self) -> &'static str {
        match self {
            Self::Png => "image/png",
            Self::Jpeg => "image/jpeg",
            Self::Webp => "image/webp",
            Self::Avif => "image/avif",
            Self::Pbf => "application/x-protobuf",
            Self::Mlt => "application/vnd.maplibre-vector-tile",
        }
    }

    /// The name the dashboard is told and the extension of the tile URL it is given.
    pub fn name(self) -> &'static str {
        match self {
            Self::Png => "png",
            Self::Jpeg => "jpg",
            Self::Webp => "webp",
            Self::Avif => "avif",
            Self::Pbf => "pbf",
            Self::Mlt => "mlt",
        }
    }

    /// A picture a raster map can draw (the dashboard's map draws no vector tiles).
    pub fn is_raster(self) -> bool {
        !matches!(self, Self::Pbf | Self::Mlt)
    }
}

/// What a pack says about itself.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct PackInfo {
    /// Its tiles' format; `None`: not said, each tile's is guessed from its bytes.
    pub format: Option<TileFormat>,
    /// Its name.
    pub name: Option<String>,
    /// Whose map it is, as plain text (markup removed: it is shown on the dashboard).
    pub attribution: Option<String>,
    /// West, south, east, north, degrees.
    pub bounds: Option<[f64; 4]>,
    /// Shallowest zoom it has.
    pub min_zoom: Option<u8>,
    /// Deepest zoom it has.
    pub max_zoom: Option<u8>,
}

/// One tile as served.
#[derive(Debug, Clone, PartialEq)]
pub struct Tile {
    /// The bytes, as stored.
    pub data: Vec<u8>,
    /// Its `Content-Type`.
    pub content_type: &'static str,
    /// Its `Content-Encoding` when stored compressed (vector tiles), e.g. `gzip`.
    pub content_encoding: Option<&'static str>,
}

impl Tile {
    /// A tile of `format` (or, not known, of the format its bytes show).
    pub(crate) fn new(data: Vec<u8>, format: Option<TileFormat>) -> Self {
        let format = format.or_else(|| TileFormat::sniff(&data));
        let gzipped = data.starts_with(&[0x1F, 0x8B]);
        Self {
            content_type: format.map_or("application/octet-stream", TileFormat::content_type),
            content_encoding: gzipped.then_some("gzip"),
            data,
        }
    }
}

/// An open pack.
pub enum TilePack {
    /// SQLite.
    MbTiles(mbtiles::MbTiles),
    /// PMTiles v3 (boxed: its reader holds the header and root directory).
    PmTiles(Box<pmtiles_v3::PmTiles>),
}

impl TilePack {
    /// Opens the pack at `path`, its kind told by its extension.
    pub async fn open(path: &Path) -> Result<Self, TilePackError> {
        if !path.is_file() {
            return Err(TilePackError::Missing { path: path.into() });
        }
        let extension = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        match extension.as_deref() {
            Some("mbtiles") => {
                let owned = path.to_path_buf();
                let opened = tokio::task::spawn_blocking(move || mbtiles::MbTiles::open(&owned))
                    .await
                    .map_err(|e| TilePackError::Corrupt {
                        path: path.into(),
                        kind: "MBTiles",
                        reason: e.to_string(),
                    })?;
                opened.map(Self::MbTiles)
            }
            Some("pmtiles") => pmtiles_v3::PmTiles::open(path)
                .await
                .map(|p| Self::PmTiles(Box::new(p))),
            _ => Err(TilePackError::UnknownKind { path: path.into() }),
        }
    }

    /// What the pack says about itself.
    pub fn info(&self) -> &PackInfo {
        match self {
            Self::MbTiles(p) => p.info(),
            Self::PmTiles(p) => p.info(),
        }
    }

    /// The tile at `coord`; `None`: the pack does not have it.
    pub async fn tile(&self, coord: TileCoord) -> Result<Option<Tile>, TilePackError> {
        match self {
            // SQLite reads the disk: off the async threads.
            Self::MbTiles(p) => {
                let reader = p.clone();
                tokio::task::spawn_blocking(move || reader.tile(coord))
                    .await
                    .unwrap_or_else(|e| {
                        Err(TilePackError::Read {
                            path: p.path().into(),
                            coord,
                            reason: e.to_string(),
                        })
                    })
            }
            Self::PmTiles(p) => p.tile(coord).await,
        }
    }
}

/// The configured pack after the attempt to open it at start.
#[derive(Clone, Default)]
pub struct LoadedPack {
    /// The pack, when it opened.
    pub pack: Option<Arc<TilePack>>,
    /// Why it did not, for the dashboard (the map shows it over its grid).
    pub error: Option<String>,
}

impl LoadedPack {
    /// Opens the configured pack, if any; a failure is logged and kept, never fatal: the
    /// station is needed in the field with or without its map.
    pub async fn load(path: Option<&Path>) -> Self {
        let Some(path) = path else {
            return Self::default();
        };
        match TilePack::open(path).await {
            Ok(pack) => {
                let info = pack.info();
                tracing::info!(
                    pack = %path.display(),
                    format = info.format.map_or("unknown", TileFormat::name),
                    zooms = ?(info.min_zoom, info.max_zoom),
                    "tile pack open"
                );
                let error = info.format.filter(|f| !f.is_raster()).map(|_| {
                    format!(
                        "tile pack {} holds vector tiles, which the map cannot draw: \
                             prepare a raster pack (png, jpg or webp)",
                        path.display()
                    )
                });
                if let Some(e) = &error {
                    tracing::warn!("{e}");
                }
                Self {
                    pack: Some(Arc::new(pack)),
                    error,
                }
            }
            Err(e) => {
                tracing::warn!("{e}; the map shows its metric grid");
                Self {
                    pack: None,
                    error: Some(e.to_string()),
                }
            }
        }
    }

    /// The pack, when the dashboard's map can draw its tiles.
    pub fn drawable(&self) -> Option<&TilePack> {
        self.pack
            .as_deref()
            .filter(|p| p.info().format.is_none_or(TileFormat::is_raster))
    }
}

/// `text` without markup: pack attributions are often HTML links, and the dashboard's map
/// would render markup from a file it did not write.
pub(crate) fn plain_text(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let mut in_tag = false;
    for c in text.chars() {
        match c {
            '<' => in_tag = true,
            '>' if in_tag => in_tag = false,
            _ if !in_tag => out.push(c),
            _ => {}
        }
    }
    let out = out
        .replace("&copy;", "©")
        .replace("&amp;", "&")
        .replace(['<', '>'], "");
    out.split_whitespace().collect::<Vec<_>>().join(" ")
}

/// An empty directory of its own for a test's packs, `format` and `name` keeping the tests
/// of both readers apart when they run at once.
#[cfg(test)]
fn scratch_dir(format: &str, name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!(
        "stx-station-{format}-{}-{name}",
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch dir");
    dir
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn addresses_are_read_with_or_without_an_extension_and_checked() {
        let c = TileCoord::parse("3/5/1.png").expect("valid");
        assert_eq!(c, TileCoord { z: 3, x: 5, y: 1 });
        assert_eq!(TileCoord::parse("/3/5/1"), Ok(c));
        assert_eq!(TileCoord::parse("3/5/1.jpg"), Ok(c));
        assert_eq!(c.tms_row(), 6);
        assert_eq!(TileCoord::parse("0/0/0").expect("root").tms_row(), 0);
        for bad in [
            "3/5",
            "3/5/1/2",
            "a/1/1",
            "3/-1/0",
            "3/+1/0",
            "3/8/0",
            "3/0/8",
            "31/0/0",
            "3//1",
            "",
            "99999999999/0/0",
            "2/1/.png",
        ] {
            assert!(TileCoord::parse(bad).is_err(), "{bad}");
        }
        let deepest = format!("{MAX_ZOOM}/{}/0", (1u64 << MAX_ZOOM) - 1);
        assert!(TileCoord::parse(&deepest).is_ok());
    }

    #[test]
    fn formats_are_named_or_sniffed() {
        assert_eq!(TileFormat::from_name("JPEG"), Some(TileFormat::Jpeg));
        assert_eq!(TileFormat::from_name("pbf"), Some(TileFormat::Pbf));
        assert_eq!(TileFormat::from_name("tiff"), None);
        assert_eq!(
            TileFormat::sniff(b"\x89PNG\r\n\x1a\n"),
            Some(TileFormat::Png)
        );
        assert_eq!(
            TileFormat::sniff(b"RIFF\0\0\0\0WEBPVP8 "),
            Some(TileFormat::Webp)
        );
        assert_eq!(TileFormat::sniff(b"hello"), None);
        let t = Tile::new(vec![0x1F, 0x8B, 8, 0], Some(TileFormat::Pbf));
        assert_eq!(
            (t.content_type, t.content_encoding),
            ("application/x-protobuf", Some("gzip"))
        );
        let t = Tile::new(b"\xFF\xD8\xFF\xE0".to_vec(), None);
        assert_eq!((t.content_type, t.content_encoding), ("image/jpeg", None));
    }

    #[test]
    fn attributions_lose_their_markup() {
        assert_eq!(
            plain_text(
                r#"<a href="https://osm.org/copyright">&copy; OpenStreetMap</a> <script>x</script>"#
            ),
            "© OpenStreetMap x"
        );
        assert_eq!(plain_text("plain & simple"), "plain & simple");
    }
}

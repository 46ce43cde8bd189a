//! PMTiles v3 packs: a header, a root directory, leaf directories and the tiles, all in one
//! file, addressed by a Hilbert-curve tile id.
//!
//! Read with the `pmtiles` crate (Stadia Maps', kept with the spec): its directory decoding,
//! leaf lookup and Hilbert ids are the spec's finicky parts and are tested there. Its reader is
//! async over a backend it is given; the crate's own file backend memory-maps the file, and a
//! pack copied over while the station runs would then kill the process (`SIGBUS`). So the
//! backend here reads the file (off the async threads), and tags each read with the file's
//! length and modification time: a pack changed underneath answers errors, never garbage.

use std::fs::File;
use std::io::{Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

use bytes::Bytes;
use pmtiles::{
    AsyncBackend, AsyncPmTilesReader, BackendResponse, Compression, HashMapCache, PmtError,
    PmtResult, TileType,
};

use super::{PackInfo, Tile, TileCoord, TileFormat, TilePackError, plain_text};

/// An open PMTiles pack.
pub struct PmTiles {
    path: PathBuf,
    info: PackInfo,
    tile_compression: Compression,
    reader: AsyncPmTilesReader<FileBackend, HashMapCache>,
}

impl PmTiles {
    /// Opens `path`: reads its header, root directory and metadata.
    pub async fn open(path: &Path) -> Result<Self, TilePackError> {
        let corrupt = |reason: String| TilePackError::Corrupt {
            path: path.into(),
            kind: "PMTiles",
            reason,
        };
        let file = File::open(path).map_err(|e| corrupt(e.to_string()))?;
        let backend = FileBackend(Arc::new(Mutex::new(file)));
        let reader = AsyncPmTilesReader::try_from_cached_source(backend, HashMapCache::default())
            .await
            .map_err(|e| corrupt(e.to_string()))?;
        let header = reader.get_header();
        // Metadata is optional in the spec; an archive without it (or with unreadable JSON)
        // still has its tiles.
        let metadata: serde_json::Value = match reader.get_metadata().await {
            Ok(text) => serde_json::from_str(&text).unwrap_or_default(),
            Err(PmtError::InvalidMetadata) => serde_json::Value::Null,
            Err(e) => return Err(corrupt(format!("its metadata: {e}"))),
        };
        let text = |key: &str| {
            metadata
                .get(key)
                .and_then(|v| v.as_str())
                .map(str::trim)
                .filter(|v| !v.is_empty())
        };
        let [w, s, e, n] = [
            header.min_longitude,
            header.min_latitude,
            header.max_longitude,
            header.max_latitude,
        ];
        let bounds_valid = w < e && s < n && w >= -180.0 && e <= 180.0 && s >= -90.0 && n <= 90.0;
        let zooms_valid = header.min_zoom <= header.max_zoom;
        let info = PackInfo {
            format: format_of(header.tile_type),
            name: text("name").map(String::from),
            attribution: text("attribution")
                .map(plain_text)
                .filter(|a| !a.is_empty()),
            bounds: bounds_valid.then_some([w, s, e, n]),
            min_zoom: zooms_valid.then_some(header.min_zoom),
            max_zoom: zooms_valid.then_some(header.max_zoom),
        };
        Ok(Self {
            path: path.into(),
            info,
            tile_compression: header.tile_compression,
            reader,
        })
    }

    /// What the pack says about itself.
    pub fn info(&self) -> &PackInfo {
        &self.info
    }

    /// The tile at `coord`; `None`: not in the pack.
    pub async fn tile(&self, coord: TileCoord) -> Result<Option<Tile>, TilePackError> {
        let read_error = |e: PmtError| TilePackError::Read {
            path: self.path.clone(),
            coord,
            reason: e.to_string(),
        };
        let at = pmtiles::TileCoord::new(coord.z, coord.x, coord.y).map_err(read_error)?;
        let Some(data) = self.reader.get_tile(at).await.map_err(read_error)? else {
            return Ok(None);
        };
        let data = data.to_vec();
        let format = self.info.format.or_else(|| TileFormat::sniff(&data));
        Ok(Some(Tile {
            content_type: format.map_or("application/octet-stream", TileFormat::content_type),
            content_encoding: self.tile_compression.content_encoding(),
            data,
        }))
    }
}

fn format_of(tile_type: TileType) -> Option<TileFormat> {
    match tile_type {
        TileType::Png => Some(TileFormat::Png),
        TileType::Jpeg => Some(TileFormat::Jpeg),
        TileType::Webp => Some(TileFormat::Webp),
        TileType::Avif => Some(TileFormat::Avif),
        TileType::Mvt => Some(TileFormat::Pbf),
        TileType::Mlt => Some(TileFormat::Mlt),
        TileType::Unknown => None,
    }
}

/// Reads the pack's file at an offset, on tokio's blocking threads.
struct FileBackend(Arc<Mutex<File>>);

impl AsyncBackend for FileBackend {
    async fn read(&self, offset: u64, length: usize) -> PmtResult<BackendResponse> {
        let file = self.0.clone();
        tokio::task::spawn_blocking(move || read_at(&file, offset, length))
            .await
            .map_err(|e| PmtError::Reading(std::io::Error::other(e)))?
    }
}

/// Up to `length` bytes at `offset` (fewer at the end of the file), tagged with the file's
/// length and modification time so the reader notices a pack changed since it opened.
fn read_at(file: &Mutex<File>, offset: u64, length: usize) -> PmtResult<BackendResponse> {
    let mut file = file.lock().unwrap_or_else(|e| e.into_inner());
    let meta = file.metadata()?;
    let version = format!("{} bytes, modified {:?}", meta.len(), meta.modified().ok());
    file.seek(SeekFrom::Start(offset))?;
    let mut bytes = Vec::new();
    (&mut *file).take(length as u64).read_to_end(&mut bytes)?;
    Ok(BackendResponse::new_with_version(
        Bytes::from(bytes),
        version,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use pmtiles::PmTilesWriter;

    fn scratch(name: &str) -> PathBuf {
        super::super::scratch_dir("pmtiles", name)
    }

    fn png(tag: u32) -> Vec<u8> {
        let mut data = b"\x89PNG\r\n\x1a\n".to_vec();
        data.extend_from_slice(&tag.to_le_bytes());
        data
    }

    /// A pack written by the format's own writer, so the reader is checked against the spec
    /// rather than against a writer of ours.
    fn write_pack(path: &Path, tiles: &[(u8, u32, u32)]) {
        let file = File::create(path).expect("create");
        let mut writer = PmTilesWriter::new(TileType::Png)
            .metadata(r#"{"name":"Alentejo field","attribution":"<b>© OpenStreetMap</b>"}"#)
            .min_zoom(0)
            .max_zoom(8)
            .bounds(-7.9, 38.5, -7.8, 38.6)
            .create(file)
            .expect("writer");
        for (i, &(z, x, y)) in tiles.iter().enumerate() {
            let coord = pmtiles::TileCoord::new(z, x, y).expect("coord");
            writer.add_tile(coord, &png(i as u32)).expect("tile");
        }
        writer.finalize().expect("finalised");
    }

    #[tokio::test]
    async fn tiles_and_metadata_are_read_and_a_missing_tile_is_none() {
        let dir = scratch("read");
        let path = dir.join("field.pmtiles");
        write_pack(&path, &[(0, 0, 0), (1, 0, 0), (2, 1, 3)]);
        let pack = PmTiles::open(&path).await.expect("opens");
        let info = pack.info();
        assert_eq!(info.format, Some(TileFormat::Png));
        assert_eq!(info.name.as_deref(), Some("Alentejo field"));
        assert_eq!(info.attribution.as_deref(), Some("© OpenStreetMap"));
        assert_eq!((info.min_zoom, info.max_zoom), (Some(0), Some(8)));
        let [w, s, e, n] = info.bounds.expect("bounds");
        assert!((w + 7.9).abs() < 1e-6 && (s - 38.5).abs() < 1e-6, "{w} {s}");
        assert!((e + 7.8).abs() < 1e-6 && (n - 38.6).abs() < 1e-6, "{e} {n}");

        let at = |z, x, y| TileCoord { z, x, y };
        let tile = pack
            .tile(at(2, 1, 3))
            .await
            .expect("read")
            .expect("present");
        assert_eq!(tile.data, png(2));
        assert_eq!(
            (tile.content_type, tile.content_encoding),
            ("image/png", None)
        );
        assert_eq!(
            pack.tile(at(1, 0, 0))
                .await
                .expect("read")
                .expect("present")
                .data,
            png(1)
        );
        // PMTiles counts rows from the north, like the map: no flip.
        assert_eq!(pack.tile(at(2, 1, 0)).await.expect("read"), None);
        assert_eq!(pack.tile(at(7, 5, 5)).await.expect("read"), None);
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// Enough distinct tiles that the writer puts leaf directories under the root one: the
    /// lookup then goes through a leaf.
    #[tokio::test]
    async fn tiles_behind_leaf_directories_are_found() {
        let dir = scratch("leaves");
        let path = dir.join("big.pmtiles");
        let tiles: Vec<(u8, u32, u32)> = (0..256u32)
            .flat_map(|x| (0..96u32).map(move |y| (8, x, y)))
            .collect();
        write_pack(&path, &tiles);
        // The header's leaf directories' length (bytes 48..56): the writer did make leaves.
        let head = std::fs::read(&path).expect("read");
        let leaf_length = u64::from_le_bytes(head[48..56].try_into().expect("8 bytes"));
        assert!(leaf_length > 0, "the pack has leaf directories");
        let pack = PmTiles::open(&path).await.expect("opens");
        for i in [0usize, 1, 5000, 12_345, tiles.len() - 1] {
            let (z, x, y) = tiles[i];
            let tile = pack
                .tile(TileCoord { z, x, y })
                .await
                .expect("read")
                .expect("present");
            assert_eq!(tile.data, png(i as u32), "tile {i}");
        }
        assert_eq!(
            pack.tile(TileCoord { z: 8, x: 0, y: 200 })
                .await
                .expect("read"),
            None
        );
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[tokio::test]
    async fn a_corrupt_cut_or_changed_pack_is_an_error_not_a_panic() {
        let dir = scratch("corrupt");
        let garbage = dir.join("garbage.pmtiles");
        std::fs::write(
            &garbage,
            b"PMTiles\x03"
                .iter()
                .chain(&[0xFF; 200])
                .copied()
                .collect::<Vec<u8>>(),
        )
        .expect("write");
        let text = dir.join("text.pmtiles");
        std::fs::write(&text, b"not a pack").expect("write");
        let empty = dir.join("empty.pmtiles");
        std::fs::write(&empty, b"").expect("write");
        for path in [&garbage, &text, &empty] {
            let err = PmTiles::open(path)
                .await
                .err()
                .expect("refused")
                .to_string();
            assert!(
                err.contains(&path.display().to_string()) && err.contains("PMTiles"),
                "{err}"
            );
        }

        // Whole at opening, then cut short (a copy over it that is still running): each read
        // answers, a tile or an error.
        let path = dir.join("cut.pmtiles");
        write_pack(&path, &[(0, 0, 0), (1, 0, 0), (1, 1, 1), (2, 1, 3)]);
        let pack = PmTiles::open(&path).await.expect("opens");
        let len = std::fs::metadata(&path).expect("meta").len();
        std::fs::OpenOptions::new()
            .write(true)
            .open(&path)
            .and_then(|f| f.set_len(len / 2))
            .expect("cut");
        let mut errors = 0;
        for (z, x, y) in [(0, 0, 0), (1, 0, 0), (1, 1, 1), (2, 1, 3)] {
            if pack.tile(TileCoord { z, x, y }).await.is_err() {
                errors += 1;
            }
        }
        assert!(errors > 0, "a pack changed underneath shows as read errors");
        let _ = std::fs::remove_dir_all(&dir);
    }
}

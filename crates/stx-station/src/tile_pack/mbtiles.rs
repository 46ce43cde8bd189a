//! MBTiles packs: an SQLite file with a `metadata` table (name/value pairs) and a `tiles` table
//! or view (`zoom_level, tile_column, tile_row, tile_data`), rows counted from the south (TMS).
//!
//! Read with `rusqlite` and SQLite compiled in (`bundled`): SQLite is the format, and the field
//! laptop need not have the system library. One read-only connection behind a mutex: a map asks
//! a few dozen tiles at a time, each a single indexed lookup, so a pool would buy nothing.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

use rusqlite::types::ValueRef;
use rusqlite::{Connection, OpenFlags, OptionalExtension};

use super::{PackInfo, Tile, TileCoord, TileFormat, TilePackError, plain_text};

/// An open MBTiles pack; clones share the connection.
#[derive(Clone)]
pub struct MbTiles(Arc<Inner>);

struct Inner {
    path: PathBuf,
    info: PackInfo,
    connection: Mutex<Connection>,
}

impl MbTiles {
    /// Opens `path` read-only, reads its metadata and looks a tile up: a file that is not an
    /// MBTiles pack, or holds no tile, is refused here rather than at the first tile.
    pub fn open(path: &Path) -> Result<Self, TilePackError> {
        let corrupt = |reason: String| TilePackError::Corrupt {
            path: path.into(),
            kind: "MBTiles",
            reason,
        };
        let flags = OpenFlags::SQLITE_OPEN_READ_ONLY | OpenFlags::SQLITE_OPEN_NO_MUTEX;
        let connection =
            Connection::open_with_flags(path, flags).map_err(|e| corrupt(e.to_string()))?;
        let tables = table_names(&connection).map_err(|e| corrupt(e.to_string()))?;
        if !tables.iter().any(|t| t == "tiles") {
            return Err(corrupt("it has no `tiles` table".into()));
        }
        let metadata = if tables.iter().any(|t| t == "metadata") {
            read_metadata(&connection).map_err(|e| corrupt(e.to_string()))?
        } else {
            HashMap::new()
        };
        let first: Option<Vec<u8>> = connection
            .query_row(
                "SELECT tile_data FROM tiles WHERE tile_data IS NOT NULL LIMIT 1",
                [],
                |row| row.get(0),
            )
            .optional()
            .map_err(|e| corrupt(e.to_string()))?;
        let Some(first) = first else {
            return Err(corrupt("it holds no tiles".into()));
        };
        let mut info = info_from(&metadata);
        info.format = info.format.or_else(|| TileFormat::sniff(&first));
        if info.min_zoom.is_none() || info.max_zoom.is_none() {
            let (lo, hi) = zoom_range(&connection).map_err(|e| corrupt(e.to_string()))?;
            info.min_zoom = info.min_zoom.or(lo);
            info.max_zoom = info.max_zoom.or(hi);
        }
        Ok(Self(Arc::new(Inner {
            path: path.into(),
            info,
            connection: Mutex::new(connection),
        })))
    }

    /// The file.
    pub fn path(&self) -> &Path {
        &self.0.path
    }

    /// What the pack says about itself.
    pub fn info(&self) -> &PackInfo {
        &self.0.info
    }

    /// The tile at `coord` (XYZ; flipped to the stored TMS row here); `None`: not in the pack.
    /// Blocking: call it off the async threads.
    pub fn tile(&self, coord: TileCoord) -> Result<Option<Tile>, TilePackError> {
        // A panic elsewhere while holding the lock leaves the connection usable.
        let connection = self.0.connection.lock().unwrap_or_else(|e| e.into_inner());
        let data: Option<Option<Vec<u8>>> = connection
            .query_row(
                "SELECT tile_data FROM tiles \
                 WHERE zoom_level = ?1 AND tile_column = ?2 AND tile_row = ?3",
                (coord.z, coord.x, coord.tms_row()),
                |row| row.get(0),
            )
            .optional()
            .map_err(|e| TilePackError::Read {
                path: self.0.path.clone(),
                coord,
                reason: e.to_string(),
            })?;
        Ok(data
            .flatten()
            .map(|data| Tile::new(data, self.0.info.format)))
    }
}

fn table_names(connection: &Connection) -> rusqlite::Result<Vec<String>> {
    let mut statement =
        connection.prepare("SELECT name FROM sqlite_master WHERE type IN ('table', 'view')")?;
    statement
        .query_map([], |row| row.get::<_, String>(0))?
        .collect()
}

/// The `metadata` table; tools store numbers as text or as integers, both are taken.
fn read_metadata(connection: &Connection) -> rusqlite::Result<HashMap<String, String>> {
    let mut statement = connection.prepare("SELECT name, value FROM metadata")?;
    let rows = statement.query_map([], |row| {
        let name: String = row.get(0)?;
        let value = match row.get_ref(1)? {
            ValueRef::Text(t) => String::from_utf8_lossy(t).into_owned(),
            ValueRef::Integer(i) => i.to_string(),
            ValueRef::Real(r) => r.to_string(),
            ValueRef::Null | ValueRef::Blob(_) => String::new(),
        };
        Ok((name, value))
    })?;
    rows.collect()
}

fn zoom_range(connection: &Connection) -> rusqlite::Result<(Option<u8>, Option<u8>)> {
    connection.query_row(
        "SELECT min(zoom_level), max(zoom_level) FROM tiles",
        [],
        |row| {
            let zoom = |v: Option<i64>| v.and_then(|z| u8::try_from(z).ok());
            Ok((zoom(row.get(0)?), zoom(row.get(1)?)))
        },
    )
}

fn info_from(metadata: &HashMap<String, String>) -> PackInfo {
    let text = |key: &str| {
        metadata
            .get(key)
            .map(|v| v.trim())
            .filter(|v| !v.is_empty())
    };
    let zoom = |key: &str| text(key).and_then(|v| v.parse::<u8>().ok());
    let bounds = text("bounds").and_then(|v| {
        let numbers: Vec<f64> = v
            .split(',')
            .map(|n| n.trim().parse::<f64>())
            .collect::<Result<_, _>>()
            .ok()?;
        let [w, s, e, n] = numbers[..] else {
            return None;
        };
        let valid = w.abs() <= 180.0 && e.abs() <= 180.0 && s.abs() <= 90.0 && n.abs() <= 90.0;
        (valid && w < e && s < n).then_some([w, s, e, n])
    });
    PackInfo {
        format: text("format").and_then(TileFormat::from_name),
        name: text("name").map(String::from),
        attribution: text("attribution")
            .map(plain_text)
            .filter(|a| !a.is_empty()),
        bounds,
        min_zoom: zoom("minzoom"),
        max_zoom: zoom("maxzoom"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The first bytes of a PNG: enough for the reader, which serves bytes and never decodes.
    const PNG: &[u8] = b"\x89PNG\r\n\x1a\n\0\0\0\rIHDR";

    fn scratch(name: &str) -> PathBuf {
        super::super::scratch_dir("mbtiles", name)
    }

    /// A pack with `metadata` rows and tiles at their XYZ addresses, stored in TMS rows as
    /// the format says.
    fn write_test_pack(
        path: &Path,
        metadata: &[(&str, &str)],
        tiles: &[(TileCoord, &[u8])],
    ) -> rusqlite::Result<()> {
        let connection = Connection::open(path)?;
        connection.execute_batch(
            "CREATE TABLE metadata (name TEXT, value TEXT);
             CREATE TABLE tiles (zoom_level INTEGER, tile_column INTEGER, tile_row INTEGER,
                                 tile_data BLOB);
             CREATE UNIQUE INDEX tile_index ON tiles (zoom_level, tile_column, tile_row);",
        )?;
        for (name, value) in metadata {
            connection.execute("INSERT INTO metadata VALUES (?1, ?2)", (name, value))?;
        }
        for (coord, data) in tiles {
            connection.execute(
                "INSERT INTO tiles VALUES (?1, ?2, ?3, ?4)",
                (coord.z, coord.x, coord.tms_row(), data),
            )?;
        }
        Ok(())
    }

    fn at(z: u8, x: u32, y: u32) -> TileCoord {
        TileCoord { z, x, y }
    }

    #[test]
    fn tiles_are_found_at_their_xyz_address_through_the_tms_flip() {
        let dir = scratch("flip");
        let path = dir.join("field.mbtiles");
        let north: Vec<u8> = [PNG, b"north"].concat();
        let south: Vec<u8> = [PNG, b"south"].concat();
        write_test_pack(
            &path,
            &[
                ("name", "Alentejo field"),
                ("format", "png"),
                (
                    "attribution",
                    "<a href=\"https://osm.org\">&copy; OpenStreetMap</a>",
                ),
                ("bounds", "-7.9,38.5,-7.8,38.6"),
                ("minzoom", "0"),
                ("maxzoom", "2"),
            ],
            &[
                (at(0, 0, 0), PNG),
                (at(1, 0, 0), &north),
                (at(2, 1, 3), &south),
            ],
        )
        .expect("pack written");
        let pack = MbTiles::open(&path).expect("opens");
        // Stored in TMS: z1 y0 (north) is row 1, z2 y3 (south) is row 0.
        let raw = Connection::open(&path).expect("db");
        let rows: Vec<(u8, u32, u32)> = raw
            .prepare("SELECT zoom_level, tile_column, tile_row FROM tiles ORDER BY zoom_level")
            .expect("query")
            .query_map([], |r| Ok((r.get(0)?, r.get(1)?, r.get(2)?)))
            .expect("rows")
            .collect::<Result<_, _>>()
            .expect("rows");
        assert_eq!(rows, [(0, 0, 0), (1, 0, 1), (2, 1, 0)]);

        let tile = pack.tile(at(1, 0, 0)).expect("read").expect("present");
        assert_eq!(tile.data, north);
        assert_eq!(
            (tile.content_type, tile.content_encoding),
            ("image/png", None)
        );
        assert_eq!(
            pack.tile(at(2, 1, 3)).expect("read").expect("present").data,
            south
        );
        // The flipped address of a stored tile is another tile, absent.
        assert_eq!(pack.tile(at(1, 0, 1)).expect("read"), None);
        assert_eq!(pack.tile(at(2, 1, 0)).expect("read"), None);
        assert_eq!(pack.tile(at(9, 3, 3)).expect("read"), None);

        let info = pack.info();
        assert_eq!(info.name.as_deref(), Some("Alentejo field"));
        assert_eq!(info.attribution.as_deref(), Some("© OpenStreetMap"));
        assert_eq!(info.format, Some(TileFormat::Png));
        assert_eq!(info.bounds, Some([-7.9, 38.5, -7.8, 38.6]));
        assert_eq!((info.min_zoom, info.max_zoom), (Some(0), Some(2)));
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn a_pack_that_does_not_say_its_format_or_zooms_is_read_from_its_tiles() {
        let dir = scratch("quiet");
        let path = dir.join("quiet.mbtiles");
        let jpeg: &[u8] = b"\xFF\xD8\xFF\xE0\0\x10JFIF";
        write_test_pack(
            &path,
            &[("bounds", "not numbers")],
            &[(at(3, 2, 2), jpeg), (at(5, 0, 0), jpeg)],
        )
        .expect("pack written");
        let pack = MbTiles::open(&path).expect("opens");
        let info = pack.info();
        assert_eq!(info.format, Some(TileFormat::Jpeg));
        assert_eq!((info.min_zoom, info.max_zoom), (Some(3), Some(5)));
        assert_eq!((info.bounds, info.name.as_deref()), (None, None));
        let tile = pack.tile(at(3, 2, 2)).expect("read").expect("present");
        assert_eq!(tile.content_type, "image/jpeg");
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn a_corrupt_empty_or_foreign_file_is_an_error_that_names_it() {
        let dir = scratch("corrupt");
        let garbage = dir.join("garbage.mbtiles");
        std::fs::write(
            &garbage,
            b"this is not an SQLite database, only a text file ".repeat(100),
        )
        .expect("write");
        let foreign = dir.join("foreign.mbtiles");
        Connection::open(&foreign)
            .and_then(|c| c.execute_batch("CREATE TABLE notes (t TEXT);"))
            .expect("db");
        let empty = dir.join("empty.mbtiles");
        write_test_pack(&empty, &[("format", "png")], &[]).expect("pack written");
        // A real pack cut short: SQLite's header says more pages than there are.
        let cut = dir.join("cut.mbtiles");
        let tiles: Vec<(TileCoord, Vec<u8>)> =
            (0..64).map(|x| (at(6, x, 0), vec![0x89; 3000])).collect();
        let refs: Vec<(TileCoord, &[u8])> = tiles.iter().map(|(c, d)| (*c, &d[..])).collect();
        write_test_pack(&cut, &[("format", "png")], &refs).expect("pack written");
        let bytes = std::fs::read(&cut).expect("read");
        std::fs::write(&cut, &bytes[..bytes.len() / 3]).expect("truncate");

        for (path, says) in [
            (&garbage, "not a database"),
            (&foreign, "no `tiles` table"),
            (&empty, "no tiles"),
        ] {
            let err = MbTiles::open(path).err().expect("refused").to_string();
            assert!(err.contains(&path.display().to_string()), "{err}");
            assert!(err.contains(says), "{err}");
        }
        // Cut short, the pack may open (its first pages are whole); every read then answers,
        // with a tile or an error, and none panics.
        if let Ok(pack) = MbTiles::open(&cut) {
            for x in 0..64 {
                let _ = pack.tile(at(6, x, 0));
            }
            assert!(
                (0..64).any(|x| pack.tile(at(6, x, 0)).is_err()),
                "a truncated file shows as read errors"
            );
        }
        let missing = MbTiles::open(&dir.join("missing.mbtiles"))
            .err()
            .expect("refused");
        assert!(
            matches!(missing, TilePackError::Corrupt { .. }),
            "{missing}"
        );
        let _ = std::fs::remove_dir_all(&dir);
    }
}

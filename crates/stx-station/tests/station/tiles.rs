//! The offline map over HTTP: a station started with a tile pack (an MBTiles file the test
//! writes) serves its tiles under `/tiles/`, fills in the dashboard's tile source from it, and
//! with a missing or corrupt pack still starts and tells the dashboard why there is no map.

use crate::common;

use std::net::SocketAddr;
use std::path::{Path, PathBuf};

use common::{VIEWER, config, http, start_station};
use rusqlite::Connection;
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::net::TcpStream;

const PNG: &[u8] = b"\x89PNG\r\n\x1a\n\0\0\0\rIHDR";

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("stx-station-tiles-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch dir");
    dir
}

/// A tile's XYZ address and its bytes.
type TileAt = ((u8, u32, u32), Vec<u8>);

/// An MBTiles pack: tiles given at XYZ addresses, stored in TMS rows (`2^z - 1 - y`).
fn write_mbtiles(path: &Path, tiles: &[TileAt]) {
    let db = Connection::open(path).expect("db");
    db.execute_batch(
        "CREATE TABLE metadata (name TEXT, value TEXT);
         CREATE TABLE tiles (zoom_level INTEGER, tile_column INTEGER, tile_row INTEGER,
                             tile_data BLOB);
         INSERT INTO metadata VALUES ('name', 'Test field'), ('format', 'png'),
             ('attribution', '<a href=\"https://osm.org\">© OpenStreetMap</a>'),
             ('bounds', '-7.9,38.5,-7.8,38.6'), ('minzoom', '0'), ('maxzoom', '2');",
    )
    .expect("schema");
    for ((z, x, y), data) in tiles {
        let tms_row = (1u32 << z) - 1 - y;
        db.execute(
            "INSERT INTO tiles VALUES (?1, ?2, ?3, ?4)",
            (z, x, tms_row, data),
        )
        .expect("tile");
    }
}

/// A GET: status, `Content-Type` and the body's bytes.
async fn get(addr: SocketAddr, path: &str) -> (u16, String, Vec<u8>) {
    let mut stream = TcpStream::connect(addr).await.expect("connect");
    let request = format!("GET {path} HTTP/1.1\r\nHost: {addr}\r\nConnection: close\r\n\r\n");
    stream.write_all(request.as_bytes()).await.expect("write");
    let mut response = Vec::new();
    stream.read_to_end(&mut response).await.expect("read");
    let split = response
        .windows(4)
        .position(|w| w == b"\r\n\r\n")
        .expect("a response head");
    let head = String::from_utf8_lossy(&response[..split]).to_string();
    let status = head
        .split_whitespace()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .expect("a status");
    let content_type = head
        .lines()
        .find_map(|l| {
            let (k, v) = l.split_once(':')?;
            k.eq_ignore_ascii_case("content-type")
                .then(|| v.trim().to_string())
        })
        .unwrap_or_default();
    (status, content_type, response[split + 4..].to_vec())
}

#[tokio::test]
async fn a_tile_pack_is_served_under_tiles_and_named_to_the_dashboard() {
    let dir = scratch("served");
    let pack = dir.join("field.mbtiles");
    let north = [PNG, b"z1 north-west"].concat();
    let south = [PNG, b"z2 south"].concat();
    write_mbtiles(
        &pack,
        &[
            ((0, 0, 0), PNG.to_vec()),
            ((1, 0, 0), north.clone()),
            ((2, 1, 3), south.clone()),
        ],
    );
    let station = start_station(config(|c| c.tile_pack = Some(pack.clone()))).await;
    let addr = station.http();

    // With or without the extension of `tile_url = "/tiles/{z}/{x}/{y}.png"`.
    for path in ["/tiles/1/0/0.png", "/tiles/1/0/0"] {
        let (status, content_type, body) = get(addr, path).await;
        assert_eq!(
            (status, content_type.as_str()),
            (200, "image/png"),
            "{path}"
        );
        assert_eq!(body, north, "{path}");
    }
    let (status, _, body) = get(addr, "/tiles/2/1/3.png").await;
    assert_eq!((status, body), (200, south));
    // The TMS row of a stored tile, read as XYZ, is another tile: absent.
    let (status, _, _) = get(addr, "/tiles/1/0/1.png").await;
    assert_eq!(status, 404);
    let (status, _, _) = get(addr, "/tiles/12/100/100.png").await;
    assert_eq!(status, 404);
    for bad in [
        "/tiles/1/5/0.png",
        "/tiles/a/0/0.png",
        "/tiles/1/0",
        "/tiles/1/0/0/0",
    ] {
        let (status, content_type, body) = get(addr, bad).await;
        assert_eq!(status, 400, "{bad}");
        assert!(
            content_type.starts_with("application/json"),
            "{bad}: {content_type}"
        );
        let reason = String::from_utf8_lossy(&body).to_string();
        assert!(reason.contains("reason"), "{bad}: {reason}");
    }

    let (status, session) = http(addr, "GET", "/api/session", Some(VIEWER), None).await;
    assert_eq!(status, 200);
    let s = &session["station"];
    assert_eq!(s["tile_url"], "/tiles/{z}/{x}/{y}.png");
    assert_eq!(s["tile_attribution"], "© OpenStreetMap");
    assert_eq!(s["offline_tiles"], true);
    assert!(s["offline_tiles_error"].is_null(), "{s}");
    assert_eq!(s["tile_max_zoom"], 2);
    assert_eq!(
        s["tile_bounds"],
        serde_json::json!([-7.9, 38.5, -7.8, 38.6])
    );
    drop(station);
    let _ = std::fs::remove_dir_all(&dir);
}

#[tokio::test]
async fn the_tiles_directory_fills_in_what_the_pack_lacks() {
    let dir = scratch("fallback");
    let pack = dir.join("field.mbtiles");
    write_mbtiles(&pack, &[((1, 0, 0), [PNG, b"pack"].concat())]);
    let tiles_dir = dir.join("tiles");
    std::fs::create_dir_all(tiles_dir.join("1/0")).expect("dirs");
    std::fs::write(tiles_dir.join("1/0/0.png"), [PNG, b"dir"].concat()).expect("tile");
    std::fs::write(tiles_dir.join("1/0/1.png"), [PNG, b"dir"].concat()).expect("tile");
    let station = start_station(config(|c| {
        c.tile_pack = Some(pack.clone());
        c.tiles_dir = Some(tiles_dir.clone());
    }))
    .await;
    let addr = station.http();
    let (status, _, body) = get(addr, "/tiles/1/0/0.png").await;
    assert_eq!(
        (status, body),
        (200, [PNG, b"pack"].concat()),
        "the pack first"
    );
    let (status, content_type, body) = get(addr, "/tiles/1/0/1.png").await;
    assert_eq!(
        (status, body),
        (200, [PNG, b"dir"].concat()),
        "then the directory"
    );
    assert_eq!(content_type, "image/png");
    let (status, _, _) = get(addr, "/tiles/1/1/1.png").await;
    assert_eq!(status, 404);
    // Both may fill the map: the pack's extent and zooms do not bound it then.
    let (_, session) = http(addr, "GET", "/api/session", Some(VIEWER), None).await;
    assert!(session["station"]["tile_bounds"].is_null(), "{session}");
    drop(station);
    let _ = std::fs::remove_dir_all(&dir);
}

#[tokio::test]
async fn a_missing_or_corrupt_pack_leaves_the_station_running_and_says_why() {
    let dir = scratch("broken");
    let corrupt = dir.join("corrupt.mbtiles");
    std::fs::write(&corrupt, b"half a download ".repeat(200)).expect("write");
    for (pack, says) in [
        (dir.join("missing.pmtiles"), "no such file"),
        (corrupt, "not a usable MBTiles file"),
    ] {
        let station = start_station(config(|c| c.tile_pack = Some(pack.clone()))).await;
        let addr = station.http();
        let (status, session) = http(addr, "GET", "/api/session", Some(VIEWER), None).await;
        assert_eq!(status, 200);
        let s = &session["station"];
        let error = s["offline_tiles_error"]
            .as_str()
            .expect("an error")
            .to_string();
        assert!(
            error.contains(&pack.display().to_string()) && error.contains(says),
            "{error}"
        );
        // No map source: the dashboard draws its metric grid.
        assert!(s["tile_url"].is_null(), "{s}");
        assert_eq!(s["offline_tiles"], false);
        let (status, _) = http(addr, "GET", "/api/state", Some(VIEWER), None).await;
        assert_eq!(status, 200, "the station runs on");
        drop(station);
    }
    let _ = std::fs::remove_dir_all(&dir);
}

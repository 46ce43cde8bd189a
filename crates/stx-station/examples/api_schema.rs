//! Writes the API's contract (`stx_station::contract`) to `web/src/generated/api.schema.json`;
//! then `npm run gen:api` in `web/` turns it into the dashboard's TypeScript types.
//!
//! `cargo run -p stx-station --example api_schema [-- OUT]`

use std::path::PathBuf;

use anyhow::Context;
use stx_station::contract::{SCHEMA_PATH, schema_text};

fn main() -> anyhow::Result<()> {
    let out = match std::env::args_os().nth(1) {
        Some(path) => PathBuf::from(path),
        None => PathBuf::from(env!("CARGO_MANIFEST_DIR"))
            .join("../..")
            .join(SCHEMA_PATH),
    };
    let text = schema_text().context("assembling the API contract")?;
    std::fs::write(&out, text).with_context(|| format!("writing {}", out.display()))?;
    println!("wrote {}", out.display());
    Ok(())
}

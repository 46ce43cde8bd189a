//! `stx relay --upstream URL --listen ADDR`: the public face of a station for any audience
//! (`stx_station::relay`). Argument parsing, the runtime and the banner only.

use std::net::SocketAddr;
use std::path::PathBuf;

use anyhow::Context;
use clap::Args;
use stx_station::relay::feed::RelaySettings;
use stx_station::relay::serve::{self, RelayOptions};
use stx_station::relay::upstream::{Upstream, tls_connector};

use crate::BadInput;
use crate::serve::{announce, shutdown_signal};

#[derive(Args, Debug)]
pub struct RelayArgs {
    /// The station, `http(s)://HOST:PORT/?token=VIEWER-TOKEN` (a viewer's token: a relay
    /// never commands), or another relay, `http(s)://HOST:PORT/`.
    #[arg(long, value_name = "URL")]
    upstream: String,
    /// PEM certificates to trust for an https:// upstream besides Mozilla's roots (the
    /// station's own self-signed `[tls] cert_path`).
    #[arg(long, value_name = "FILE")]
    upstream_ca: Option<PathBuf>,
    /// Where the viewers connect (no token).
    #[arg(long, value_name = "ADDR", default_value = "0.0.0.0:8090")]
    listen: SocketAddr,
    /// Show everything this long after the station, s (0 to 3600).
    #[arg(long, value_name = "S", default_value_t = 0.0)]
    delay: f64,
    /// Round positions to a grid this coarse, m (0 off, up to 10000).
    #[arg(long, value_name = "M", default_value_t = 0.0)]
    coarsen: f64,
    /// Most viewers at once.
    #[arg(long, value_name = "N", default_value_t = 5000)]
    max_viewers: usize,
    /// Run at the usual priority. By default the relay runs at the lowest (nice 19, the idle
    /// class): beside the station it never takes a core the flight's telemetry needs, and on a
    /// machine of its own it makes no difference.
    #[arg(long)]
    full_priority: bool,
    /// The built dashboard (its public page and assets).
    #[arg(long, value_name = "DIR", default_value = "web/dist")]
    web_dir: PathBuf,
}

pub fn run(args: RelayArgs) -> anyhow::Result<()> {
    let settings = RelaySettings::new(args.delay, args.coarsen).map_err(|e| BadInput(e.into()))?;
    let shown = Upstream::parse(&args.upstream)
        .map_err(|e| BadInput(e.into()))?
        .shown;
    if let Some(ca) = &args.upstream_ca {
        tls_connector(Some(ca)).map_err(|e| BadInput(e.into()))?;
    }
    let options = RelayOptions {
        upstream: args.upstream,
        upstream_ca: args.upstream_ca,
        web_dir: args.web_dir,
        settings,
        max_viewers: args.max_viewers.max(1),
    };
    if !args.full_priority {
        // Before the runtime: its threads inherit it.
        stx_station::priority::lower_this_thread("stx relay");
    }
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .enable_all()
        .build()
        .context("starting the async runtime")?;
    runtime.block_on(async {
        let listener = serve::bind(args.listen)
            .await
            .with_context(|| format!("listening on {}", args.listen))?;
        let at = listener.local_addr().context("the relay's address")?;
        announce(&format!(
            "stx relay: {shown} for viewers at http://{at}/ (delay {} s, grid {} m)\nopen http://{at}/\n",
            settings.delay_s, settings.coarsen_m
        ));
        serve::run(options, listener, shutdown_signal())
            .await
            .context("serving the relay")
    })
}

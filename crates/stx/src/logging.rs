//! Where and how `stx` logs: `tracing` events to stderr, filtered by `RUST_LOG` (default
//! `info`). As text they are coloured only when stderr is a terminal (and `NO_COLOR` is not
//! set), so `stx serve 2> log`, a pipe or journald get no escape codes; `--log-format json`
//! writes one JSON object per line (`timestamp`, `level`, `target`, `fields`) for machines.

use std::io::IsTerminal;

use tracing_subscriber::EnvFilter;

/// How log lines are written.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum LogFormat {
    /// Human-readable lines, coloured on a terminal.
    #[default]
    Text,
    /// One JSON object per line.
    Json,
}

/// Installs the global subscriber; call once, before anything logs.
pub fn init(format: LogFormat) {
    let filter = EnvFilter::try_from_default_env().unwrap_or_else(|_| EnvFilter::new("info"));
    let builder = tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_writer(std::io::stderr);
    match format {
        LogFormat::Text => builder
            .with_ansi(colour(std::io::stderr().is_terminal()))
            .init(),
        LogFormat::Json => builder.json().with_ansi(false).init(),
    }
}

/// Whether text logs are coloured: only on a terminal, and never with `NO_COLOR` set to
/// anything (<https://no-color.org>).
fn colour(terminal: bool) -> bool {
    terminal && std::env::var_os("NO_COLOR").is_none_or(|v| v.is_empty())
}

//! `stx relay`: the station's public face for any audience. A relay keeps one connection to
//! its upstream (the station, through a viewer's token, or another relay, so relays form a
//! tree) and serves any number of viewers the public page, a slim public state and the KML
//! feed, with no token and no command route at all; optionally it delays what it shows and
//! rounds positions to a grid.
//!
//! - [`public`]: the public state and track (what a viewer may see), read from the upstream;
//! - [`feed`]: the relay's picture on its own clock: the delay, the grid, the track (pure);
//! - [`kml`]: the Google Earth document of the public picture;
//! - `upstream` (daemon): the socket to the upstream (plain or TLS), reporting the audience up;
//! - `serve` (daemon): the viewers' server.

pub mod feed;
pub mod kml;
pub mod public;
#[cfg(feature = "daemon")]
pub mod serve;
#[cfg(feature = "daemon")]
pub mod upstream;

#[cfg(test)]
mod tests;

//! One truth on every screen: whole missions flown from the pad to the landing with the
//! station's core beside the simulated drone, and what the station publishes held, at every
//! control period, against what really happened.
//!
//! The simulated drone knows the truth — its state, its onboard guidance's mode, phase, plan and
//! prediction, and where each body touched down — and the station knows only what the link
//! carries. Both are sans-io, so a mission flies here without sockets or a clock, deterministic
//! for a seed, at any ratio of mission time to the station's wall time (`stx serve --sim
//! --sim-speed N`): the station's link timers, heartbeats and link statistics run in its own
//! time, as in the daemon.
//!
//! - [`pair`]: the drone and the station on one link, stepped together;
//! - [`truth`]: the truth at an instant and at the landing;
//! - [`compare`]: one instant of the station's `state` against the truth;
//! - [`report`]: a mission's figures (shares of disagreement and their sizes, predictions at
//!   set heights against the touchdown, landing figures);
//! - [`mission`]: one whole mission flown and reported;
//! - [`campaign`]: missions by scenario, seed, dispersions and speed, flown on threads, with
//!   the goals they are held to.
//!
//! The test command flies a short campaign (`tests/agreement.rs`); `stx bench agreement`
//! flies the full one.

pub mod campaign;
pub mod compare;
pub mod mission;
pub mod pair;
pub mod report;
pub mod truth;

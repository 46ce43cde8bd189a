//! A finished flight of a scenario ([`Run`]: its samples and summary), open or closed loop,
//! and why one failed ([`RunError`]).

use serde::Serialize;
use stx_dynamics::integrate::IntegrateError;
use stx_dynamics::output::Sample;
use thiserror::Error;

use crate::scenario::ScenarioError;
use crate::summary::Summary;

/// Why a run failed.
#[derive(Debug, Error)]
pub enum RunError {
    /// The scenario is invalid.
    #[error(transparent)]
    Scenario(#[from] ScenarioError),
    /// The integrator could not follow the solution.
    #[error("integration failed")]
    Integrate(#[from] IntegrateError),
    /// Navigation could not be set up.
    #[error(transparent)]
    Navigation(#[from] crate::closed_loop::NavigationError),
    /// After the transponder's contact the payload did not come down (the model failed, or
    /// it flew on too long).
    #[error("the payload's landing: {reason}")]
    Payload {
        /// What went wrong.
        reason: String,
    },
}

/// A finished run.
#[derive(Debug, Clone, Serialize)]
pub struct Run {
    /// Recorded samples at the scenario's output interval (and the last instant).
    pub samples: Vec<Sample>,
    /// The summary.
    pub summary: Summary,
}

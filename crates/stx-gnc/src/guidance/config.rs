//! What guidance is configured with: the control laws' gains, the glide performance it plans
//! with, and the spiral's settings.

use serde::{Deserialize, Serialize};

use super::spiral::config::SpiralConfig;
use crate::control::ControlGains;
use crate::performance::GlidePerformance;

/// Everything guidance is configured with.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields, default)]
pub struct GuidanceConfig {
    /// Control-law gains and limits.
    pub gains: ControlGains,
    /// How the parafoil flies, for planning.
    pub performance: GlidePerformance,
    /// Spiral-landing settings.
    pub spiral: SpiralConfig,
    /// Keep the nominal glide and no main-line trim instead of learning them in flight: for
    /// judging the control laws alone (the gain tuning's step experiments). Default: learn.
    pub freeze_learning: bool,
}

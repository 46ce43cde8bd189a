//! The go/no-go board as every page shows it: the checks the station works out itself and the
//! checklist's manual items with who ticked them and when.

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// Where one check stands.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum CheckStatus {
    /// Holds.
    Go,
    /// Does not hold: the detail says why.
    NoGo,
    /// Cannot be told yet (nothing heard, nothing configured): open, like a no-go.
    Unknown,
}

/// One line of the board.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
pub struct CheckView {
    /// Stable name: `link`, `gps`, `plan`, `fence`, `params`, `battery`, `recording`,
    /// `forecast`, `reach` for the station's own; the checklist file's `id` for a manual item.
    pub id: String,
    /// What is checked, as the board says it.
    pub label: String,
    /// Ticked by an operator (a checklist item), not worked out by the station.
    pub manual: bool,
    /// Where it stands.
    pub status: CheckStatus,
    /// Why, with the figures (e.g. "12.5 V, at least 11.5 V").
    pub detail: String,
    /// The operator who ticked a manual item; `null` while it is not ticked.
    pub ticked_by: Option<String>,
    /// When it was ticked, Unix ms; `null` while it is not ticked.
    pub ticked_wall_ms: Option<u64>,
}

/// The whole board.
#[derive(Debug, Clone, Default, PartialEq, Serialize, JsonSchema)]
pub struct ReadinessView {
    /// The station's checks first, then the checklist's items in the file's order.
    pub checks: Vec<CheckView>,
    /// How many are not `go`.
    pub open: u32,
    /// The labels of the checks still open when the drone reported its launch (empty if it
    /// launched with every check go, or has not launched): every page announces them.
    pub launched_with_open: Vec<String>,
    /// Why the checklist file could not be read; `null` when it was (or none is configured).
    pub checklist_error: Option<String>,
}

/// `POST /api/readiness/{id}`: an operator ticks (or unticks) a checklist item.
#[derive(Debug, Clone, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct TickBody {
    /// `true` to tick, `false` to take the tick back.
    pub ticked: bool,
}

//! The cutdown's arm-then-confirm: an operator arms it, and only a confirmation naming that
//! arming within the configured window sends the command. A stale page cannot confirm
//! someone else's arming, and an arming nobody confirms lapses.

use super::requests::ApiError;

/// An armed cutdown, as `POST /api/cutdown/arm` answers it.
#[derive(Debug, Clone, PartialEq, serde::Serialize, schemars::JsonSchema)]
pub struct CutdownArm {
    /// The id to confirm with.
    pub arm_id: String,
    /// Seconds left to confirm.
    pub expires_in_s: f64,
}

#[derive(Debug, Clone)]
struct Armed {
    arm_id: String,
    until_s: f64,
    by: String,
}

/// The cutdown's arming.
#[derive(Debug)]
pub(crate) struct Cutdown {
    armed: Option<Armed>,
    window_s: f64,
    next_arm: u64,
}

impl Cutdown {
    pub fn new(window_s: f64) -> Self {
        Self {
            armed: None,
            window_s,
            next_arm: 1,
        }
    }

    pub fn arm(&mut self, now_s: f64, who: &str) -> CutdownArm {
        // Unpredictable enough that a stale page cannot confirm someone else's arming.
        let n = self.next_arm;
        self.next_arm += 1;
        let salt = (now_s.to_bits() ^ 0x9E37_79B9_7F4A_7C15).rotate_left((n % 63) as u32);
        let arm_id = format!("arm-{n}-{salt:016x}");
        self.armed = Some(Armed {
            arm_id: arm_id.clone(),
            until_s: now_s + self.window_s,
            by: who.to_string(),
        });
        CutdownArm {
            arm_id,
            expires_in_s: self.window_s,
        }
    }

    /// Uses up the arming `arm_id` if it is the current one and still open.
    pub fn confirm(&mut self, now_s: f64, who: &str, arm_id: &str) -> Result<(), ApiError> {
        let not_armed = |reason: &str| ApiError {
            status: 409,
            error: "not_armed",
            reason: reason.to_string(),
        };
        let Some(armed) = self.armed.take() else {
            return Err(not_armed("the cutdown is not armed: arm it first"));
        };
        if now_s > armed.until_s {
            return Err(not_armed("the arming expired: arm it again"));
        }
        if armed.arm_id != arm_id {
            self.armed = Some(armed);
            return Err(not_armed("that is not the current arming"));
        }
        if armed.by != who {
            tracing::warn!(armed_by = %armed.by, confirmed_by = who, "cutdown confirmed by another operator");
        }
        Ok(())
    }

    /// Drops an arming whose window has passed; the sentence for the log.
    pub fn expire(&mut self, now_s: f64) -> Option<String> {
        if self.armed.as_ref().is_some_and(|a| now_s > a.until_s) {
            let a = self.armed.take()?;
            return Some(format!("cutdown armed by {} expired unconfirmed", a.by));
        }
        None
    }

    pub fn armed_until(&self) -> Option<f64> {
        self.armed.as_ref().map(|a| a.until_s)
    }
}

//! Taking a phase from another copy of the same guidance: the ground station's replica flies on
//! its own estimate, and where a decision near its threshold fell the other way from the
//! drone's, it adopts the drone's phase (which the drone reports) rather than fly its own story
//! for a whole loop. Only the phase is reported; what the machine keeps with a phase (the loop
//! count, the entry branch, whether the axis may turn) is set as the machine's own transition
//! into that phase would have set it. A base leg's position is not reported, so a base leg
//! adopted without one is flown as the pattern's across leg until the next report.

use super::phases::PhaseMachine;
use crate::mission::GuidancePhase;

impl PhaseMachine {
    /// Enters `to` at `now_s` as the other copy did.
    pub(super) fn adopt(&mut self, to: GuidancePhase, now_s: f64) {
        use GuidancePhase as P;
        let from = self.phase;
        if from == to {
            return;
        }
        match to {
            P::Approximation => {
                self.approach_from_ne_m = None;
                self.set_base(None, None);
                self.downwind_y_m = None;
                self.extending = false;
                self.reorient = true;
            }
            P::Branch1 | P::Branch2 | P::Branch3 | P::Branch4 => {
                if matches!(from, P::Approximation | P::Idle | P::BestReachable) {
                    self.entry_branch = to;
                    self.loop_number = self.loop_number.max(1);
                } else if to == P::Branch1 && from == P::Branch4 {
                    self.downwind_y_m = None;
                    self.reorient = true;
                    self.loop_number += 1;
                }
            }
            P::FinalApproach => self.reorient = true,
            P::Flare => self.flare_off_line = from == P::BestReachable,
            P::BestReachable => {
                self.set_base(None, None);
                self.downwind_y_m = None;
                self.extending = false;
            }
            P::Idle | P::Landed => {}
        }
        self.phase = to;
        self.phase_since_s = now_s;
    }
}

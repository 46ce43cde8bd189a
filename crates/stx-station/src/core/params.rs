//! The drone's parameter table as the station knows it: filled by the list read whenever the
//! drone (re)appears, and kept current by every value the drone sends or echoes. The wire
//! carries names and values only; ranges, units and meanings come from the onboard catalogue
//! (`stx_gnc::params`) when the `params` message is built.

use std::collections::BTreeMap;

use stx_link::param::{ParamEvent, ParamValue};

/// Parameters by name.
#[derive(Debug, Clone, Default)]
pub(crate) struct Table {
    pub values: BTreeMap<String, ParamValue>,
    /// Every parameter the drone announced has arrived.
    pub complete: bool,
}

impl Table {
    fn store(&mut self, p: &ParamValue) {
        self.values.insert(p.name.clone(), p.clone());
        if self.values.len() >= usize::from(p.count) {
            self.complete = true;
        }
    }

    /// Takes in what a parameter event says; whether the table changed.
    pub fn on_event(&mut self, e: &ParamEvent) -> bool {
        match e {
            ParamEvent::ListComplete { params } => {
                for p in params {
                    self.store(p);
                }
                self.complete = true;
                true
            }
            ParamEvent::ListFailed { received, .. } => {
                for p in received {
                    self.store(p);
                }
                true
            }
            ParamEvent::ReadDone { param } | ParamEvent::Value { param } => {
                self.store(param);
                true
            }
            ParamEvent::ReadFailed { .. } | ParamEvent::SetFailed { .. } => false,
            ParamEvent::SetDone { name, actual, .. } => match self.values.get_mut(name) {
                Some(p) => {
                    p.value = *actual;
                    true
                }
                None => false,
            },
        }
    }
}

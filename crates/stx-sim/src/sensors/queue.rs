//! [`DeliveryQueue`]: measurements on their way to the estimator, held until they arrive.

use std::collections::VecDeque;

use super::Delivery;

/// Deliveries waiting for their arrival time, handed out in arrival order (ties in the order
/// they were pushed).
#[derive(Debug, Clone, Default)]
pub struct DeliveryQueue {
    waiting: VecDeque<Delivery>,
}

impl DeliveryQueue {
    /// An empty queue.
    pub fn new() -> Self {
        Self::default()
    }

    /// Queues a delivery.
    pub fn push(&mut self, delivery: Delivery) {
        // Few deliveries wait at once (latency × rates), so a linear insertion is cheapest.
        let at = self
            .waiting
            .iter()
            .rposition(|d| d.arrival_s <= delivery.arrival_s)
            .map_or(0, |i| i + 1);
        self.waiting.insert(at, delivery);
    }

    /// The earliest delivery that has arrived by `now_s`, if any.
    pub fn pop_due(&mut self, now_s: f64) -> Option<Delivery> {
        if self.waiting.front()?.arrival_s <= now_s {
            self.waiting.pop_front()
        } else {
            None
        }
    }

    /// Deliveries still waiting.
    pub fn len(&self) -> usize {
        self.waiting.len()
    }

    /// Whether none is waiting.
    pub fn is_empty(&self) -> bool {
        self.waiting.is_empty()
    }
}

//! Counters of the simulated bus and of each node on it.

/// What one node did on the bus (counted by the bus from what it reported to the node).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct NodeStats {
    /// Frames it sent successfully on the wire.
    pub sent: u64,
    /// Internal (loop-back) frames it sent, never on the wire.
    pub sent_internal: u64,
    /// Frames from other nodes it received correctly.
    pub received: u64,
    /// Transmission attempts that ended in an error.
    pub tx_errors: u64,
    /// Errors it detected while receiving.
    pub rx_errors: u64,
    /// Arbitrations it lost.
    pub arbitration_lost: u64,
}

/// Totals of the whole bus.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct BusStats {
    /// Bit times elapsed since the bus started.
    pub elapsed_bits: u64,
    /// Bit times occupied by frames and error frames, intermission included.
    pub busy_bits: u64,
    /// Frame attempts started on the wire (SOFs).
    pub frames_started: u64,
    /// Attempts that ended without any node detecting an error.
    pub frames_error_free: u64,
    /// Attempts in which some node detected an error.
    pub frames_with_errors: u64,
    /// Internal frames (never on the wire).
    pub internal_frames: u64,
}

impl BusStats {
    /// Bus load: busy bit times over elapsed bit times (0 before any time has passed).
    ///
    /// The intermission after each frame counts as busy, so back-to-back frames read 1.0.
    pub fn load(&self) -> f64 {
        if self.elapsed_bits == 0 {
            0.0
        } else {
            self.busy_bits as f64 / self.elapsed_bits as f64
        }
    }
}
